// One still picture of a session (render/volume_session.h) through the brick
// renderer vxr view uses: what `vxr render` draws. Frames are rendered until
// nothing is missing (every wanted brick resident), or a fixed number, or,
// with a frame budget, a number of frames while the LOD bias follows the
// frame time; each frame's figures come back with the last image.
#pragma once

#include <cstdint>
#include <functional>
#include <vector>

#include "core/image.h"
#include "core/status.h"
#include "gpu/context.h"
#include "render/camera.h"
#include "render/lod/brick_renderer.h"
#include "render/volume_session.h"

namespace vxr {

struct StillFrame {
  int frame = 0;  // 1-based
  double wall_ms = 0.0;  // record + submit + wait, this frame
  double gpu_ms = 0.0;   // timestamp queries
  double lod_bias = 0.0;  // the bias this frame was drawn with
  uint64_t samples = 0, bricks_drawn = 0, bricks_missing = 0, bricks_uploaded = 0;
  double rmse_vs_reference = -1.0;  // 8-bit units over black, all four channels; < 0: not measured
};

struct StillOptions {
  uint32_t width = 512, height = 512;
  double lod_bias = 0.0;         // log2 voxels per pixel accepted; the start value with a budget
  double frame_budget_ms = 0.0;  // > 0: `frames` frames (30 if 0), the bias following the frame time
  int frames = 0;                // 0: until converged (an error past 1000 frames); else exactly this many
  bool skip_empty = true;        // false: march empty space too (the same image; for A/B timing)
  // Each frame's RMSE against the CPU reference of the finest level (drawn once, at this step).
  bool compare_to_reference = false;
  double reference_step = 1.0 / 16.0;
  std::function<void(const StillFrame&)> on_frame;  // after each frame
};

struct StillResult {
  ImageRgba8 image;  // the last frame, premultiplied alpha (over_black() for a PNG)
  std::vector<StillFrame> frames;
  bool converged = false;  // the last frame missed no brick
  double total_ms = 0.0;   // wall clock over every frame
  double reference_cpu_ms = 0.0;  // the CPU reference, when compared
  BrickFrameStats last;           // the last frame's statistics
  uint64_t bricks_uploaded = 0, bytes_uploaded = 0;  // in all, the bricks pinned at creation included
  uint32_t pool_used = 0, pool_capacity = 0;
};

// Draws `session` (its source, settings, channels, timepoint and annotation
// store) seen by `camera` (volume frame, centred at 0). kInvalidArgument for
// settings the brick renderer refuses; kInternal when frames = 0 and no
// budget and bricks are still missing after 1000 frames.
Result<StillResult> render_still(gpu::Context& gpu, const VolumeSession& session, const Camera& camera,
                                 const StillOptions& options);

// The CPU reference picture of `vxr render --reference`: the whole volume
// read (averaged down to at most `max_dim` per side), timepoint 0, the
// settings choose_settings + resolve_drawn_settings give (as the session's,
// with windows from the volume read), drawn once in double precision
// (render/reference_renderer.h), clipped by the settings' cut plane and box.
struct ReferenceStillOptions {
  uint32_t width = 512, height = 512;
  double reference_step = 1.0 / 16.0;  // the CPU reference's step in voxels
  uint32_t max_dim = 2048;             // what is read, per side
};

struct ReferenceStill {
  ImageRgba8 image;  // premultiplied alpha
  RenderSettings settings;
  std::vector<uint32_t> channels;  // the source channels drawn
  Camera camera;
  uint32_t shrink = 1;          // the volume was averaged down by this per axis
  uint64_t sample_bound = 0;    // samples the rays march before early termination (slab test per pixel)
  double ms = 0.0;              // the render, wall clock
  std::vector<std::string> notes;
};

// The camera for a volume's placement (`flat`: a single slice).
using CameraChooser = std::function<Result<Camera>(const VolumePlacement& placement, bool flat)>;

// `failed_at` as open_volume_session's.
Result<ReferenceStill> render_still_reference(const std::string& input, const SessionFlags& flags,
                                              const CameraChooser& camera_for, const ReferenceStillOptions& options,
                                              SessionStep* failed_at = nullptr);

}  // namespace vxr
