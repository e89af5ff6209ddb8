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
  std::array<bool, 2> pressed{false, false};
  for (Hand h : {kLeft, kRight}) {
    const bool was = held_[h];
    held_[h] = trigger_held(h, input.hands[h]);
    pressed[h] = held_[h] && !was;
  }
  if (!active) {
    following_ = false;  // the plane stays where it was
    return out;
  }
  const HandInput& right = input.hands[kRight];
  if (pressed[kRight]) following_ = true;
  if (following_ && !held_[kRight]) {
    following_ = false;
    out.placed = right.tracked;  // lost tracking freezes the plane where it was last seen, no click
  }
  if (following_) {
    plane_ = plane_of_hand(right, t);
    owns_ = true;
  }
  if (pressed[kLeft] && plane_.enabled && !following_) {
    plane_ = CutPlane{};
    out.cleared = true;
    owns_ = true;
  }
  return out;
}

}  // namespace vxr::xr
