#include "volume/memory_slab_source.h"

#include <cstring>

namespace vxr {

MemorySlabSource::MemorySlabSource(VolumeInfo info, std::vector<std::vector<uint8_t>> volumes)
    : info_(std::move(info)), volumes_(std::move(volumes)) {}

MemorySlabSource::MemorySlabSource(const DenseVolume& v) {
  info_.dims = {v.dims[0], v.dims[1], v.dims[2]};
  info_.dtype = v.dtype;
  info_.voxel_size = v.voxel_size;
  info_.unit = v.unit;
  volumes_.push_back(v.data);
}

Status MemorySlabSource::read_region(uint32_t channel, uint32_t timepoint, const Box3& box, std::span<uint8_t> dst) {
  const uint32_t bpv = dtype_bytes(info_.dtype);
  if (channel >= info_.channels || timepoint >= info_.timepoints) return out_of_range("channel/timepoint out of range");
  if (dst.size() != box.voxels() * bpv) return invalid_argument("read_region buffer has the wrong size");
  for (int a = 0; a < 3; ++a)
    if (box.origin[a] + box.size[a] > info_.dims[a]) return out_of_range("region outside the volume");
  const auto& vol = volumes_.at(uint64_t(timepoint) * info_.channels + channel);
  if (vol.size() != info_.voxels_per_volume() * bpv) return internal_error("in-memory volume has the wrong size");
  uint8_t* out = dst.data();
  for (uint64_t z = 0; z < box.size[2]; ++z)
    for (uint64_t y = 0; y < box.size[1]; ++y) {
      const uint64_t off = (((box.origin[2] + z) * info_.dims[1] + box.origin[1] + y) * info_.dims[0] + box.origin[0]) * bpv;
      std::memcpy(out, vol.data() + off, box.size[0] * bpv);
      out += box.size[0] * bpv;
    }
  return Status::ok();
}

}  // namespace vxr
