// A whole single-channel 3D scalar field in memory, x fastest.
//
// Used for small volumes (the bundled sample, tests, one pyramid level that
// fits a 3D texture). Large data goes through ChunkSource instead.
#pragma once

#include <array>
#include <cstdint>
#include <string>
#include <vector>

#include "core/status.h"
#include "volume/dtype.h"

namespace vxr {

struct DenseVolume {
  std::array<uint32_t, 3> dims{0, 0, 0};     // voxels along x, y, z
  DType dtype = DType::kU8;
  std::array<double, 3> voxel_size{1, 1, 1};  // physical size of one voxel
  std::string unit = "um";
  std::vector<uint8_t> data;                  // dims[0]*dims[1]*dims[2]*dtype_bytes bytes

  uint64_t voxel_count() const { return uint64_t(dims[0]) * dims[1] * dims[2]; }
  uint64_t byte_size() const { return voxel_count() * dtype_bytes(dtype); }
  // The voxel as a double in its own units (no normalisation).
  double value_at(uint32_t x, uint32_t y, uint32_t z) const;
};

// Reads a raw volume described by a JSON sidecar:
//   {"file": "mri-stack.u8.raw", "dims": [186, 226, 27], "dtype": "u8",
//    "voxel_size": [1, 1, 5], "unit": "um"}
// "file" is relative to the sidecar. Sizes are checked against the file.
Result<DenseVolume> load_raw_volume(const std::string& json_path);

}  // namespace vxr
