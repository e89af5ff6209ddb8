// The analysis tools (engine/annotate/tools.h) driven by the hands, whatever
// device produced the InputState (OpenXR actions, a pose script): the
// dominant (right) hand's trigger acts at the controller tip, a point a few
// centimetres along its aim ray, mapped into voxel coordinates through the
// volume transform. Press above `press`, release below `release`
// (hysteresis, as GrabSettings); while held, moves preview a measurement or
// box. Either hand's menu button cycles count -> measure -> trace -> track ->
// roi -> cut. "cut" is the cut plane (xr/cut_plane_tool.h): it edits no store,
// so it is no annotate::Tool; while it is on, the triggers, A and B leave the
// store alone and the session's CutPlaneTool takes them. The left hand's trigger removes the nearest (ToolAction::kRemove at
// its tip). The right hand's primary button (A) picks at its tip (trace: the
// nearest node becomes the one the next node hangs below) and its secondary
// button (B) finishes (trace: the next node starts a new root; track: the
// next marker starts a new track). Grabbing stays on the squeeze
// (xr/interaction.h), so the trigger hand never also grabs.
//
// Edits go through ViewerTools (the desktop viewer's palette and revision),
// so the holder of the store redraws markers when revision() changes.
#pragma once

#include <array>
#include <optional>
#include <string>

#include "render/annotation_renderer.h"
#include "render/camera.h"
#include "xr/desktop/viewer_tools.h"
#include "xr/pose.h"
#include "xr/volume_transform.h"

namespace vxr::xr {

struct HandToolSettings {
  double press = 0.6;    // trigger value that presses
  double release = 0.4;  // ... and that releases
  double tip_m = 0.05;   // the tip: this far along the aim ray from its origin
  annotate::Tool tool = annotate::Tool::kCount;  // the starting tool
  std::string count_class = "cell";              // the class count (and track) markers get
};

// What one frame's input did.
struct HandToolFrame {
  bool stored = false;        // an edit reached the store (a haptic click)
  Hand hand = kRight;         // ... made by this hand's trigger
  bool tool_changed = false;  // the menu button cycled the tool
  bool picked = false;        // a pick or finish was applied (the live state changed, nothing stored)
  std::string error;          // an event the tools refused, one line (empty: none)
};

class HandTools {
 public:
  HandTools(ViewerTools& tools, const VolumePlacement& placement, HandToolSettings settings = {});

  HandToolFrame update(const InputState& input, const VolumeTransform& t, uint32_t timepoint);

  // The annotation tool; while cutting(), the one the cycle left (roi).
  annotate::Tool tool() const { return tool_; }
  // The cycle is on the cut plane: the triggers belong to the CutPlaneTool.
  bool cutting() const { return cutting_; }
  bool pressed(Hand hand) const { return held_[hand]; }
  ViewerTools& tools() { return tools_; }

  // The hand's tip in the reference space, and in voxel coordinates of the volume at `t`.
  glm::dvec3 tip(const HandInput& hand) const;
  glm::dvec3 tip_voxel(const HandInput& hand, const VolumeTransform& t) const;

  // One line: the tool, the live count of its class, the last edit (a
  // stored measurement's length among them).
  std::string report() const;

  // What the store holds, drawn as `vxr render` draws it, and with the
  // measure tool the stored measurements too (thin cones).
  Result<AnnotationScene> stored_scene(uint32_t timepoint) const;
  // Adds what is live: the measurement or box being drawn, the node the next
  // traced node hangs below (after a pick: where the branch starts), and a
  // small ball at the right hand's tip while it is inside the volume's box.
  void add_live(const InputState& input, const VolumeTransform& t, AnnotationScene& scene) const;

 private:
  glm::dvec3 world(const annotate::Vec3& voxel) const;  // the renderer's world units
  double marker_radius() const;

  ViewerTools& tools_;
  VolumePlacement placement_;
  HandToolSettings s_;
  annotate::Tool tool_;
  bool cutting_ = false;
  std::array<bool, 2> held_{false, false};
  bool menu_down_ = false;
  bool primary_down_ = false, secondary_down_ = false;  // the right hand's, last frame
  std::optional<annotate::Vec3> last_move_;  // no repeated move while the hand rests
  // The trace tool's current node and where it is (read once when it changes, not per frame).
  int64_t shown_node_ = annotate::kNoParent;
  std::optional<annotate::Vec3> shown_node_pos_;
  void follow_current_node();
  void cycle();  // the menu's next step: the tools in next_tool's order, then cut, then count
};

// The annotation tool after `tool` (roi: count; the menu puts cut between them).
annotate::Tool next_tool(annotate::Tool tool);

}  // namespace vxr::xr
