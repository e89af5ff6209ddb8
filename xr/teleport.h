// Teleport, the paper's "tele-transport" half of the transformation tool,
// device-independent like GrabInteraction: hold a hand's thumbstick click
// (stick_click) to aim, release to jump. While held, the target is the point
// where that hand's aim ray enters the volume's box (none when the ray
// misses). On release over a target the volume moves, translation only, so
// the target comes to a comfortable spot: `distance_m` in front of the head,
// at eye height, along the head's horizontal forward. The user never moves;
// the volume comes to them, which keeps the reference space (and the
// floor) where the runtime put it.
//
// One hand aims at a time (the first to press); losing its tracking cancels
// the aim rather than jump to a stale ray.
#pragma once

#include <array>
#include <optional>

#include "render/camera.h"
#include "xr/pose.h"
#include "xr/volume_transform.h"

namespace vxr::xr {

struct TeleportSettings {
  double distance_m = 0.4;  // how far in front of the head the target lands
};

struct TeleportFrame {
  bool moved = false;  // released on a target: the volume moved (a haptic click)
  Hand hand = kRight;  // ... aimed by this hand
};

class Teleport {
 public:
  explicit Teleport(const VolumePlacement& placement, TeleportSettings s = {}) : placement_(placement), s_(s) {}

  // `head`: the user's head in the reference space this frame.
  TeleportFrame update(const InputState& input, const Pose& head, VolumeTransform& t);

  // While aiming at the volume: the target in the volume frame (the renderer's
  // world units, as annotations are placed), to be drawn as a marker.
  const std::optional<glm::dvec3>& target() const { return target_; }
  bool aiming() const { return aiming_.has_value(); }

  // Where the aim ray of `hand` enters the volume's box at `t` (volume frame);
  // its origin when it starts inside; none when it misses.
  std::optional<glm::dvec3> aim_point(const HandInput& hand, const VolumeTransform& t) const;

 private:
  VolumePlacement placement_;
  TeleportSettings s_;
  std::array<bool, 2> held_{false, false};
  std::optional<Hand> aiming_;
  std::optional<glm::dvec3> target_;
};

// `distance_m` in front of `head` at its height, along its forward direction
// projected onto the horizontal (-z when the head looks straight up or down).
glm::dvec3 comfortable_spot(const Pose& head, double distance_m);

}  // namespace vxr::xr
