// What a multi-channel, multi-timepoint volume is, independent of storage.
#pragma once

#include <array>
#include <cstdint>
#include <string>

#include "volume/dtype.h"

namespace vxr {

struct VolumeInfo {
  std::array<uint64_t, 3> dims{0, 0, 0};      // level-0 voxels along x, y, z
  DType dtype = DType::kU8;
  uint32_t channels = 1;
  uint32_t timepoints = 1;
  std::array<double, 3> voxel_size{1, 1, 1};  // physical size of one level-0 voxel
  std::string unit = "um";                    // "um", "nm", "mm", ... ("px" when unknown)
  // Physical position (in `unit`) of voxel (0, 0, 0): OME-Zarr's translation,
  // so volumes of one experiment keep their relative placement. 0 when unknown.
  std::array<double, 3> origin{0, 0, 0};

  uint64_t voxels_per_volume() const { return dims[0] * dims[1] * dims[2]; }
};

// An axis-aligned block of voxels: [origin, origin + size).
struct Box3 {
  std::array<uint64_t, 3> origin{0, 0, 0};
  std::array<uint64_t, 3> size{0, 0, 0};
  uint64_t voxels() const { return size[0] * size[1] * size[2]; }
};

}  // namespace vxr
