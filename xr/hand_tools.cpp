#include "xr/hand_tools.h"


#include "annotate/annotation_store.h"

namespace vxr::xr {
namespace {

using annotate::Tool;
using annotate::ToolAction;

bool drags(Tool tool) { return tool == Tool::kMeasure || tool == Tool::kRoi; }

annotate::Vec3 vec3(const glm::dvec3& v) { return {v.x, v.y, v.z}; }

const glm::vec4 kPreview{0.8f, 0.8f, 0.8f, 1.0f};   // what is being drawn
const glm::vec4 kStored{1.0f, 1.0f, 1.0f, 1.0f};    // stored measurements
const glm::vec4 kCursor{0.3f, 1.0f, 0.4f, 1.0f};
const glm::vec4 kCurrentNode{1.0f, 0.5f, 0.1f, 1.0f};  // where the next traced node hangs

}  // namespace

Tool next_tool(Tool tool) {
  switch (tool) {
    case Tool::kCount: return Tool::kMeasure;
    case Tool::kMeasure: return Tool::kTrace;
    case Tool::kTrace: return Tool::kTrack;
    case Tool::kTrack: return Tool::kRoi;
    case Tool::kRoi: return Tool::kCount;
  }
  return Tool::kCount;
}

HandTools::HandTools(ViewerTools& tools, const VolumePlacement& placement, HandToolSettings settings)
    : tools_(tools), placement_(placement), s_(std::move(settings)), tool_(s_.tool) {
  tools_.select_tool(tool_);
}

glm::dvec3 HandTools::tip(const HandInput& hand) const {
  return hand.aim.apply(glm::dvec3(0.0, 0.0, -s_.tip_m));  // aim looks along -z
}

glm::dvec3 HandTools::tip_voxel(const HandInput& hand, const VolumeTransform& t) const {
  // The transform's volume frame is the camera's world space (camera_for_view).
  return placement_.world_to_voxel_point(t.to_volume(tip(hand)));
}

void HandTools::cycle() {
  if (cutting_) {
    cutting_ = false;
    tool_ = Tool::kCount;
  } else if (tool_ == Tool::kRoi) {
    cutting_ = true;
  } else {
    tool_ = next_tool(tool_);
  }
  tools_.select_tool(tool_);  // drops what the old tool was drawing
  last_move_.reset();
}

HandToolFrame HandTools::update(const InputState& input, const VolumeTransform& t, uint32_t timepoint) {
  HandToolFrame out;
  const bool menu = input.hands[kLeft].menu || input.hands[kRight].menu;
  if (menu && !menu_down_) {
    cycle();
    out.tool_changed = true;
  }
  menu_down_ = menu;
  if (cutting_) {
    // The cut plane owns the triggers and buttons; a press held into the next tool must be pressed again.
    held_ = {true, true};
    primary_down_ = secondary_down_ = true;
    follow_current_node();
    return out;
  }

  auto send = [&](Hand h, ToolAction action, const annotate::Vec3& at) {
    const uint64_t before = tools_.revision();
    const Status s = tools_.apply_event(tool_, s_.count_class, {action, at, timepoint});
    if (!s) {
      out.error = s.message();
    } else if (tools_.revision() != before) {
      out.stored = true;
      out.hand = h;
    } else if (action == ToolAction::kPick || action == ToolAction::kFinish) {
      out.picked = true;
      out.hand = h;
    }
  };
  // The right hand's buttons, on the press only (a held button does not repeat).
  const HandInput& right = input.hands[kRight];
  const bool pick = right.tracked && right.primary, finish = right.tracked && right.secondary;
  if (pick && !primary_down_) send(kRight, ToolAction::kPick, vec3(tip_voxel(right, t)));
  if (finish && !secondary_down_) send(kRight, ToolAction::kFinish, vec3(tip_voxel(right, t)));
  primary_down_ = pick;
  secondary_down_ = finish;
  for (Hand h : {kRight, kLeft}) {
    const HandInput& hand = input.hands[h];
    const bool was = held_[h];
    const bool now = hand.tracked && (was ? hand.trigger > s_.release : hand.trigger >= s_.press);
    held_[h] = now;
    if (!hand.tracked) {
      // Lost tracking mid-drag: drop the drawing rather than end it at a stale pose.
      if (was && h == kRight && drags(tool_)) tools_.select_tool(tool_);
      continue;
    }
    const annotate::Vec3 at = vec3(tip_voxel(hand, t));
    if (h == kLeft) {
      if (now && !was) send(h, ToolAction::kRemove, at);
      continue;
    }
    if (now && !was) {
      send(h, ToolAction::kPress, at);
      last_move_ = at;
    } else if (now && drags(tool_) && last_move_ != at) {
      send(h, ToolAction::kMove, at);
      last_move_ = at;
    } else if (!now && was && drags(tool_)) {
      send(h, ToolAction::kRelease, at);
      last_move_.reset();
    }
  }
  follow_current_node();
  return out;
}

void HandTools::follow_current_node() {
  const annotate::ToolLiveState& live = tools_.palette().live();
  const int64_t current = tool_ == Tool::kTrace ? live.current_node : annotate::kNoParent;
  if (current == shown_node_) return;
  shown_node_ = current;
  shown_node_pos_.reset();
  if (current == annotate::kNoParent) return;
  auto sk = tools_.store().skeleton(live.skeleton);
  if (!sk) return;  // not drawn; the store's own error shows with the next edit
  if (const annotate::SkeletonNode* n = sk->find(current)) shown_node_pos_ = n->pos;
}

std::string HandTools::report() const {
  const annotate::ToolLiveState& live = tools_.palette().live();
  if (cutting_) return "tool cut";
  std::string r = std::string("tool ") + annotate::tool_name(tool_);
  if (tool_ == Tool::kCount || tool_ == Tool::kTrack) {
    const auto it = live.counts.find(s_.count_class);
    r += " (" + s_.count_class + "): " + std::to_string(it == live.counts.end() ? 0 : it->second) + " counted";
  }
  if (!live.last_edit.empty()) r += "; last: " + live.last_edit;
  return r;
}

glm::dvec3 HandTools::world(const annotate::Vec3& v) const {
  const glm::dvec3 dims(placement_.dims[0], placement_.dims[1], placement_.dims[2]);
  const glm::dvec3 size(placement_.voxel_size[0], placement_.voxel_size[1], placement_.voxel_size[2]);
  return placement_.origin + (glm::dvec3(v[0], v[1], v[2]) - 0.5 * dims) * size;
}

double HandTools::marker_radius() const { return 0.015 * glm::length(placement_.extent()); }  // as the store's markers

Result<AnnotationScene> HandTools::stored_scene(uint32_t timepoint) const {
  annotate::AnnotationStore& store = tools_.store();
  VXR_ASSIGN_OR_RETURN(AnnotationScene scene, annotation_scene_of_store(store, placement_, timepoint));
  if (tool_ == Tool::kMeasure) {
    VXR_ASSIGN_OR_RETURN(std::vector<annotate::Measurement> all, store.measurements());
    const double r = 0.15 * marker_radius();
    for (const annotate::Measurement& m : all)
      if (m.timepoint == timepoint) scene.cones.push_back({world(m.a), world(m.b), r, r, kStored});
  }
  return scene;
}

void HandTools::add_live(const InputState& input, const VolumeTransform& t, AnnotationScene& scene) const {
  const annotate::ToolLiveState& live = tools_.palette().live();
  const double r = marker_radius();
  if (tool_ == Tool::kMeasure && live.measuring) {
    scene.cones.push_back({world(live.measuring->a), world(live.measuring->b), 0.15 * r, 0.15 * r, kPreview});
    scene.spheres.push_back({world(live.measuring->a), 0.3 * r, kPreview});
  }
  if (tool_ == Tool::kRoi && live.roi && held_[kRight]) {
    // The box being dragged: its twelve edges.
    const annotate::Vec3 lo = live.roi->min, hi = live.roi->max;
    auto corner = [&](int i) { return world({i & 1 ? hi[0] : lo[0], i & 2 ? hi[1] : lo[1], i & 4 ? hi[2] : lo[2]}); };
    for (int i = 0; i < 8; ++i)
      for (int axis : {1, 2, 4})
        if (!(i & axis)) scene.cones.push_back({corner(i), corner(i | axis), 0.1 * r, 0.1 * r, kPreview});
  }
  if (shown_node_pos_) scene.spheres.push_back({world(*shown_node_pos_), 0.5 * r, kCurrentNode});
  const HandInput& right = input.hands[kRight];
  if (!right.tracked) return;
  const glm::dvec3 v = tip_voxel(right, t);
  for (int i = 0; i < 3; ++i)
    if (!(v[i] >= 0.0 && v[i] <= double(placement_.dims[i]))) return;  // outside the box: no cursor
  scene.spheres.push_back({world(vec3(v)), 0.3 * r, kCursor});
}

}  // namespace vxr::xr
