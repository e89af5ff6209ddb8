#include "volume/tiff_export.h"

#include <cstring>
#include <vector>

#include "core/trace.h"
#include "volume/tiff_writer.h"

namespace vxr {

Status export_tiff(const ChunkSource& src, const std::string& out_path, const TiffExportOptions& opt) {
  VXR_TRACE_SCOPE("export_tiff");
  const VolumeInfo& info0 = src.info();
  const auto& levels = src.levels();
  if (opt.level >= levels.size())
    return invalid_argument("--level " + std::to_string(opt.level) + ": the volume has levels 0.." +
                            std::to_string(levels.size() - 1));
  if (opt.channel && *opt.channel >= info0.channels)
    return invalid_argument("--channel " + std::to_string(*opt.channel) + ": the volume has channels 0.." +
                            std::to_string(info0.channels - 1));
  if (opt.timepoint && *opt.timepoint >= info0.timepoints)
    return invalid_argument("--timepoint " + std::to_string(*opt.timepoint) + ": the volume has timepoints 0.." +
                            std::to_string(info0.timepoints - 1));
  const LevelInfo& lv = levels[opt.level];
  const uint32_t c0 = opt.channel.value_or(0), nc = opt.channel ? 1 : info0.channels;
  const uint32_t t0 = opt.timepoint.value_or(0), nt = opt.timepoint ? 1 : info0.timepoints;
  VolumeInfo out = info0;
  out.dims = lv.dims;
  out.channels = nc;
  out.timepoints = nt;
  for (int a = 0; a < 3; ++a) out.voxel_size[a] = info0.voxel_size[a] * lv.downsample[a];

  const uint32_t cs = src.chunk_size(), ap = src.apron();
  const uint32_t ob = dtype_bytes(info0.dtype);
  const uint64_t X = lv.dims[0], Y = lv.dims[1], Z = lv.dims[2];
  const uint64_t plane = X * Y * ob;
  // Hold one chunk layer (cs planes) of every exported channel when it fits the
  // budget, so each chunk decodes once; else decode per plane (each chunk cs times).
  const uint64_t layer_planes = std::min<uint64_t>(cs, Z);
  const bool whole_layer = plane * layer_planes * nc <= opt.memory_budget;
  const uint64_t held = whole_layer ? layer_planes : 1;

  VXR_ASSIGN_OR_RETURN(std::unique_ptr<TiffStackWriter> writer, TiffStackWriter::create(out_path, out));
  std::vector<uint8_t> buf(plane * held * nc);
  // Fills buf with planes [z0, z0 + n) of every exported channel of timepoint t.
  auto fill = [&](uint32_t t, uint64_t z0, uint64_t n) -> Status {
    for (uint32_t ci = 0; ci < nc; ++ci) {
      const uint64_t kz0 = z0 / cs, kz1 = (z0 + n - 1) / cs;
      for (uint64_t kz = kz0; kz <= kz1; ++kz)
        for (uint32_t ky = 0; ky < lv.chunk_counts[1]; ++ky)
          for (uint32_t kx = 0; kx < lv.chunk_counts[0]; ++kx) {
            ChunkKey key;
            key.level = opt.level;
            key.x = kx, key.y = ky, key.z = uint32_t(kz);
            key.channel = c0 + ci;
            key.timepoint = t;
            Result<std::shared_ptr<const Chunk>> chunk = src.read(key);
            if (!chunk) return chunk.status();
            const Chunk& ch = **chunk;
            const uint64_t e = ch.edge;
            if (ch.data.size() != e * e * e * ob || e < cs + 2 * ap)
              return corrupt(out_path + ": chunk has an unexpected size in the source");
            const uint64_t x0 = uint64_t(kx) * cs, y0 = uint64_t(ky) * cs;
            const uint64_t nx = std::min<uint64_t>(cs, X - x0), ny = std::min<uint64_t>(cs, Y - y0);
            for (uint64_t z = std::max(z0, kz * cs); z < std::min(z0 + n, (kz + 1) * cs) && z < Z; ++z) {
              const uint64_t lz = z - kz * cs + ap;
              uint8_t* dst_plane = buf.data() + ((z - z0) * nc + ci) * plane;
              for (uint64_t y = 0; y < ny; ++y) {
                const uint8_t* s = ch.data.data() + (((lz * e) + y + ap) * e + ap) * ob;
                std::memcpy(dst_plane + ((y0 + y) * X + x0) * ob, s, nx * ob);
              }
            }
          }
    }
    return Status::ok();
  };
  for (uint32_t ti = 0; ti < nt; ++ti) {
    for (uint64_t z0 = 0; z0 < Z; z0 += held) {
      const uint64_t n = std::min<uint64_t>(held, Z - z0);
      VXR_RETURN_IF_ERROR(fill(t0 + ti, z0, n));
      for (uint64_t z = 0; z < n; ++z)
        for (uint32_t ci = 0; ci < nc; ++ci) {
          VXR_RETURN_IF_ERROR(writer->write_page(buf.data() + (z * nc + ci) * plane));
          if (opt.progress) opt.progress->advance(plane);
        }
    }
  }
  return writer->finish();
}

}  // namespace vxr
