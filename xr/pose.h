// Rigid poses, fields of view and per-hand input: the vocabulary every
// FrameTarget speaks. Double precision on the CPU (../shared/design/numerics.md);
// OpenXR's float poses are widened on the way in.
#pragma once

#include <array>
#include <glm/glm.hpp>
#include <glm/gtc/quaternion.hpp>

namespace vxr::xr {

// Maps points of a child frame into its parent: p_parent = orientation * p + position.
struct Pose {
  glm::dquat orientation{1.0, 0.0, 0.0, 0.0};  // glm order: w, x, y, z
  glm::dvec3 position{0.0};

  glm::dvec3 apply(const glm::dvec3& p) const { return orientation * p + position; }
  Pose inverse() const {
    const glm::dquat inv = glm::conjugate(orientation);
    return {inv, -(inv * position)};
  }
  // (a * b) applies b first, then a.
  friend Pose operator*(const Pose& a, const Pose& b) {
    return {a.orientation * b.orientation, a.orientation * b.position + a.position};
  }
};

// Half-angles of a view's frustum in radians, OpenXR's sign convention
// (left and down negative for a centred view).
struct Fov {
  double left = -0.7, right = 0.7, up = 0.7, down = -0.7;
};

// One controller as the interaction code sees it, whatever the device.
struct HandInput {
  bool tracked = false;  // grip pose valid this frame
  Pose grip;             // where the hand holds the controller
  Pose aim;              // pointing ray: origin and -z forward
  double grab = 0.0;     // squeeze (or select on simple controllers), 0..1
  double trigger = 0.0;  // 0..1
  glm::dvec2 thumbstick{0.0};
  bool menu = false;
  bool stick_click = false;  // the thumbstick pressed in (Vive: the left trackpad): teleport
  bool primary = false;      // right hand: A (Vive: trackpad click, WMR: trackpad click): pick a node
  bool secondary = false;    // right hand: B (Vive and WMR: the right menu button): finish the branch
};

enum Hand { kLeft = 0, kRight = 1 };

struct InputState {
  std::array<HandInput, 2> hands;
};

}  // namespace vxr::xr
