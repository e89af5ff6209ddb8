// The frame loop every target shares, inside an outer restart loop
// (hello_xr's shape):
//
//   for each (re)start: make the target -> Vulkan context (target's hooks)
//     -> attach -> eye renderer (uploads the volume)
//     frame loop: wait_frame -> interaction -> render each view into the
//                 target's image -> end_frame
//   a lost session/instance (wants_restart) tears everything down in order
//   and starts again; any other error ends the run with its message.
//
// The volume transform and frame count live outside the restart loop, so a
// recovered session continues where the lost one stopped.
#pragma once

#include <functional>
#include <memory>
#include <string>

#include "render/raycaster.h"
#include "volume/dense_volume.h"
#include "xr/frame_target.h"
#include "xr/interaction.h"
#include "xr/lens_warp.h"
#include "xr/volume_transform.h"

namespace vxr::xr {

struct ViewOptions {
  uint64_t frames = 0;  // rendered frames before an orderly exit; 0: until the target ends
  RenderSettings settings;
  LensWarp warp;
  int max_restarts = 3;
  // Called after each rendered frame with the images of its views (mirror
  // window, tests); may be empty.
  std::function<void(uint64_t frame, const std::vector<ImageRgba8>& views)> on_frame;
};

struct ViewStats {
  std::string target;          // describe() of the last target
  std::string device_fingerprint;  // of the Vulkan device the frames were rendered on
  uint64_t frames_rendered = 0;
  uint64_t frames_submitted = 0;  // including frames the runtime said not to render
  int restarts = 0;
  double mean_frame_ms = 0.0;  // wall time per rendered frame (render + upload + submit)
  double max_frame_ms = 0.0;
  uint64_t rays = 0;
  VolumeTransform transform;   // where the interaction left the volume
};

using TargetFactory = std::function<Result<std::unique_ptr<FrameTarget>>()>;

// The RenderSettings `vxr view` uses for 8-bit data of unknown content.
RenderSettings default_view_settings();

Result<ViewStats> run_view(const TargetFactory& make_target, const DenseVolume& volume, const ViewOptions& options,
                           const VolumeTransform& initial);

}  // namespace vxr::xr
