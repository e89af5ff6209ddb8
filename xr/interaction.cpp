#include "xr/interaction.h"

#include <algorithm>
#include <cmath>

namespace vxr::xr {

std::array<bool, 2> GrabInteraction::update(const InputState& input, VolumeTransform& t, double dt) {
  std::array<bool, 2> started{false, false};
  bool changed = false;
  for (int h = 0; h < 2; ++h) {
    const HandInput& hand = input.hands[h];
    const bool was = held_[h];
    bool now = hand.tracked && (was ? hand.grab > s_.release : hand.grab >= s_.press);
    if (now != was) {
      changed = true;
      started[h] = now;
    }
    held_[h] = now;
  }
  if (changed) anchor(input, t);

  if (active_count_ == 1) {
    const Pose grip = input.hands[one_hand_].grip;
    const Pose volume = grip * hand_to_volume_;
    t.position = volume.position;
    t.orientation = glm::normalize(volume.orientation);
  } else if (active_count_ == 2) {
    const glm::dvec3 a = input.hands[kLeft].grip.position, b = input.hands[kRight].grip.position;
    const double d = glm::length(b - a);
    const glm::dvec3 mid = 0.5 * (a + b);
    if (start_distance_ > 1e-6 && d > 1e-6) {
      const double k = std::clamp(start_.scale * d / start_distance_, s_.min_scale, s_.max_scale) / start_.scale;
      // x' = mid + k (x - start_mid): the point under the midpoint stays under it.
      t.scale = start_.scale * k;
      t.position = mid + k * (start_.position - start_mid_);
      t.orientation = start_.orientation;
    }
  }
  if (active_count_ == 0 && dt > 0.0) {
    for (int h = 0; h < 2; ++h) {
      const HandInput& hand = input.hands[h];
      // A pressed stick aims a teleport (xr/teleport.h); a Vive trackpad's click reads as a push too.
      if (!hand.tracked || hand.stick_click || std::abs(hand.thumbstick.y) < s_.deadzone) continue;
      const glm::dvec3 forward = hand.aim.orientation * glm::dvec3(0, 0, -1);
      t.position -= forward * (s_.fly_speed * hand.thumbstick.y * dt);
    }
  }
  return started;
}

void GrabInteraction::anchor(const InputState& input, const VolumeTransform& t) {
  start_ = t;
  active_count_ = int(held_[kLeft]) + int(held_[kRight]);
  if (active_count_ == 1) {
    one_hand_ = held_[kLeft] ? kLeft : kRight;
    const Pose volume{t.orientation, t.position};
    hand_to_volume_ = input.hands[one_hand_].grip.inverse() * volume;
  } else if (active_count_ == 2) {
    const glm::dvec3 a = input.hands[kLeft].grip.position, b = input.hands[kRight].grip.position;
    start_distance_ = glm::length(b - a);
    start_mid_ = 0.5 * (a + b);
  }
}

}  // namespace vxr::xr
