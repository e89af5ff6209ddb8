#include "xr/cut_plane_tool.h"

namespace vxr::xr {

CutPlane CutPlaneTool::plane_of_hand(const HandInput& hand, const VolumeTransform& t) const {
  const glm::dvec3 tip = hand.aim.apply(glm::dvec3(0.0, 0.0, -s_.tip_m));  // aim looks along -z
  const glm::dvec3 aim_dir = hand.aim.orientation * glm::dvec3(0.0, 0.0, -1.0);
  // Into the volume frame: the transform is a similarity, so a direction only turns.
  const glm::dvec3 normal_volume = glm::conjugate(t.orientation) * aim_dir;
  // World -> voxel divides each axis by the voxel size; a plane's normal
  // transforms with the inverse transpose, i.e. multiplies by it.
  const glm::dvec3 vs(placement_.voxel_size[0], placement_.voxel_size[1], placement_.voxel_size[2]);
  const glm::dvec3 normal = glm::normalize(normal_volume * vs);
  const glm::dvec3 through = placement_.world_to_voxel_point(t.to_volume(tip));
  return {true, normal, -glm::dot(normal, through)};
}

bool CutPlaneTool::trigger_held(Hand h, const HandInput& hand) const {
  return hand.tracked && (held_[h] ? hand.trigger > s_.release : hand.trigger >= s_.press);
}

CutPlaneFrame CutPlaneTool::update(const InputState& input, const VolumeTransform& t, bool active) {
  CutPlaneFrame out;
  if (!active) {
    held_ = {false, false};  // a trigger held into the cut tool must be pressed again
    return out;
  }
  const HandInput& right = input.hands[kRight];
  const bool was_right = held_[kRight];
  held_[kRight] = trigger_held(kRight, right);
  // While held the plane follows the hand; lost tracking freezes it where it was last seen.
  if (held_[kRight]) plane_ = plane_of_hand(right, t);
  else if (was_right && right.tracked) out.placed = true;

  const bool was_left = held_[kLeft];
  held_[kLeft] = trigger_held(kLeft, input.hands[kLeft]);
  if (held_[kLeft] && !was_left && plane_.enabled && !held_[kRight]) {
    plane_ = CutPlane{};
    out.cleared = true;
  }
  return out;
}

}  // namespace vxr::xr
