#include "render/camera.h"

#include <cmath>

namespace vxr {

glm::dvec3 VolumePlacement::extent() const {
  return {dims[0] * voxel_size[0], dims[1] * voxel_size[1], dims[2] * voxel_size[2]};
}

glm::dvec3 VolumePlacement::world_to_voxel_point(const glm::dvec3& w) const {
  return world_to_voxel_vector(w - origin) + 0.5 * glm::dvec3(dims[0], dims[1], dims[2]);
}

glm::dvec3 VolumePlacement::world_to_voxel_vector(const glm::dvec3& w) const {
  return {w.x / voxel_size[0], w.y / voxel_size[1], w.z / voxel_size[2]};
}

Camera orbit_camera(const VolumePlacement& v, double azimuth_deg, double elevation_deg, double distance,
                    double fov_y_deg) {
  const double az = glm::radians(azimuth_deg), el = glm::radians(elevation_deg);
  const double r = glm::length(v.extent()) * distance;
  Camera c;
  c.target = {0, 0, 0};
  c.eye = r * glm::dvec3(std::cos(el) * std::sin(az), -std::cos(el) * std::cos(az), std::sin(el));
  c.up = {0, 0, 1};
  c.fov_y_deg = fov_y_deg;
  return c;
}

VoxelSpaceRays rays_in_voxel_space(const Camera& c, const VolumePlacement& v, uint32_t width, uint32_t height) {
  const glm::dvec3 f = glm::normalize(c.target - c.eye);
  glm::dvec3 r = glm::cross(f, c.up);
  if (glm::length(r) < 1e-12) r = glm::cross(f, glm::dvec3(1, 0, 0));  // looking straight along up
  r = glm::normalize(r);
  const glm::dvec3 u = glm::cross(r, f);
  if (c.frustum) {
    // ndc -1..1 maps linearly onto left..right (down..up): shift the centre
    // direction, scale the half-extent. Top image row is `up`.
    const FrustumTangents& t = *c.frustum;
    const glm::dvec3 centre = f + r * (0.5 * (t.right + t.left)) + u * (0.5 * (t.up + t.down));
    return {v.world_to_voxel_point(c.eye), v.world_to_voxel_vector(centre),
            v.world_to_voxel_vector(r * (0.5 * (t.right - t.left))),
            v.world_to_voxel_vector(u * (0.5 * (t.up - t.down)))};
  }
  const double ty = std::tan(glm::radians(c.fov_y_deg) * 0.5);
  const double tx = ty * static_cast<double>(width) / static_cast<double>(height);
  // Directions are mapped linearly, so a pixel's ray maps exactly into voxel space.
  return {v.world_to_voxel_point(c.eye), v.world_to_voxel_vector(f), v.world_to_voxel_vector(r * tx),
          v.world_to_voxel_vector(u * ty)};
}

}  // namespace vxr
