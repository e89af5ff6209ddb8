#include "render/transfer_function.h"

#include <algorithm>
#include <cmath>

#include "render/colormap.h"

namespace vxr {
namespace {

template <typename P, typename V>
V piecewise(const std::vector<P>& pts, double x, V (*value)(const P&)) {
  if (x <= pts.front().x) return value(pts.front());
  if (x >= pts.back().x) return value(pts.back());
  for (size_t k = 1; k < pts.size(); ++k) {
    if (x <= pts[k].x) {
      const double span = pts[k].x - pts[k - 1].x;
      const double f = span > 0 ? (x - pts[k - 1].x) / span : 1.0;
      return value(pts[k - 1]) * (1.0 - f) + value(pts[k]) * f;
    }
  }
  return value(pts.back());
}

glm::dvec3 color_of(const ColorPoint& p) { return {p.rgb[0], p.rgb[1], p.rgb[2]}; }
double opacity_of(const OpacityPoint& p) { return p.opacity; }

std::string num(double v) {
  char b[32];
  std::snprintf(b, sizeof(b), "%g", v);
  return b;
}

// The hue of one channel's entries, where every colour is hue * s (see TransferTable::hue).
std::optional<glm::vec3> factor_hue(const glm::vec4* entries) {
  glm::vec3 hue(0.0f);
  for (int i = 0; i < VXR_TF_SIZE; ++i)
    for (int k = 0; k < 3; ++k)
      if (entries[i][k] != 0.0f) hue[k] = 1.0f;
  for (int i = 0; i < VXR_TF_SIZE; ++i)
    if (hue * hue_value(hue, entries[i]) != glm::vec3(entries[i])) return std::nullopt;
  return hue;
}

}  // namespace

glm::dvec4 TransferTable::lookup(int channel, double x) const {
  const double u = std::clamp(x, 0.0, 1.0) * (VXR_TF_SIZE - 1);
  const int i = std::min(static_cast<int>(u), VXR_TF_SIZE - 2);
  const double f = u - i;
  return at(channel, i) * (1.0 - f) + at(channel, i + 1) * f;
}

ChannelSettings channel_settings(const RenderSettings& s, uint32_t c) {
  if (c < s.channels.size()) return s.channels[c];
  ChannelSettings off;
  off.enabled = false;
  return off;
}

Status validate_render_settings(const RenderSettings& s, uint32_t channel_count) {
  if (channel_count < 1 || channel_count > VXR_MAX_CHANNELS)
    return invalid_argument("the volume has " + std::to_string(channel_count) + " channels; the ray caster takes 1 to " +
                            std::to_string(VXR_MAX_CHANNELS));
  if (s.channels.empty()) return invalid_argument("channels: at least one channel's settings are needed");
  if (s.channels.size() > VXR_MAX_CHANNELS)
    return invalid_argument("channels: " + std::to_string(s.channels.size()) + " given, at most " +
                            std::to_string(VXR_MAX_CHANNELS));
  if (!(s.step_voxels > 0.0) || !std::isfinite(s.step_voxels))
    return invalid_argument("step: " + num(s.step_voxels) + " voxels; the step must be > 0");
  if (!(s.density >= 0.0) || !std::isfinite(s.density))
    return invalid_argument("density: " + num(s.density) + "; it must be >= 0");
  if (!(s.opacity_unit_distance >= 0.0) || !std::isfinite(s.opacity_unit_distance))
    return invalid_argument("opacity_unit_distance: " + num(s.opacity_unit_distance) +
                            "; it must be > 0 world units, or 0 for per-voxel opacity");
  if (!(s.early_termination >= 0.0 && s.early_termination < 1.0))
    return invalid_argument("early_termination: " + num(s.early_termination) + "; it must be in [0, 1)");
  if (!(s.sample_offset >= 0.0 && s.sample_offset <= 1.0))
    return invalid_argument("sample_offset: " + num(s.sample_offset) + "; it must be in 0..1");
  if (s.max_steps == 0) return invalid_argument("max_steps: must be > 0");
  if (s.iso_channel >= channel_count)
    return invalid_argument("iso_channel: " + std::to_string(s.iso_channel) + " but the volume has " +
                            std::to_string(channel_count) + " channel(s)");
  if (s.gradient_opacity.enabled && !(s.gradient_opacity.hi > s.gradient_opacity.lo))
    return invalid_argument("gradient_opacity: lo " + num(s.gradient_opacity.lo) + " must be below hi " +
                            num(s.gradient_opacity.hi));
  bool any = false;
  for (size_t c = 0; c < s.channels.size(); ++c) {
    const ChannelSettings& ch = s.channels[c];
    const std::string at = "channels[" + std::to_string(c) + "].";
    if (!(ch.window_hi > ch.window_lo) || !std::isfinite(ch.window_lo) || !std::isfinite(ch.window_hi))
      return invalid_argument(at + "window: lo " + num(ch.window_lo) + " must be below hi " + num(ch.window_hi));
    if (!(ch.gamma > 0.0) || !std::isfinite(ch.gamma))
      return invalid_argument(at + "gamma: " + num(ch.gamma) + "; it must be > 0");
    if (!find_colormap(ch.colormap)) {
      std::string names;
      for (const auto& n : colormap_names()) names += (names.empty() ? "" : ", ") + n;
      return invalid_argument(at + "colormap: unknown colormap '" + ch.colormap + "' (known: " + names + ", or #rrggbb for one hue)");
    }
    double last = -1.0;
    for (const auto& p : ch.color_points) {
      if (!(p.x >= 0.0 && p.x <= 1.0) || p.x < last)
        return invalid_argument(at + "color_points: x must rise within 0..1, got " + num(p.x));
      last = p.x;
      for (double v : p.rgb)
        if (!(v >= 0.0 && v <= 1.0)) return invalid_argument(at + "color_points: rgb must be in 0..1");
    }
    last = -1.0;
    for (const auto& p : ch.opacity_points) {
      if (!(p.x >= 0.0 && p.x <= 1.0) || p.x < last)
        return invalid_argument(at + "opacity_points: x must rise within 0..1, got " + num(p.x));
      last = p.x;
      if (!(p.opacity >= 0.0 && p.opacity <= 1.0))
        return invalid_argument(at + "opacity_points: opacity must be in 0..1, got " + num(p.opacity));
    }
    if (ch.enabled && c < channel_count) any = true;
  }
  if (!any) return invalid_argument("channels: no enabled channel to draw");
  return Status::ok();
}

TransferTable build_transfer_table(const RenderSettings& s) {
  TransferTable t;
  t.rgba.assign(size_t(VXR_TF_SIZE) * VXR_MAX_CHANNELS, glm::vec4(0.0f));
  for (uint32_t c = 0; c < VXR_MAX_CHANNELS; ++c) {
    const ChannelSettings ch = channel_settings(s, c);
    const auto cmap = find_colormap(ch.colormap);
    for (int i = 0; i < VXR_TF_SIZE; ++i) {
      const double x = i / double(VXR_TF_SIZE - 1);
      glm::dvec3 rgb = ch.color_points.empty() ? (cmap ? (*cmap)[i] : glm::dvec3(x))
                                               : piecewise<ColorPoint, glm::dvec3>(ch.color_points, x, color_of);
      const double a = ch.opacity_points.empty() ? x : piecewise<OpacityPoint, double>(ch.opacity_points, x, opacity_of);
      t.rgba[size_t(c) * VXR_TF_SIZE + i] = glm::vec4(glm::dvec4(rgb, a));
    }
    t.hue[c] = factor_hue(&t.rgba[size_t(c) * VXR_TF_SIZE]);
  }
  return t;
}

}  // namespace vxr
