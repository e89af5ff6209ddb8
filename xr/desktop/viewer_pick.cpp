#include "xr/desktop/viewer_pick.h"

#include <cmath>

namespace vxr::xr {
namespace {

// The desktop's convention, as the renderer's: voxel v sits at (v - dims/2) * voxel size.
glm::dvec3 voxel_to_world(const std::array<double, 3>& v, const VolumePlacement& p) {
  glm::dvec3 w;
  for (int i = 0; i < 3; ++i) w[i] = (v[i] - 0.5 * p.dims[i]) * p.voxel_size[i];
  return w;
}

std::array<double, 3> world_to_voxel(const glm::dvec3& w, const VolumePlacement& p) {
  std::array<double, 3> v;
  for (int i = 0; i < 3; ++i) v[i] = w[i] / p.voxel_size[i] + 0.5 * p.dims[i];
  return v;
}

// The view's camera axes in the volume's frame.
struct Axes {
  glm::dvec3 eye, forward, right, up;
};
Axes axes_of(const WindowView& v, const VolumeTransform& t) {
  const Camera c = camera_for_view(v.view, t);
  Axes a;
  a.eye = c.eye;
  a.forward = glm::normalize(c.target - c.eye);
  a.right = glm::normalize(glm::cross(a.forward, c.up));
  a.up = glm::cross(a.right, a.forward);
  return a;
}

}  // namespace

std::optional<size_t> view_at(const std::vector<WindowView>& views, double x) {
  std::optional<size_t> found;
  for (size_t i = 0; i < views.size(); ++i)
    if (x >= views[i].x0) found = i;
  return found;
}

std::optional<std::array<double, 3>> voxel_under(const WindowView& v, const VolumeTransform& t,
                                                 const VolumePlacement& placement, const glm::dvec3& focus,
                                                 double x, double y) {
  const Axes a = axes_of(v, t);
  const Fov& f = v.view.fov;
  // Pixel -> tangents of the off-axis frustum, left..right and up..down.
  const double u = (x - v.x0) / double(v.view.width), w = y / double(v.view.height);
  const double tx = std::tan(f.left) + u * (std::tan(f.right) - std::tan(f.left));
  const double ty = std::tan(f.up) + w * (std::tan(f.down) - std::tan(f.up));
  const glm::dvec3 dir = a.forward + tx * a.right + ty * a.up;
  const double along = glm::dot(dir, a.forward);
  const double depth = glm::dot(focus - a.eye, a.forward);
  if (!(along > 0.0) || !(depth > 0.0)) return std::nullopt;
  return world_to_voxel(a.eye + dir * (depth / along), placement);
}

std::optional<std::array<double, 2>> project_voxel(const WindowView& v, const VolumeTransform& t,
                                                   const VolumePlacement& placement,
                                                   const std::array<double, 3>& voxel) {
  const Axes a = axes_of(v, t);
  const glm::dvec3 d = voxel_to_world(voxel, placement) - a.eye;
  const double z = glm::dot(d, a.forward);
  if (z <= 1e-9) return std::nullopt;
  const Fov& f = v.view.fov;
  const double tx = glm::dot(d, a.right) / z, ty = glm::dot(d, a.up) / z;
  const double u = (tx - std::tan(f.left)) / (std::tan(f.right) - std::tan(f.left));
  const double w = (ty - std::tan(f.up)) / (std::tan(f.down) - std::tan(f.up));
  return std::array<double, 2>{v.x0 + u * v.view.width, w * v.view.height};
}

std::optional<size_t> nearest_on_screen(const WindowView& v, const VolumeTransform& t, const VolumePlacement& placement,
                                        const std::vector<std::array<double, 3>>& voxels, double x, double y,
                                        double radius_px) {
  std::optional<size_t> best;
  double best_d = radius_px;
  for (size_t i = 0; i < voxels.size(); ++i) {
    const auto p = project_voxel(v, t, placement, voxels[i]);
    if (!p || (*p)[0] < v.x0 || (*p)[0] >= v.x0 + v.view.width) continue;  // behind the eye or in the other eye
    const double d = std::hypot((*p)[0] - x, (*p)[1] - y);
    if (d <= best_d) {
      best = i;
      best_d = d;
    }
  }
  return best;
}

int depth_axis(const WindowView& v, const VolumeTransform& t) {
  const glm::dvec3 f = axes_of(v, t).forward;
  int axis = 0;
  for (int i = 1; i < 3; ++i)
    if (std::abs(f[i]) > std::abs(f[axis])) axis = i;
  return axis;
}

std::array<double, 3> on_volume_face(std::array<double, 3> voxel, int axis, const VolumePlacement& placement,
                                     bool far) {
  voxel[axis] = far ? double(placement.dims[axis]) : 0.0;
  return voxel;
}

}  // namespace vxr::xr
