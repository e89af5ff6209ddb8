// The paper's analysis tools as device-independent logic: counting,
// measuring, skeleton tracing, feature tracking across timepoints and ROI
// boxes. A front end (OpenXR actions, mouse and keyboard, a script: `vxr
// annotate play`) turns its input into ToolEvents at a 3D cursor in volume
// coordinates (voxels of the finest level); the ToolPalette applies them to
// the AnnotationStore, where every edit is synced before apply() returns, and
// keeps the live state a renderer or a panel shows: counts per class, the
// measurement being drawn and its length, the node being traced from, the
// active track, the box being dragged and what lies inside it.
//
//   tool     press                   move              release           pick / remove / finish
//   count    a marker of the class   -                 -                 - / nearest marker / -
//   measure  first end point         preview length    stores it         - / nearest measurement / -
//   trace    node below the current  -                 -                 nearest node becomes current /
//            (a new root if none)                                        current node (parent becomes current) /
//                                                                        next press starts a new root
//   track    marker at the event's   -                 -                 - / nearest marker of the track /
//            timepoint, appended                                         next press starts a new track
//   roi      first corner            preview box       stores the box    - / nearest box (by centre) / -
#pragma once

#include <map>
#include <optional>
#include <string>

#include "annotate/annotation_store.h"

namespace vxr::annotate {

enum class Tool { kCount, kMeasure, kTrace, kTrack, kRoi };
enum class ToolAction { kPress, kMove, kRelease, kPick, kRemove, kFinish };

// "count", "measure", "trace", "track", "roi" (and back); nullopt for another name.
std::optional<Tool> tool_from_name(const std::string& name);
const char* tool_name(Tool tool);
std::optional<ToolAction> tool_action_from_name(const std::string& name);

struct ToolEvent {
  ToolAction action = ToolAction::kPress;
  Vec3 cursor{0, 0, 0};  // volume coordinates
  uint32_t timepoint = 0;
};

struct ToolLiveState {
  std::map<std::string, size_t> counts;  // markers per class at the last event's timepoint
  std::optional<Measurement> measuring;  // being drawn (a fixed, b follows the cursor)
  double measuring_length = 0.0;         // in the store's unit
  Id skeleton = 0;                       // traced into (0: none yet)
  int64_t current_node = kNoParent;      // the next traced node hangs below it
  Id track = 0;                          // the active track (0: none)
  std::optional<Roi> roi;                // being dragged, or the last stored
  size_t roi_markers = 0;                // markers inside `roi` at the last event's timepoint
  std::string last_edit;                 // one line: what the last event changed
};

class ToolPalette {
 public:
  // `pick_radius`: how near (in voxels) the cursor must be to pick or remove.
  explicit ToolPalette(AnnotationStore& store, double pick_radius = 5.0);

  Tool tool() const { return tool_; }
  // Switching tools drops what the old tool was drawing (nothing stored is lost).
  void select_tool(Tool tool);
  // The class (and colour) new count markers get.
  void set_class(const std::string& cls, const std::array<double, 4>& color);
  void set_node_radius(double radius) { node_radius_ = radius; }

  // Applies one event; an edit the store refuses leaves the store and the
  // live state as they were and returns why.
  Status apply(const ToolEvent& event);
  const ToolLiveState& live() const { return live_; }

 private:
  Status count(const ToolEvent& e);
  Status measure(const ToolEvent& e);
  Status trace(const ToolEvent& e);
  Status track(const ToolEvent& e);
  Status roi(const ToolEvent& e);
  Status refresh(uint32_t timepoint);
  Marker marker_at(const ToolEvent& e) const;  // of the current class, at the cursor and timepoint

  AnnotationStore& store_;
  double pick_radius_;
  Tool tool_ = Tool::kCount;
  std::string cls_ = "default";
  std::array<double, 4> color_{1, 1, 0, 1};
  double node_radius_ = 1.0;
  std::optional<Vec3> roi_corner_;
  ToolLiveState live_;
};

}  // namespace vxr::annotate
