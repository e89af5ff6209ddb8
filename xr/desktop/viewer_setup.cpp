#include "xr/desktop/viewer_setup.h"

#include <algorithm>
#include <cmath>

namespace vxr::xr {

Result<std::vector<float>> coarse_histogram(const ChunkSource& source, uint32_t channel, uint32_t timepoint,
                                            std::array<double, 2> range, size_t bins, uint32_t max_chunks) {
  const std::vector<LevelInfo>& levels = source.levels();
  if (levels.empty() || bins == 0 || !(range[1] > range[0])) return invalid_argument("histogram: nothing to count");
  size_t level = levels.size() - 1;
  for (size_t l = 0; l < levels.size(); ++l) {
    const auto& c = levels[l].chunk_counts;
    if (uint64_t(c[0]) * c[1] * c[2] <= max_chunks) {
      level = l;
      break;
    }
  }
  const LevelInfo& info = levels[level];
  const uint32_t size = source.chunk_size(), apron = source.apron();
  std::vector<double> counts(bins, 0.0);
  const double scale = double(bins) / (range[1] - range[0]);
  for (uint32_t cz = 0; cz < info.chunk_counts[2]; ++cz)
    for (uint32_t cy = 0; cy < info.chunk_counts[1]; ++cy)
      for (uint32_t cx = 0; cx < info.chunk_counts[0]; ++cx) {
        const ChunkKey key{uint32_t(level), cx, cy, cz, channel, timepoint};
        VXR_ASSIGN_OR_RETURN(std::shared_ptr<const Chunk> chunk, source.read(key));
        const uint32_t bytes = dtype_bytes(chunk->dtype), edge = chunk->edge;
        // Interior voxels inside the level (edge chunks repeat their last voxel past it).
        const uint64_t n[3] = {std::min<uint64_t>(size, info.dims[0] - uint64_t(cx) * size),
                               std::min<uint64_t>(size, info.dims[1] - uint64_t(cy) * size),
                               std::min<uint64_t>(size, info.dims[2] - uint64_t(cz) * size)};
        for (uint64_t z = 0; z < n[2]; ++z)
          for (uint64_t y = 0; y < n[1]; ++y)
            for (uint64_t x = 0; x < n[0]; ++x) {
              const size_t at = ((z + apron) * edge + (y + apron)) * edge + (x + apron);
              const double v = decode_voxel(&chunk->data[at * bytes], chunk->dtype);
              if (!std::isfinite(v)) continue;
              const double b = std::floor((v - range[0]) * scale);
              counts[size_t(std::clamp(b, 0.0, double(bins - 1)))] += 1.0;
            }
      }
  std::vector<float> out(bins);
  for (size_t i = 0; i < bins; ++i) out[i] = float(std::log1p(counts[i]));
  return out;
}

}  // namespace vxr::xr

namespace vxr::xr {

std::optional<OrbitCamera> scene_orbit(const Scene& scene, const VolumePlacement& placement) {
  if (!scene.has_camera) return std::nullopt;
  const glm::dvec3 e = placement.extent();
  return orbit_for_camera(camera_in_volume_frame(scene.camera, scene.transform), std::max({e.x, e.y, e.z}));
}

}  // namespace vxr::xr
