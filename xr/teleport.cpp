#include "xr/teleport.h"

#include <algorithm>
#include <cmath>
#include <limits>

namespace vxr::xr {
namespace {

// The first t >= 0 at which o + t d is inside [lo, hi] (slab test), none when the ray misses.
std::optional<double> ray_box_entry(const glm::dvec3& o, const glm::dvec3& d, const glm::dvec3& lo,
                                    const glm::dvec3& hi) {
  double t0 = 0.0, t1 = std::numeric_limits<double>::infinity();
  for (int a = 0; a < 3; ++a) {
    if (d[a] == 0.0) {
      if (o[a] < lo[a] || o[a] > hi[a]) return std::nullopt;
      continue;
    }
    const double ta = (lo[a] - o[a]) / d[a], tb = (hi[a] - o[a]) / d[a];
    t0 = std::max(t0, std::min(ta, tb));
    t1 = std::min(t1, std::max(ta, tb));
  }
  if (t0 > t1) return std::nullopt;
  return t0;
}

}  // namespace

glm::dvec3 comfortable_spot(const Pose& head, double distance_m) {
  const glm::dvec3 forward = head.orientation * glm::dvec3(0, 0, -1);
  glm::dvec3 level(forward.x, 0.0, forward.z);
  const double n = glm::length(level);
  level = n > 1e-6 ? level / n : glm::dvec3(0, 0, -1);
  return head.position + distance_m * level;
}

std::optional<glm::dvec3> Teleport::aim_point(const HandInput& hand, const VolumeTransform& t) const {
  // The ray in the volume frame: t.to_volume is affine, so map the origin and a second point.
  const glm::dvec3 o = t.to_volume(hand.aim.position);
  const glm::dvec3 d = t.to_volume(hand.aim.apply(glm::dvec3(0, 0, -1))) - o;
  const glm::dvec3 half = 0.5 * placement_.extent();
  const auto entry = ray_box_entry(o, d, placement_.origin - half, placement_.origin + half);
  if (!entry) return std::nullopt;
  return o + *entry * d;
}

TeleportFrame Teleport::update(const InputState& input, const Pose& head, VolumeTransform& t) {
  TeleportFrame out;
  std::array<bool, 2> released{false, false};
  for (Hand h : {kLeft, kRight}) {
    const HandInput& hand = input.hands[h];
    const bool now = hand.tracked && hand.stick_click;
    if (now && !held_[h] && !aiming_) aiming_ = h;
    released[h] = held_[h] && !now;
    held_[h] = now;
  }
  if (!aiming_) return out;
  const Hand h = *aiming_;
  if (!input.hands[h].tracked) {  // tracking lost: cancel, never jump to a stale ray
    aiming_.reset();
    target_.reset();
    return out;
  }
  if (!released[h]) {
    target_ = aim_point(input.hands[h], t);
    return out;
  }
  if (target_) {
    t.position += comfortable_spot(head, s_.distance_m) - t.to_reference(*target_);
    out.moved = true;
    out.hand = h;
  }
  aiming_.reset();
  target_.reset();
  return out;
}

}  // namespace vxr::xr
