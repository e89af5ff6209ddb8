// Transfer functions: settings -> the table the GPU and the CPU reference both
// read, and the checks that turn bad settings into one clear message.
#pragma once

#include <glm/glm.hpp>
#include <vector>

#include "core/status.h"
#include "scene/render_settings.h"
#include "shared/raycast_params.h"

namespace vxr {

// VXR_TF_SIZE x VXR_MAX_CHANNELS RGBA, row c = channel c; entry i is the
// colour (rgb) and opacity (a) at window-normalised x = i / (VXR_TF_SIZE - 1).
struct TransferTable {
  std::vector<glm::vec4> rgba;
  glm::dvec4 at(int channel, int i) const { return glm::dvec4(rgba[size_t(channel) * VXR_TF_SIZE + i]); }
  // The same interpolation as vxr_transfer_table() in raycast_core.glsl, in double.
  glm::dvec4 lookup(int channel, double x) const;
};

// Checks every setting against a volume of `channel_count` channels; the
// message names the setting ("channels[1].window: lo 30 must be below hi 20").
Status validate_render_settings(const RenderSettings& s, uint32_t channel_count);

// Assumes validate_render_settings() passed.
TransferTable build_transfer_table(const RenderSettings& s);

// The settings of channel c of a volume (channels past those given are off).
ChannelSettings channel_settings(const RenderSettings& s, uint32_t c);

}  // namespace vxr
