// The CPU reference ray caster: the same optical models and transfer functions
// as the GPU core (shaders_glsl/include/raycast_core.glsl), in double
// precision, with exact exponentials, exact trilinear interpolation and a fine
// step. It is the ground truth that GPU error is measured against, and it is
// slow on purpose (about 20 M samples/s per core).
#pragma once

#include <span>

#include "core/status.h"
#include "render/camera.h"
#include "render/raycaster.h"
#include "scene/render_settings.h"
#include "volume/dense_volume.h"

namespace vxr {

struct ReferenceOptions {
  double step_voxels = 1.0 / 16.0;  // replaces the settings' step
  unsigned threads = 0;             // 0: hardware concurrency
};

// Premultiplied RGBA, like Raycaster::render_float. Channels as for
// Raycaster::set_channels (values normalised the way the GPU's textures are:
// u8 / 255, u16 / 65535, others as they are).
Result<ImageRgbaF> render_reference(std::span<const DenseVolume> channels, const Camera& camera,
                                    const RenderSettings& settings, uint32_t width, uint32_t height,
                                    const ReferenceOptions& options = {});

}  // namespace vxr
