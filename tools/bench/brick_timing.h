// What `vxr bench peer` and `vxr bench roofline` share: the VTK-style
// transfer function and the timing of converged brick-renderer frames.
#pragma once

#include "core/image.h"
#include "core/status.h"
#include "render/camera.h"
#include "render/lod/brick_renderer.h"
#include "scene/render_settings.h"

namespace vxr::bench {

// A linear opacity ramp over the window [lo, hi], grey: VTK's usual setup.
RenderSettings vtk_ramp(OpticalModel model, double lo, double hi);

struct TimedFrames {
  double wall_ms = 0.0, gpu_ms = 0.0;  // medians over the timed frames
  BrickFrameStats stats;               // the last frame's
  ImageRgba8 image;                    // the last frame
};

// Renders until every brick is resident (an error past 200 frames), then
// the median wall and GPU time of `repeats` more frames (after a warm-up).
Result<TimedFrames> time_converged(BrickRenderer& r, const Camera& cam, const RenderSettings& s,
                                   const BrickFrameSettings& f, uint32_t size, int repeats);

}  // namespace vxr::bench
