// Picks the FrameTarget for `vxr view`: the one factory file that knows every
// implementation (hello_xr's platform/graphics plugin factory, one axis).
#pragma once

#include <memory>
#include <string>

#include "xr/headless/headless_target.h"
#include "xr/view_session.h"

namespace vxr::xr {

struct ViewerSetup;  // xr/desktop/viewer_setup.h

enum class TargetKind { kAuto, kOpenXr, kDesktop, kHeadless };

struct TargetRequest {
  TargetKind kind = TargetKind::kAuto;
  HeadlessOptions headless;     // also gives desktop its eye size and fov
  bool desktop_stereo = false;  // side-by-side
  bool mirror = false;              // OpenXR: also show the eye images in a desktop window
  std::string desktop_screenshot;  // desktop: grab the window from the X server into this PNG at exit
  uint32_t max_eye_width = 0, max_eye_height = 0;  // OpenXR: clamp the runtime's eye size
  std::shared_ptr<const ViewerSetup> viewer;       // desktop: panels and controls (null: the bare window)
};

struct TargetChoice {
  TargetKind kind = TargetKind::kHeadless;
  std::string reason;     // "using OpenXR (...)", "using headless (no display: ...)"
  TargetFactory factory;  // called at each (re)start of the session loop
};

// Probes in order OpenXR, desktop, headless (or only the forced one) and says
// why it chose what it chose. A forced target that is unavailable is an error
// naming what is missing.
Result<TargetChoice> choose_target(const TargetRequest& request);

}  // namespace vxr::xr
