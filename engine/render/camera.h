// Cameras and the mapping between world space and a volume's voxel space.
//
// World space is physical units (the volume's unit) with the volume centred
// at the origin. All camera math is double on the CPU; the GPU only sees the
// result in voxel coordinates.
#pragma once

#include <array>
#include <glm/glm.hpp>
#include <optional>

namespace vxr {

// An off-axis frustum as tangents of its half-angles (OpenXR's XrFovf, after
// tan()): left and down are usually negative. Head-mounted displays give each
// eye an asymmetric one.
struct FrustumTangents {
  double left = -1.0, right = 1.0, down = -1.0, up = 1.0;
};

struct Camera {
  glm::dvec3 eye{0, 0, 1};
  glm::dvec3 target{0, 0, 0};
  glm::dvec3 up{0, 1, 0};
  double fov_y_deg = 40.0;
  // When set, the image spans exactly this frustum (fov_y_deg and the image
  // aspect are ignored); the eye still looks along target - eye.
  std::optional<FrustumTangents> frustum;
};

// Where a volume sits in world space: voxel (i + 0.5) centres, the box centre
// at `origin`, scaled by voxel size.
struct VolumePlacement {
  std::array<uint32_t, 3> dims{1, 1, 1};
  std::array<double, 3> voxel_size{1, 1, 1};
  // World position of the box centre. Kept in double and subtracted before
  // anything reaches the GPU, so a volume 2^24 voxels from the origin renders
  // like one at the origin (../shared/design/numerics.md).
  glm::dvec3 origin{0, 0, 0};

  glm::dvec3 extent() const;  // physical size of the whole box
  glm::dvec3 world_to_voxel_point(const glm::dvec3& w) const;
  glm::dvec3 world_to_voxel_vector(const glm::dvec3& w) const;
};

// A camera looking at the volume centre from (azimuth, elevation) degrees, at
// `distance` times the box diagonal; +z of the volume is up on screen.
Camera orbit_camera(const VolumePlacement& v, double azimuth_deg, double elevation_deg, double distance = 1.6,
                    double fov_y_deg = 40.0);

// The eye and pixel-direction basis: pixel (nx, ny) looks along
// forward + nx right - ny up (see pixel_ray). In world space forward is a unit
// vector (off-axis: its component along the view axis is 1) and right/up are
// scaled by the frustum's half-extent tangents, so t along that direction is
// view depth.
struct PixelRays {
  glm::dvec3 eye, forward, right, up;  // right/up scaled by tan(fov/2) (and aspect for right)
};
using VoxelSpaceRays = PixelRays;
PixelRays rays_in_world(const Camera& c, uint32_t width, uint32_t height);
// The same rays in a volume's voxel space, as the ray casters want them.
VoxelSpaceRays rays_in_voxel_space(const Camera& c, const VolumePlacement& v, uint32_t width, uint32_t height);

// Pixel (x, y)'s unit ray direction in voxel space (pixel centres, top row
// first: the same ndc as the ray caster, (2 x + 1 - width) / width).
glm::dvec3 pixel_ray(const VoxelSpaceRays& r, uint32_t width, uint32_t height, uint32_t x, uint32_t y);

// Length of the ray eye + t dir (t >= 0, dir unit) inside the box [0, dims],
// by the slab test in double; 0 when it misses.
double length_in_box(const glm::dvec3& eye, const glm::dvec3& dir, const glm::dvec3& dims);

// Samples a ray marching the whole box takes at `step` voxels without early
// termination or skipping: per pixel, ceil(length in the box / step).
uint64_t dense_sample_count(const Camera& c, const VolumePlacement& v, double step, uint32_t width, uint32_t height);

}  // namespace vxr
