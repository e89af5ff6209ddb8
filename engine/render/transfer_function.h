// Transfer functions: settings -> the table the GPU and the CPU reference both
// read, and the checks that turn bad settings into one clear message.
#pragma once

#include <array>
#include <glm/glm.hpp>
#include <optional>
#include <vector>

#include "core/status.h"
#include "scene/render_settings.h"
#include "shared/raycast_params.h"

namespace vxr {

// VXR_TF_SIZE x VXR_MAX_CHANNELS RGBA, row c = channel c; entry i is the
// colour (rgb) and opacity (a) at window-normalised x = i / (VXR_TF_SIZE - 1).
struct TransferTable {
  std::vector<glm::vec4> rgba;
  // Per channel, the hue h (each component 0 or 1) with rgb = h * s at every
  // entry, s the entry's one value: a single-hue colour map (gray, red, ...,
  // yellow, #00ff00). The GPU then reads one texel a lookup (entries i and
  // i + 1 of s and opacity) and gets the same floats. None where the colours
  // do not factor so (hot, viridis, #ff8000, most colour points).
  std::array<std::optional<glm::vec3>, VXR_MAX_CHANNELS> hue;
  glm::dvec4 at(int channel, int i) const { return glm::dvec4(rgba[size_t(channel) * VXR_TF_SIZE + i]); }
  // The same interpolation as vxr_transfer_table() in raycast_core.glsl, in double.
  glm::dvec4 lookup(int channel, double x) const;
};

// The value s of a colour rgb = hue * s (TransferTable::hue): the component the hue keeps.
inline float hue_value(const glm::vec3& hue, const glm::vec4& rgba) {
  return hue.r != 0.0f ? rgba.r : hue.g != 0.0f ? rgba.g : rgba.b;
}

// Checks every setting against a volume of `channel_count` channels; the
// message names the setting ("channels[1].window: lo 30 must be below hi 20").
Status validate_render_settings(const RenderSettings& s, uint32_t channel_count);

// Assumes validate_render_settings() passed.
TransferTable build_transfer_table(const RenderSettings& s);

// The settings of channel c of a volume (channels past those given are off).
ChannelSettings channel_settings(const RenderSettings& s, uint32_t c);

}  // namespace vxr
