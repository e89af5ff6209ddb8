#include "render/raycast_setup.h"

#include <algorithm>
#include <cmath>

#include "render/transfer_function.h"

namespace vxr {

RaycastSetup plan_raycast(const Camera& camera, const RenderSettings& s, const VolumePlacement& placement,
                          std::span<const double> value_scales, uint32_t width, uint32_t height) {
  RaycastSetup r;
  r.rays = rays_in_voxel_space(camera, placement, width, height);
  r.dims = glm::dvec3(placement.dims[0], placement.dims[1], placement.dims[2]);
  r.channels = static_cast<uint32_t>(value_scales.size());
  r.width = width;
  r.height = height;
  for (uint32_t c = 0; c < VXR_MAX_CHANNELS; ++c) {
    const ChannelSettings ch = channel_settings(s, c);
    const double scale = c < value_scales.size() ? value_scales[c] : 1.0;
    r.window[c] = {ch.window_lo / scale, ch.window_hi / scale, ch.gamma, (ch.enabled && c < r.channels) ? 1.0 : 0.0};
  }
  r.model = s.model;
  r.blend = s.blend;
  r.step = s.step_voxels;
  r.density = s.density;
  r.epsilon = s.early_termination;
  r.opacity_correction = s.opacity_correction;
  if (s.opacity_unit_distance > 0.0)
    r.world_opacity = glm::dvec3(placement.voxel_size[0], placement.voxel_size[1], placement.voxel_size[2]) /
                      s.opacity_unit_distance;
  r.jitter = s.jitter;
  r.sample_offset = s.sample_offset;
  r.iso_channel = s.iso_channel;
  {
    const ChannelSettings ch = channel_settings(s, s.iso_channel);
    const double v = std::clamp((s.iso_value - ch.window_lo) / (ch.window_hi - ch.window_lo), 0.0, 1.0);
    r.iso_norm = ch.gamma == 1.0 ? v : std::pow(v, ch.gamma);
  }
  r.shading = s.shading;
  r.depth_mode = s.depth_color;
  // View depth of the box's corners along the unit voxel-space forward axis.
  const glm::dvec3 f = glm::normalize(r.rays.forward);
  double lo = 1e300, hi = -1e300;
  for (int k = 0; k < 8; ++k) {
    const glm::dvec3 corner((k & 1) ? r.dims.x : 0.0, (k & 2) ? r.dims.y : 0.0, (k & 4) ? r.dims.z : 0.0);
    const double d = glm::dot(corner - r.rays.eye, f);
    lo = std::min(lo, d);
    hi = std::max(hi, d);
  }
  r.depth_lo = lo;
  r.depth_hi = hi > lo ? hi : lo + 1.0;
  r.gradient = s.gradient_opacity.enabled;
  r.gradient_lo = s.gradient_opacity.lo;
  r.gradient_hi = s.gradient_opacity.hi;
  r.max_steps = s.max_steps;
  return r;
}

double ray_density(const RaycastSetup& r, const glm::dvec3& dir) {
  if (r.world_opacity == glm::dvec3(0.0)) return r.density;
  return r.density * glm::length(dir * r.world_opacity);
}

shader::RaycastParams pack_params(const RaycastSetup& r, bool has_depth_image) {
  auto v4 = [](const glm::dvec3& v, double w = 0.0) { return glm::vec4(glm::dvec4(v, w)); };
  shader::RaycastParams p{};
  p.eye = v4(r.rays.eye);
  p.forward = v4(r.rays.forward);
  p.right = v4(r.rays.right);
  p.up = v4(r.rays.up);
  p.dims = v4(r.dims, r.channels);
  p.march = glm::vec4(glm::dvec4(r.step, r.density, r.epsilon, r.jitter ? -1.0 : r.sample_offset));
  p.iso = glm::vec4(glm::dvec4(r.iso_norm, r.shading.ambient, r.shading.diffuse, r.shading.specular));
  p.shading = glm::vec4(glm::dvec4(r.shading.shininess, has_depth_image ? 1.0 : 0.0, 0.0, 0.0));
  p.depth = glm::vec4(glm::dvec4(static_cast<double>(r.depth_mode), r.depth_lo, r.depth_hi, 0.0));
  p.gradient = glm::vec4(glm::dvec4(r.gradient ? 1.0 : 0.0, r.gradient_lo, r.gradient_hi, 0.0));
  p.world_opacity = v4(r.world_opacity);
  p.region_lo = v4(glm::dvec3(0.0));  // the whole volume; a renderer with an ROI narrows it
  p.region_hi = v4(r.dims);
  uint32_t model = VXR_MODEL_EMISSION_ABSORPTION;
  switch (r.model) {
    case OpticalModel::kEmissionAbsorption: model = VXR_MODEL_EMISSION_ABSORPTION; break;
    case OpticalModel::kEmission: model = VXR_MODEL_EMISSION; break;
    case OpticalModel::kMip: model = VXR_MODEL_MIP; break;
    case OpticalModel::kMinIp: model = VXR_MODEL_MINIP; break;
    case OpticalModel::kAverage: model = VXR_MODEL_AVERAGE; break;
    case OpticalModel::kIsosurface: model = VXR_MODEL_ISOSURFACE; break;
  }
  p.control = glm::uvec4(model, r.width, r.height, r.max_steps);
  p.control2 = glm::uvec4(r.blend == ChannelBlend::kAdditive ? VXR_BLEND_ADDITIVE : VXR_BLEND_COMPOSITE,
                          r.iso_channel, r.opacity_correction ? 0u : 1u, 0);
  for (int c = 0; c < VXR_MAX_CHANNELS; ++c) {
    glm::vec4& w = p.window[c] = glm::vec4(r.window[c]);
    if (w.w != 0.0f) w.w = 1.0f / (w.y - w.x);  // the rays' scale: lavapipe divided again every sample
  }
  return p;
}

}  // namespace vxr
