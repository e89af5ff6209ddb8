#include "render/camera.h"

#include <algorithm>
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

PixelRays rays_in_world(const Camera& c, uint32_t width, uint32_t height) {
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
    return {c.eye, centre, r * (0.5 * (t.right - t.left)), u * (0.5 * (t.up - t.down))};
  }
  const double ty = std::tan(glm::radians(c.fov_y_deg) * 0.5);
  const double tx = ty * static_cast<double>(width) / static_cast<double>(height);
  return {c.eye, f, r * tx, u * ty};
}

VoxelSpaceRays rays_in_voxel_space(const Camera& c, const VolumePlacement& v, uint32_t width, uint32_t height) {
  // Directions are mapped linearly, so a pixel's ray maps exactly into voxel space.
  const PixelRays w = rays_in_world(c, width, height);
  return {v.world_to_voxel_point(w.eye), v.world_to_voxel_vector(w.forward), v.world_to_voxel_vector(w.right),
          v.world_to_voxel_vector(w.up)};
}

glm::dvec3 pixel_ray(const VoxelSpaceRays& r, uint32_t width, uint32_t height, uint32_t x, uint32_t y) {
  const double nx = (2.0 * x + 1.0 - width) / width, ny = (2.0 * y + 1.0 - height) / height;
  return glm::normalize(r.forward + nx * r.right - ny * r.up);
}

double length_in_box(const glm::dvec3& eye, const glm::dvec3& dir, const glm::dvec3& dims) {
  double t0 = 0.0, t1 = 1e300;
  for (int a = 0; a < 3; ++a) {
    if (dir[a] == 0.0) {
      if (eye[a] < 0.0 || eye[a] > dims[a]) return 0.0;
      continue;
    }
    const double ta = (0.0 - eye[a]) / dir[a], tb = (dims[a] - eye[a]) / dir[a];
    t0 = std::max(t0, std::min(ta, tb));
    t1 = std::min(t1, std::max(ta, tb));
  }
  return std::max(0.0, t1 - t0);
}

uint64_t dense_sample_count(const Camera& c, const VolumePlacement& v, double step, uint32_t width, uint32_t height) {
  const VoxelSpaceRays r = rays_in_voxel_space(c, v, width, height);
  const glm::dvec3 dims(v.dims[0], v.dims[1], v.dims[2]);
  uint64_t n = 0;
  for (uint32_t y = 0; y < height; ++y)
    for (uint32_t x = 0; x < width; ++x) {
      const double length = length_in_box(r.eye, pixel_ray(r, width, height, x, y), dims);
      if (length > 0.0) n += static_cast<uint64_t>(std::ceil(length / step));
    }
  return n;
}

}  // namespace vxr
