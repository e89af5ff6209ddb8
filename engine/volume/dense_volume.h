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
  std::array<double, 3> origin{0, 0, 0};      // world position of the box centre (physical units)
  std::string unit = "um";
  std::vector<uint8_t> data;                  // dims[0]*dims[1]*dims[2]*dtype_bytes bytes

  uint64_t voxel_count() const { return uint64_t(dims[0]) * dims[1] * dims[2]; }
  uint64_t byte_size() const { return voxel_count() * dtype_bytes(dtype); }
  // The voxel as a double in its own units (no normalisation).
  double value_at(uint32_t x, uint32_t y, uint32_t z) const;
};

// Why a volume cannot be rendered (a zero side, a voxel size that is not a
// positive finite number), or ok. Both renderers check it before anything else.
Status check_renderable(const DenseVolume& v);

// A voxel value as the renderers read it (GPU texture and CPU reference
// alike): NaN reads as 0 and magnitudes are clamped to 1e30, so trilinear
// filtering and windowing never meet inf - inf or 0 * inf.
inline double renderable_value(double v) {
  if (v != v) return 0.0;
  return v > 1e30 ? 1e30 : (v < -1e30 ? -1e30 : v);
}

// Reads a raw volume described by a JSON sidecar:
//   {"file": "mri-stack.u8.raw", "dims": [186, 226, 27], "dtype": "u8",
//    "voxel_size": [1, 1, 5], "unit": "um"}
// "file" is relative to the sidecar. Sizes are checked against the file.
Result<DenseVolume> load_raw_volume(const std::string& json_path);

}  // namespace vxr
