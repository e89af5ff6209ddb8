#include "xr/desktop/viewer_tools.h"

#include <iterator>

namespace vxr::xr {

std::array<double, 4> ViewerTools::class_colour(const std::string& cls) {
  static const std::array<double, 4> table[] = {
      {1, 1, 0, 1}, {0, 1, 1, 1}, {1, 0, 1, 1}, {0, 1, 0, 1}, {1, 0.5, 0, 1}, {0.5, 0.5, 1, 1}};
  size_t index = 0;
  while (index < classes_.size() && classes_[index] != cls) ++index;
  if (index == classes_.size()) classes_.push_back(cls);
  return table[index % std::size(table)];
}

Status ViewerTools::apply(annotate::Tool tool, annotate::ToolAction action, const annotate::Vec3& at,
                          uint32_t timepoint) {
  if (palette_.tool() != tool) palette_.select_tool(tool);
  return palette_.apply({action, at, timepoint});
}

Status ViewerTools::count(const annotate::Vec3& voxel, const std::string& cls, uint32_t timepoint) {
  palette_.set_class(cls, class_colour(cls));
  VXR_RETURN_IF_ERROR(apply(annotate::Tool::kCount, annotate::ToolAction::kPress, voxel, timepoint));
  ++revision_;
  return Status::ok();
}

Status ViewerTools::measure(const annotate::Vec3& a, const annotate::Vec3& b, uint32_t timepoint) {
  cancel();
  VXR_RETURN_IF_ERROR(apply(annotate::Tool::kMeasure, annotate::ToolAction::kPress, a, timepoint));
  VXR_RETURN_IF_ERROR(apply(annotate::Tool::kMeasure, annotate::ToolAction::kMove, b, timepoint));
  VXR_RETURN_IF_ERROR(apply(annotate::Tool::kMeasure, annotate::ToolAction::kRelease, b, timepoint));
  ++revision_;
  return Status::ok();
}

Status ViewerTools::measure_click(const annotate::Vec3& voxel, uint32_t timepoint) {
  const bool drawing = palette_.tool() == annotate::Tool::kMeasure && palette_.live().measuring.has_value();
  VXR_RETURN_IF_ERROR(apply(annotate::Tool::kMeasure,
                            drawing ? annotate::ToolAction::kRelease : annotate::ToolAction::kPress, voxel, timepoint));
  if (drawing) ++revision_;
  return Status::ok();
}

Status ViewerTools::measure_hover(const annotate::Vec3& voxel, uint32_t timepoint) {
  if (palette_.tool() != annotate::Tool::kMeasure || !palette_.live().measuring) return Status::ok();
  return palette_.apply({annotate::ToolAction::kMove, voxel, timepoint});
}

namespace {

// Whether `action` of `tool` writes the store (when it succeeds).
bool stores(annotate::Tool tool, annotate::ToolAction action) {
  using annotate::Tool, annotate::ToolAction;
  if (action == ToolAction::kRemove) return true;
  if (tool == Tool::kMeasure || tool == Tool::kRoi) return action == ToolAction::kRelease;
  return action == ToolAction::kPress;
}

}  // namespace

Status ViewerTools::apply_event(annotate::Tool tool, const std::string& cls, const annotate::ToolEvent& event) {
  if (tool == annotate::Tool::kCount || tool == annotate::Tool::kTrack) palette_.set_class(cls, class_colour(cls));
  VXR_RETURN_IF_ERROR(apply(tool, event.action, event.cursor, event.timepoint));
  if (stores(tool, event.action)) ++revision_;
  return Status::ok();
}

void ViewerTools::cancel() {
  // Selecting a tool drops what the old one was drawing; nothing stored is lost.
  const annotate::Tool current = palette_.tool();
  palette_.select_tool(current == annotate::Tool::kCount ? annotate::Tool::kMeasure : annotate::Tool::kCount);
  palette_.select_tool(current);
}

Result<annotate::Id> ViewerTools::card(const Scene& scene, const std::string& title, const std::string& note,
                                       std::vector<uint8_t> snapshot_png) {
  annotate::Card c;
  c.title = title;
  c.note = note;
  c.scene_json = scene_to_json(scene);
  c.snapshot_png = std::move(snapshot_png);
  VXR_ASSIGN_OR_RETURN(annotate::Id id, store_.add_card(std::move(c)));
  ++revision_;
  return id;
}

}  // namespace vxr::xr
