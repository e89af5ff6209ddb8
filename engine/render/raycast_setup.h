// Everything a ray needs, derived once in double on the CPU from the camera,
// the settings and the volume: the GPU ray caster packs it into floats
// (shader::RaycastParams), the CPU reference uses it as is.
#pragma once

#include <array>
#include <span>

#include "render/camera.h"
#include "scene/render_settings.h"
#include "shared/raycast_params.h"

namespace vxr {

struct RaycastSetup {
  VoxelSpaceRays rays;
  glm::dvec3 dims{1, 1, 1};
  uint32_t channels = 1;
  uint32_t width = 1, height = 1;
  // Per channel: window lo, hi in texel units (data / value_scale), gamma, enabled (0/1).
  std::array<glm::dvec4, VXR_MAX_CHANNELS> window{};
  OpticalModel model = OpticalModel::kEmissionAbsorption;
  ChannelBlend blend = ChannelBlend::kAdditive;
  double step = 0.5, density = 0.25, epsilon = 1.0 / 512.0;
  bool opacity_correction = true;
  // Opacity per world unit (settings.opacity_unit_distance > 0): world units
  // per voxel along each axis divided by the unit distance; a ray with unit
  // voxel-space direction d then has extinction density * |d * this| per
  // voxel of t. Zero: per-voxel opacity, density as is.
  glm::dvec3 world_opacity{0.0};
  bool jitter = false;
  double sample_offset = 0.5;
  double iso_norm = 0.5;  // the iso value, windowed and gamma'd like the samples
  uint32_t iso_channel = 0;
  ShadingSettings shading;
  DepthColorMode depth_mode = DepthColorMode::kOff;
  double depth_lo = 0.0, depth_hi = 1.0;  // view-axis depth across the box (voxel units)
  bool gradient = false;
  double gradient_lo = 0.0, gradient_hi = 1.0;
  uint32_t max_steps = 1u << 16;
};

// `value_scales[c]`: data units per texel unit of channel c (255 for u8 in an
// R8_UNORM texture, 65535 for u16, 1 for float textures).
RaycastSetup plan_raycast(const Camera& camera, const RenderSettings& s, const VolumePlacement& placement,
                          std::span<const double> value_scales, uint32_t width, uint32_t height);

// The extinction at TF opacity 1 per unit of ray parameter t along the unit
// voxel-space direction `dir`: the density, scaled by the physical length of
// one voxel of t in world-unit opacity. The GPU repeats it (vxr_ray_density).
double ray_density(const RaycastSetup& r, const glm::dvec3& dir);

shader::RaycastParams pack_params(const RaycastSetup& r, bool has_depth_image);

}  // namespace vxr
