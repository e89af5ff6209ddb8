// What `vxr bench peer` and `vxr bench roofline` share: the VTK-style
// transfer function and the timing of converged brick-renderer frames.
#pragma once

#include <functional>
#include <vector>

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

// Frame settings of one view timed in turn: each rendered until every
// brick is resident (an error past 200 frames) and warmed up, then
// `repeats` rounds that draw each in turn (a frame shorter than 20 ms
// several times back to back, up to 50), so a busy machine's drift falls
// on all of them alike and their ratios hold (skipping on against off);
// the median wall and GPU time of each over all its timed frames. `after_round`, if set, runs after each
// round, and an untimed frame of the first kind follows it.
Result<std::vector<TimedFrames>> time_in_turn(BrickRenderer& r, const Camera& cam, const RenderSettings& s,
                                              const std::vector<BrickFrameSettings>& frames, uint32_t size,
                                              int repeats, const std::function<Status()>& after_round = {});

}  // namespace vxr::bench
