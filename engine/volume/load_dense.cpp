#include "volume/load_dense.h"

#include <cmath>
#include <algorithm>
#include <cstring>
#include <filesystem>

#include "volume/container_reader.h"
#include "volume/importers/import_source.h"
#include "volume/open_chunk_source.h"

namespace vxr {
namespace {

template <typename T>
void shrink_typed(const DenseVolume& v, DenseVolume& out) {
  const T* src = reinterpret_cast<const T*>(v.data.data());
  T* dst = reinterpret_cast<T*>(out.data.data());
  const auto& d = v.dims;
  for (uint32_t z = 0; z < out.dims[2]; ++z)
    for (uint32_t y = 0; y < out.dims[1]; ++y)
      for (uint32_t x = 0; x < out.dims[0]; ++x) {
        double sum = 0;
        int n = 0;
        for (uint32_t dz = 0; dz < 2; ++dz)
          for (uint32_t dy = 0; dy < 2; ++dy)
            for (uint32_t dx = 0; dx < 2; ++dx) {
              const uint64_t sx = std::min<uint64_t>(2 * x + dx, d[0] - 1), sy = std::min<uint64_t>(2 * y + dy, d[1] - 1),
                             sz = std::min<uint64_t>(2 * z + dz, d[2] - 1);
              sum += static_cast<double>(src[(sz * d[1] + sy) * d[0] + sx]);
              ++n;
            }
        const double mean = sum / n;
        dst[(uint64_t(z) * out.dims[1] + y) * out.dims[0] + x] =
            std::is_floating_point_v<T> ? static_cast<T>(mean) : static_cast<T>(std::llround(mean));
      }
}

}  // namespace

DenseVolume shrink_by_two(const DenseVolume& v) {
  DenseVolume out;
  out.dtype = v.dtype;
  out.unit = v.unit;
  for (int a = 0; a < 3; ++a) {
    out.dims[a] = v.dims[a] > 1 ? (v.dims[a] + 1) / 2 : 1;
    out.voxel_size[a] = v.voxel_size[a] * (v.dims[a] > 1 ? 2.0 : 1.0);
  }
  out.data.resize(out.byte_size());
  switch (v.dtype) {
    case DType::kU8: shrink_typed<uint8_t>(v, out); break;
    case DType::kI8: shrink_typed<int8_t>(v, out); break;
    case DType::kU16: shrink_typed<uint16_t>(v, out); break;
    case DType::kI16: shrink_typed<int16_t>(v, out); break;
    case DType::kU32: shrink_typed<uint32_t>(v, out); break;
    case DType::kI32: shrink_typed<int32_t>(v, out); break;
    case DType::kF32: shrink_typed<float>(v, out); break;
  }
  return out;
}

// The display metadata of channels 0..n-1 of `info` (empty when it has none).
static std::vector<ChannelDisplay> first_channels_display(const VolumeInfo& info, uint32_t n) {
  if (info.channel_display.empty()) return {};
  return {info.channel_display.begin(), info.channel_display.begin() + std::min<size_t>(n, info.channel_display.size())};
}

// A .vxc or OME-Zarr: the finest pyramid level that fits, read chunk by chunk (no shrinking in memory).
static Result<LoadedVolume> load_chunk_source_level(const std::string& path, uint32_t max_dim, uint64_t max_bytes) {
  VXR_ASSIGN_OR_RETURN(OpenedChunkSource opened, open_chunk_source(path));
  const ChunkSource& source = *opened.source;
  const VolumeInfo& info = source.info();
  LoadedVolume out;
  out.format = opened.format;
  out.notes = opened.warnings;
  const uint32_t level = finest_level_that_fits(source, max_dim, max_bytes);
  const auto& lv = source.levels()[level];
  out.shrink = std::max({lv.downsample[0], lv.downsample[1], lv.downsample[2]});
  const uint32_t channels = std::min<uint32_t>(info.channels, 4);
  if (info.channels > 4) out.notes.push_back("showing the first 4 of " + std::to_string(info.channels) + " channels");
  if (info.timepoints > 1) out.notes.push_back("showing timepoint 0 of " + std::to_string(info.timepoints));
  for (uint32_t c = 0; c < channels; ++c) {
    VXR_ASSIGN_OR_RETURN(DenseVolume v, read_level_dense(source, level, c, 0, max_bytes));
    out.channels.push_back(std::move(v));
  }
  out.channel_display = first_channels_display(info, channels);
  if (level > 0) out.notes.push_back("drawing pyramid level " + std::to_string(level) + " to fit the GPU's limits");
  return out;
}

Result<LoadedVolume> load_for_render(const std::string& path, uint32_t max_dim, uint64_t max_bytes) {
  if (is_chunk_source_input(path)) return load_chunk_source_level(path, max_dim, max_bytes);
  VXR_ASSIGN_OR_RETURN(std::unique_ptr<SlabSource> src, open_import_source({path}));
  const VolumeInfo& info = src->info();
  LoadedVolume out;
  out.format = src->format_name();
  out.notes = src->warnings();
  const uint32_t channels = std::min<uint32_t>(info.channels, 4);
  if (info.channels > 4) out.notes.push_back("showing the first 4 of " + std::to_string(info.channels) + " channels");
  out.channel_display = first_channels_display(info, channels);
  const uint64_t bytes = info.voxels_per_volume() * dtype_bytes(info.dtype);
  if (bytes > (uint64_t(8) << 30))
    return unsupported(path + ": " + std::to_string(bytes >> 20) + " MiB per channel is too large to render "
                              "whole; convert it to a .vxc pyramid first");
  // A time series is held whole when every timepoint fits the budget unshrunk;
  // otherwise timepoint 0 alone (and the user is told how to play the rest).
  const bool series = info.timepoints > 1 && bytes <= max_bytes / info.timepoints &&
                      std::max({info.dims[0], info.dims[1], info.dims[2]}) <= max_dim;
  if (info.timepoints > 1 && !series)
    out.notes.push_back("showing timepoint 0 of " + std::to_string(info.timepoints) +
                        " (the series is too large to hold in memory; import it to a .vxc to play every timepoint)");
  // One channel of one timepoint, whole.
  auto read_volume = [&](uint32_t c, uint32_t t) -> Result<DenseVolume> {
    DenseVolume v;
    v.dims = {static_cast<uint32_t>(info.dims[0]), static_cast<uint32_t>(info.dims[1]),
              static_cast<uint32_t>(info.dims[2])};
    v.dtype = info.dtype;
    v.voxel_size = info.voxel_size;
    v.unit = info.unit;
    v.data.resize(v.byte_size());
    VXR_RETURN_IF_ERROR(src->read_region(c, t, Box3{{0, 0, 0}, info.dims}, v.data));
    return v;
  };
  for (uint32_t t = 1; series && t < info.timepoints; ++t) {
    std::vector<DenseVolume> volumes;
    for (uint32_t c = 0; c < channels; ++c) {
      VXR_ASSIGN_OR_RETURN(DenseVolume v, read_volume(c, t));
      volumes.push_back(std::move(v));
    }
    out.later_timepoints.push_back(std::move(volumes));
  }
  for (uint32_t c = 0; c < channels; ++c) {
    VXR_ASSIGN_OR_RETURN(DenseVolume v, read_volume(c, 0));
    uint32_t shrink = 1;
    while (std::max({v.dims[0], v.dims[1], v.dims[2]}) > max_dim || v.byte_size() > max_bytes) {
      v = shrink_by_two(v);
      shrink *= 2;
    }
    out.shrink = shrink;
    out.channels.push_back(std::move(v));
  }
  if (out.shrink > 1)
    out.notes.push_back("averaged down " + std::to_string(out.shrink) + "x per axis to fit the GPU's texture limits");
  return out;
}

}  // namespace vxr
