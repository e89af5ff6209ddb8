// The desktop viewer's annotation tools and cards over one AnnotationStore:
// the ToolPalette (engine/annotate/tools.h) fed from mouse clicks or a UI
// script, class colours, cards of the current scene, and a revision the
// marker overlay and the panel follow. No ImGui or Vulkan here.
//
// The mouse's tools: count, measure, trace and track act on a click, ROI on a
// drag (press, move, release); finish (a button, Enter) ends the traced
// branch or the track. The annotation list (annotation_list) and remove()
// are the panel's view of the whole store.
#pragma once

#include <array>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "annotate/tools.h"
#include "scene/render_settings.h"

namespace vxr::xr {

// What the tools panel shows of the tool being used.
struct ToolStatus {
  annotate::Id skeleton = 0;     // trace: the skeleton traced into (0: none yet)
  size_t nodes = 0;              // ... its node count
  double traced_length = 0.0;    // ... the sum of its edges, in the store's unit
  int64_t current_node = annotate::kNoParent;  // the next node hangs below it
  annotate::Id track = 0;        // track: the active track (0: none)
  size_t track_markers = 0;      // ... its markers
  uint32_t first_timepoint = 0, last_timepoint = 0;  // ... the timepoints it spans
  std::optional<annotate::Roi> roi;  // roi: being dragged, or the last stored
  size_t roi_markers = 0;            // ... markers inside at the current timepoint
};

// One row of the annotation list.
enum class AnnotationKind { kMarker, kMeasurement, kSkeleton, kTrack, kRoi };
struct AnnotationRow {
  AnnotationKind kind = AnnotationKind::kMarker;
  annotate::Id id = 0;
  std::string group;  // markers: their class; else empty
  std::string text;   // one line: what it is, with its length where it has one
};

// "marker", "measurement", "skeleton", "track", "roi" (and back).
const char* annotation_kind_name(AnnotationKind kind);
std::optional<AnnotationKind> annotation_kind_from_name(const std::string& name);

class ViewerTools {
 public:
  explicit ViewerTools(annotate::AnnotationStore& store);

  annotate::AnnotationStore& store() { return store_; }
  const annotate::ToolPalette& palette() const { return *palette_; }
  // Bumped on every stored edit.
  uint64_t revision() const { return revision_; }
  // Bumped on every event the tools take, stored or not (a pick, a move, finish): the live state may have changed.
  uint64_t events() const { return events_; }

  // A count marker of `cls` (colour by the order classes first appear).
  Status count(const annotate::Vec3& voxel, const std::string& cls, uint32_t timepoint);
  // A whole measurement from a to b.
  Status measure(const annotate::Vec3& a, const annotate::Vec3& b, uint32_t timepoint);
  // Interactive measuring: the first click starts, the cursor previews, the second click stores.
  Status measure_click(const annotate::Vec3& voxel, uint32_t timepoint);
  Status measure_hover(const annotate::Vec3& voxel, uint32_t timepoint);
  // Trace: a click within the pick radius of a node of the skeleton being
  // traced continues from that node; elsewhere it adds a node below the
  // current one (a new root after finish, a new skeleton the first time).
  Status trace_click(const annotate::Vec3& voxel, uint32_t timepoint);
  // Track: a marker of `cls` at `timepoint` joins the active track (a new track when none).
  Status track_click(const annotate::Vec3& voxel, const std::string& cls, uint32_t timepoint);
  // ROI: press at one corner, move previews, release stores the box.
  Status roi_drag(annotate::ToolAction action, const annotate::Vec3& voxel, uint32_t timepoint);
  // The trace tool: the next node starts a new root; the track tool: the next marker a new track.
  Status finish(uint32_t timepoint);
  void cancel();  // drops a measurement or box being drawn
  // Any tool's event (the headset's controllers, xr/hand_tools.h): the
  // palette switches to `tool` first; count markers get `cls`.
  Status apply_event(annotate::Tool tool, const std::string& cls, const annotate::ToolEvent& event);
  // Switches the palette's tool, dropping what the old one was drawing.
  void select_tool(annotate::Tool tool) {
    ++events_;
    palette_->select_tool(tool);
  }
  // A card of `scene` with an optional PNG snapshot; returns its id.
  Result<annotate::Id> card(const Scene& scene, const std::string& title, const std::string& note,
                            std::vector<uint8_t> snapshot_png);

  // The live state for the panel, read from the store.
  Result<ToolStatus> status(uint32_t timepoint) const;
  // Every stored marker (grouped by class), measurement, skeleton, track and ROI, in id order per kind.
  Result<std::vector<AnnotationRow>> annotation_list() const;
  // Deletes one of them (a track with its markers). A skeleton, track or box
  // the tools were working on is dropped from their live state too.
  Status remove(AnnotationKind kind, annotate::Id id);

  std::array<double, 4> class_colour(const std::string& cls);

 private:
  Status apply(annotate::Tool tool, annotate::ToolAction action, const annotate::Vec3& at, uint32_t timepoint);
  void restart_palette();  // a fresh palette on the same tool and class (its live ids are gone)

  annotate::AnnotationStore& store_;
  std::unique_ptr<annotate::ToolPalette> palette_;
  std::string cls_ = "default";       // the palette's class, kept across restart_palette
  std::vector<std::string> classes_;  // in order of first use
  uint64_t revision_ = 0;
  uint64_t events_ = 0;
};

}  // namespace vxr::xr
