#include "xr/volume_transform.h"

#include <cmath>

namespace vxr::xr {

VolumeTransform default_volume_transform(const VolumePlacement& placement, double size_m, glm::dvec3 centre) {
  VolumeTransform t;
  t.position = centre;
  // -90 degrees about x: volume +z -> reference +y, volume -y -> reference +z (towards the viewer).
  t.orientation = glm::angleAxis(-glm::half_pi<double>(), glm::dvec3(1, 0, 0));
  t.scale = size_m / glm::length(placement.extent());
  return t;
}

Camera camera_for_view(const ViewSpec& view, const VolumeTransform& t) {
  if (view.camera) return *view.camera;
  const glm::dquat to_volume = glm::conjugate(t.orientation);
  const glm::dquat eye_in_volume = to_volume * view.pose.orientation;
  Camera c;
  c.eye = t.to_volume(view.pose.position);
  c.target = c.eye + eye_in_volume * glm::dvec3(0, 0, -1);
  c.up = eye_in_volume * glm::dvec3(0, 1, 0);
  c.frustum = FrustumTangents{std::tan(view.fov.left), std::tan(view.fov.right), std::tan(view.fov.down),
                              std::tan(view.fov.up)};
  return c;
}

VolumeTransform transform_placing_camera(const Camera& camera, const Pose& head, double scale) {
  // The camera's frame in the volume (right, up, back), as rays_in_world builds it.
  const glm::dvec3 f = glm::normalize(camera.target - camera.eye);
  glm::dvec3 r = glm::cross(f, camera.up);
  if (glm::length(r) < 1e-12) r = glm::cross(f, glm::dvec3(1, 0, 0));  // looking straight along up
  r = glm::normalize(r);
  const glm::dvec3 u = glm::cross(r, f);
  const glm::dquat camera_in_volume = glm::quat_cast(glm::dmat3(r, u, -f));
  VolumeTransform t;
  t.scale = scale;
  t.orientation = glm::normalize(head.orientation * glm::conjugate(camera_in_volume));
  t.position = head.position - t.orientation * (scale * camera.eye);
  return t;
}

Pose head_of_views(const std::vector<ViewSpec>& views) {
  Pose head;
  if (views.empty()) return head;
  head.orientation = views.front().pose.orientation;
  head.position = glm::dvec3(0.0);
  for (const ViewSpec& v : views) head.position += v.pose.position;
  head.position /= double(views.size());
  return head;
}

std::vector<ViewSpec> stereo_views(const Pose& head, double ipd_m, const Fov& fov, uint32_t width,
                                   uint32_t height) {
  std::vector<ViewSpec> views(2);
  for (int eye = 0; eye < 2; ++eye) {
    Pose offset;
    offset.position = {(eye == 0 ? -0.5 : 0.5) * ipd_m, 0.0, 0.0};
    views[eye] = {head * offset, fov, width, height};
  }
  return views;
}

}  // namespace vxr::xr
