// The desktop viewer's annotation tools and cards over one AnnotationStore:
// the ToolPalette (engine/annotate/tools.h) fed from mouse clicks or a UI
// script, class colours, cards of the current scene, and a revision the
// marker overlay and the panel follow. No ImGui or Vulkan here.
#pragma once

#include <array>
#include <string>
#include <vector>

#include "annotate/tools.h"
#include "scene/render_settings.h"

namespace vxr::xr {

class ViewerTools {
 public:
  explicit ViewerTools(annotate::AnnotationStore& store) : store_(store), palette_(store) {}

  annotate::AnnotationStore& store() { return store_; }
  const annotate::ToolPalette& palette() const { return palette_; }
  // Bumped on every stored edit.
  uint64_t revision() const { return revision_; }

  // A count marker of `cls` (colour by the order classes first appear).
  Status count(const annotate::Vec3& voxel, const std::string& cls, uint32_t timepoint);
  // A whole measurement from a to b.
  Status measure(const annotate::Vec3& a, const annotate::Vec3& b, uint32_t timepoint);
  // Interactive measuring: the first click starts, the cursor previews, the second click stores.
  Status measure_click(const annotate::Vec3& voxel, uint32_t timepoint);
  Status measure_hover(const annotate::Vec3& voxel, uint32_t timepoint);
  void cancel();  // drops a measurement being drawn
  // Any tool's event (the headset's controllers, xr/hand_tools.h): the
  // palette switches to `tool` first; count markers get `cls`.
  Status apply_event(annotate::Tool tool, const std::string& cls, const annotate::ToolEvent& event);
  // Switches the palette's tool, dropping what the old one was drawing.
  void select_tool(annotate::Tool tool) { palette_.select_tool(tool); }
  // A card of `scene` with an optional PNG snapshot; returns its id.
  Result<annotate::Id> card(const Scene& scene, const std::string& title, const std::string& note,
                            std::vector<uint8_t> snapshot_png);

  std::array<double, 4> class_colour(const std::string& cls);

 private:
  Status apply(annotate::Tool tool, annotate::ToolAction action, const annotate::Vec3& at, uint32_t timepoint);

  annotate::AnnotationStore& store_;
  annotate::ToolPalette palette_;
  std::vector<std::string> classes_;  // in order of first use
  uint64_t revision_ = 0;
};

}  // namespace vxr::xr
