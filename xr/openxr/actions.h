// The OpenXR actions vxr reads and the bindings it suggests, one table per
// controller family: grip pose, aim pose, grab, trigger, thumbstick, menu,
// thumbstick click (teleport), pick and finish (the tracing tool's buttons)
// and haptics, for each hand. The runtime picks the profile that matches the
// controllers; the interaction code only ever sees InputState.
#pragma once

#include <array>
#include <string>

#include "xr/openxr/xr_check.h"
#include "xr/pose.h"

namespace vxr::xr {

class XrActions {
 public:
  // Creates the action set and actions and suggests bindings for
  // khr/simple_controller, oculus/touch_controller, htc/vive_controller,
  // valve/index_controller and microsoft/motion_controller.
  Status create(XrInstance instance, XrErrors& errors);
  // Attaches the set to the session and creates the pose spaces.
  Status attach(XrSession session, XrErrors& errors);
  // Syncs and reads both hands (poses located in `base` at `time`).
  Status read(XrSession session, XrSpace base, XrTime time, InputState& out, XrErrors& errors);
  Status haptic(XrSession session, Hand hand, double amplitude, double seconds, XrErrors& errors);
  // The profile the runtime chose for the left/right hand ("" if none yet).
  std::string current_profile(XrInstance instance, XrSession session, XrErrors& errors);
  // Destroys the session's spaces (the action set goes with the instance).
  void detach();

 private:
  XrActionSet set_ = XR_NULL_HANDLE;
  XrAction grip_ = XR_NULL_HANDLE, aim_ = XR_NULL_HANDLE, grab_ = XR_NULL_HANDLE, trigger_ = XR_NULL_HANDLE,
           thumbstick_ = XR_NULL_HANDLE, menu_ = XR_NULL_HANDLE, stick_click_ = XR_NULL_HANDLE, pick_ = XR_NULL_HANDLE,
           finish_ = XR_NULL_HANDLE, haptic_ = XR_NULL_HANDLE;
  std::array<XrPath, 2> hands_{XR_NULL_PATH, XR_NULL_PATH};
  std::array<XrSpace, 2> grip_space_{XR_NULL_HANDLE, XR_NULL_HANDLE};
  std::array<XrSpace, 2> aim_space_{XR_NULL_HANDLE, XR_NULL_HANDLE};
};

Pose to_pose(const XrPosef& p);

}  // namespace vxr::xr
