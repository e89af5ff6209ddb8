// The paper's cut plane tool ("virtual scissors"), device-independent like
// Teleport: a front end hands it the frame's InputState and the volume
// transform, and it keeps the plane the renderer clips by.
//
// While the right trigger is held (press above `press`, release below
// `release`, as HandTools) the plane follows the right controller: it passes
// through the controller's tip (`tip_m` along the aim ray) and its normal is
// the aim direction, so what lies between the hand and the tip plane is cut
// away and the volume beyond it stays (LodSettings::cut keeps
// dot(normal, p) + offset >= 0). Releasing leaves the plane where it was.
// The left trigger clears it (not while the right one holds the plane).
// A trigger already held when the tool becomes active must be pressed again.
//
// The plane is stored in the volume's level-0 voxel coordinates (the frame
// LodSettings::cut is in), not in the reference space: grabbing, scaling or
// teleporting the volume afterwards carries the plane with the volume.
//
// The tool acts only while `active` (the headset's tool cycle is on "cut");
// inactive, it keeps its plane and ignores the triggers.
#pragma once

#include <array>

#include "render/camera.h"
#include "render/lod/lod_traversal.h"
#include "xr/pose.h"
#include "xr/volume_transform.h"

namespace vxr::xr {

struct CutPlaneSettings {
  double press = 0.6;    // trigger value that presses
  double release = 0.4;  // ... and that releases
  double tip_m = 0.05;   // the plane passes this far along the aim ray (as HandTools' tip)
};

// What one frame's input did to the plane.
struct CutPlaneFrame {
  bool placed = false;   // the right trigger was released: the plane stays there (a haptic click)
  bool cleared = false;  // the left trigger removed the plane (a haptic click)
};

class CutPlaneTool {
 public:
  explicit CutPlaneTool(const VolumePlacement& placement, CutPlaneSettings s = {}) : placement_(placement), s_(s) {}

  // `active`: the headset's tool is the cut plane this frame.
  CutPlaneFrame update(const InputState& input, const VolumeTransform& t, bool active);

  // The plane the next frame clips by (disabled: none), in voxel coordinates.
  const CutPlane& plane() const { return plane_; }
  // Whether the frame's cut is this tool's: once the hands placed or cleared
  // a plane, or one was set. Until then the settings' clip (RenderSettings::clip:
  // a card's, a --settings file's, the window's panel) decides the cut.
  bool owns_plane() const { return owns_; }
  // Starts from a plane (the settings' or a caller's); `own`: it overrides the settings' from the first frame.
  void set_plane(const CutPlane& plane, bool own) {
    plane_ = plane;
    owns_ = own;
  }
  bool following() const { return following_; }

  // The plane through `hand`'s tip, normal along its aim direction, in voxel
  // coordinates of the volume placed at `t` (normal of unit length).
  CutPlane plane_of_hand(const HandInput& hand, const VolumeTransform& t) const;

 private:
  bool trigger_held(Hand h, const HandInput& hand) const;

  VolumePlacement placement_;
  CutPlaneSettings s_;
  CutPlane plane_;
  std::array<bool, 2> held_{false, false};  // each trigger, active or not (a press is an edge)
  bool following_ = false;                   // pressed while active and not yet released
  bool owns_ = false;
};

}  // namespace vxr::xr
