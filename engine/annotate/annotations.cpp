#include "annotate/annotations.h"

#include <cmath>

namespace vxr::annotate {

Vec3 VoxelSpace::to_physical(const Vec3& p) const {
  return {p[0] * voxel_size[0], p[1] * voxel_size[1], p[2] * voxel_size[2]};
}

Vec3 VoxelSpace::from_physical(const Vec3& p) const {
  return {p[0] / voxel_size[0], p[1] / voxel_size[1], p[2] / voxel_size[2]};
}

double VoxelSpace::distance(const Vec3& a, const Vec3& b) const {
  const Vec3 pa = to_physical(a), pb = to_physical(b);
  return std::hypot(pb[0] - pa[0], pb[1] - pa[1], pb[2] - pa[2]);
}

double micrometres_per_unit(const std::string& unit) {
  if (unit == "um" || unit == "µm" || unit == "\u00B5m" || unit == "micron" || unit == "micrometer" ||
      unit == "micrometre")
    return 1.0;
  if (unit == "nm" || unit == "nanometer" || unit == "nanometre") return 1e-3;
  if (unit == "mm" || unit == "millimeter" || unit == "millimetre") return 1e3;
  return 0.0;
}

bool Roi::contains(const Vec3& p) const {
  for (int i = 0; i < 3; ++i)
    if (p[i] < min[i] || p[i] > max[i]) return false;
  return true;
}

}  // namespace vxr::annotate
