// Device-independent volume manipulation (the paper's transformation tool):
// one hand grabs and moves/rotates the volume rigidly; two hands pinch to
// scale it about their midpoint (and carry it with the midpoint). A
// thumbstick pushed forward on a hand that is not grabbing flies the user
// along that hand's aim ray (the volume moves the other way); not while the
// stick is pressed in, which aims a teleport (xr/teleport.h).
//
// Works on any InputState, whichever target or controller produced it. Each
// time the set of grabbing hands changes, the gesture re-anchors on the
// current transform, so switching from two hands to one never jumps.
#pragma once

#include <array>

#include "xr/pose.h"
#include "xr/volume_transform.h"

namespace vxr::xr {

struct GrabSettings {
  double press = 0.6;    // grab value that starts a grab
  double release = 0.4;  // ... and that ends it (hysteresis)
  double min_scale = 1e-9, max_scale = 1e9;  // metres per volume unit
  double fly_speed = 0.5;                    // metres per second at full thumbstick
  double deadzone = 0.2;
};

class GrabInteraction {
 public:
  explicit GrabInteraction(GrabSettings s = {}) : s_(s) {}

  // Updates `t` from this frame's input; `dt` (seconds since the last frame)
  // scales thumbstick flight. Returns the hands whose grab started this frame
  // (for a haptic click).
  std::array<bool, 2> update(const InputState& input, VolumeTransform& t, double dt = 0.0);

  bool grabbing(Hand h) const { return held_[h]; }

 private:
  void anchor(const InputState& input, const VolumeTransform& t);

  GrabSettings s_;
  std::array<bool, 2> held_{false, false};
  int active_count_ = 0;
  VolumeTransform start_;
  // One hand: the volume's pose relative to the grip at grab time.
  Pose hand_to_volume_;
  Hand one_hand_ = kLeft;
  // Two hands: distance and midpoint at anchor time.
  double start_distance_ = 0.0;
  glm::dvec3 start_mid_{0.0};
};

}  // namespace vxr::xr
