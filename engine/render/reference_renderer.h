// The CPU reference ray caster: the same optical models and transfer functions
// as the GPU core (shaders_glsl/include/raycast_core.glsl), in double
// precision, with exact exponentials, exact trilinear interpolation and a fine
// step. It is the ground truth that GPU error is measured against, and it is
// slow on purpose (about 20 M samples/s per core).
#pragma once

#include <span>

#include "core/status.h"
#include "render/camera.h"
#include "core/image.h"
#include "scene/render_settings.h"
#include "volume/dense_volume.h"

namespace vxr {

struct ReferenceOptions {
  double step_voxels = 1.0 / 16.0;  // replaces the settings' step
  unsigned threads = 0;             // 0: hardware concurrency
  // Clipping in voxel coordinates, as the out-of-core renderer's ROI and cut
  // plane do it (render/lod/lod_traversal.h): only [clip_lo, clip_hi] and the
  // side dot(plane.xyz, p) + plane.w >= 0 are drawn. Defaults clip nothing.
  glm::dvec3 clip_lo{-1e300}, clip_hi{1e300};
  glm::dvec4 plane{0.0};
  // false: samples at segment midpoints from where the ray enters the box
  // (the last segment partial; the exact quadrature). true: sample i at (i + o) * step from the eye,
  // each for a whole step, o the settings' sample_offset or, with jitter, the
  // shader's per-pixel hash: the out-of-core renderer's grid, which every
  // brick shares, so a comparison at the same step takes the same samples.
  bool grid_from_eye = false;
  // Where rays end, per pixel (width x height, row-major): view depth in world
  // units along the camera's forward axis (an annotation pass's depth), +inf:
  // nowhere. Empty: the box decides.
  std::span<const float> view_depth;
};

// Premultiplied RGBA, like BrickRenderer::render_float. 1-4 channels of the
// same dims (values normalised the way the GPU's textures are: u8 / 255,
// u16 / 65535, others as they are).
Result<ImageRgbaF> render_reference(std::span<const DenseVolume> channels, const Camera& camera,
                                    const RenderSettings& settings, uint32_t width, uint32_t height,
                                    const ReferenceOptions& options = {});

}  // namespace vxr
