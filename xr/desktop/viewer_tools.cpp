#include "xr/desktop/viewer_tools.h"

#include <algorithm>
#include <cstdio>
#include <iterator>

namespace vxr::xr {

ViewerTools::ViewerTools(annotate::AnnotationStore& store)
    : store_(store), palette_(std::make_unique<annotate::ToolPalette>(store)) {}

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
  ++events_;
  if (palette_->tool() != tool) palette_->select_tool(tool);
  return palette_->apply({action, at, timepoint});
}

Status ViewerTools::count(const annotate::Vec3& voxel, const std::string& cls, uint32_t timepoint) {
  cls_ = cls;
  palette_->set_class(cls, class_colour(cls));
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
  const bool drawing = palette_->tool() == annotate::Tool::kMeasure && palette_->live().measuring.has_value();
  VXR_RETURN_IF_ERROR(apply(annotate::Tool::kMeasure,
                            drawing ? annotate::ToolAction::kRelease : annotate::ToolAction::kPress, voxel, timepoint));
  if (drawing) ++revision_;
  return Status::ok();
}

Status ViewerTools::measure_hover(const annotate::Vec3& voxel, uint32_t timepoint) {
  if (palette_->tool() != annotate::Tool::kMeasure || !palette_->live().measuring) return Status::ok();
  ++events_;
  return palette_->apply({annotate::ToolAction::kMove, voxel, timepoint});
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
  if (tool == annotate::Tool::kCount || tool == annotate::Tool::kTrack) {
    cls_ = cls;
    palette_->set_class(cls, class_colour(cls));
  }
  VXR_RETURN_IF_ERROR(apply(tool, event.action, event.cursor, event.timepoint));
  if (stores(tool, event.action)) ++revision_;
  return Status::ok();
}

void ViewerTools::cancel() {
  // Selecting a tool drops what the old one was drawing; nothing stored is lost.
  ++events_;
  const annotate::Tool current = palette_->tool();
  palette_->select_tool(current == annotate::Tool::kCount ? annotate::Tool::kMeasure : annotate::Tool::kCount);
  palette_->select_tool(current);
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

Status ViewerTools::trace_click(const annotate::Vec3& voxel, uint32_t timepoint) {
  using annotate::Tool, annotate::ToolAction;
  ++events_;
  if (palette_->tool() != Tool::kTrace) palette_->select_tool(Tool::kTrace);
  // On a node of the skeleton being traced: continue from it (a pick stores nothing).
  if (palette_->live().skeleton != 0 && palette_->apply({ToolAction::kPick, voxel, timepoint})) return Status::ok();
  VXR_RETURN_IF_ERROR(apply(Tool::kTrace, ToolAction::kPress, voxel, timepoint));
  ++revision_;
  return Status::ok();
}

Status ViewerTools::track_click(const annotate::Vec3& voxel, const std::string& cls, uint32_t timepoint) {
  return apply_event(annotate::Tool::kTrack, cls, {annotate::ToolAction::kPress, voxel, timepoint});
}

Status ViewerTools::roi_drag(annotate::ToolAction action, const annotate::Vec3& voxel, uint32_t timepoint) {
  return apply_event(annotate::Tool::kRoi, cls_, {action, voxel, timepoint});
}

Status ViewerTools::finish(uint32_t timepoint) {
  const annotate::Tool tool = palette_->tool();
  if (tool != annotate::Tool::kTrace && tool != annotate::Tool::kTrack) return Status::ok();
  ++events_;
  return palette_->apply({annotate::ToolAction::kFinish, {0, 0, 0}, timepoint});
}

Result<ToolStatus> ViewerTools::status(uint32_t timepoint) const {
  const annotate::ToolLiveState& live = palette_->live();
  ToolStatus st;
  st.current_node = live.current_node;
  st.roi = live.roi;
  st.roi_markers = live.roi_markers;
  if (live.roi && live.roi->id != 0) {  // a stored box: count again, the markers may have changed since
    VXR_ASSIGN_OR_RETURN(annotate::RoiContents inside, store_.query(*live.roi, timepoint));
    st.roi_markers = inside.markers.size();
  }
  if (live.skeleton != 0) {
    VXR_ASSIGN_OR_RETURN(annotate::Skeleton sk, store_.skeleton(live.skeleton));
    st.skeleton = live.skeleton;
    st.nodes = sk.size();
    for (const auto& [id, n] : sk.nodes())
      if (const annotate::SkeletonNode* p = sk.find(n.parent)) st.traced_length += store_.voxel_space().distance(n.pos, p->pos);
  }
  if (live.track != 0) {
    VXR_ASSIGN_OR_RETURN(annotate::Track t, store_.track(live.track));
    st.track = live.track;
    st.track_markers = t.markers.size();
    for (size_t i = 0; i < t.markers.size(); ++i) {
      VXR_ASSIGN_OR_RETURN(annotate::Marker m, store_.marker(t.markers[i]));
      st.first_timepoint = i == 0 ? m.timepoint : std::min(st.first_timepoint, m.timepoint);
      st.last_timepoint = i == 0 ? m.timepoint : std::max(st.last_timepoint, m.timepoint);
    }
  }
  return st;
}

namespace {

std::string point_text(const annotate::Vec3& p) {
  char buf[80];
  std::snprintf(buf, sizeof buf, "(%.1f, %.1f, %.1f)", p[0], p[1], p[2]);
  return buf;
}

std::string length_text(double length, const std::string& unit) {
  char buf[48];
  std::snprintf(buf, sizeof buf, "%.3f ", length);
  return buf + unit;
}

}  // namespace

const char* annotation_kind_name(AnnotationKind kind) {
  switch (kind) {
    case AnnotationKind::kMarker: return "marker";
    case AnnotationKind::kMeasurement: return "measurement";
    case AnnotationKind::kSkeleton: return "skeleton";
    case AnnotationKind::kTrack: return "track";
    case AnnotationKind::kRoi: return "roi";
  }
  return "?";
}

std::optional<AnnotationKind> annotation_kind_from_name(const std::string& name) {
  for (AnnotationKind k : {AnnotationKind::kMarker, AnnotationKind::kMeasurement, AnnotationKind::kSkeleton,
                           AnnotationKind::kTrack, AnnotationKind::kRoi})
    if (name == annotation_kind_name(k)) return k;
  return std::nullopt;
}

Result<std::vector<AnnotationRow>> ViewerTools::annotation_list() const {
  const std::string& unit = store_.voxel_space().unit;
  std::vector<AnnotationRow> rows;
  VXR_ASSIGN_OR_RETURN(std::vector<annotate::Marker> markers, store_.markers());
  std::stable_sort(markers.begin(), markers.end(),
                   [](const annotate::Marker& a, const annotate::Marker& b) { return a.cls < b.cls; });
  for (const annotate::Marker& m : markers)
    rows.push_back({AnnotationKind::kMarker, m.id, m.cls,
                    "marker " + std::to_string(m.id) + " " + point_text(m.pos) + " t" + std::to_string(m.timepoint)});
  VXR_ASSIGN_OR_RETURN(std::vector<annotate::Measurement> measurements, store_.measurements());
  for (const annotate::Measurement& m : measurements)
    rows.push_back({AnnotationKind::kMeasurement, m.id, "",
                    "measurement " + std::to_string(m.id) + ": " + length_text(store_.length(m), unit)});
  VXR_ASSIGN_OR_RETURN(std::vector<annotate::SkeletonInfo> skeletons, store_.skeletons());
  for (const annotate::SkeletonInfo& info : skeletons) {
    VXR_ASSIGN_OR_RETURN(annotate::Skeleton sk, store_.skeleton(info.id));
    double length = 0.0;
    for (const auto& [id, n] : sk.nodes())
      if (const annotate::SkeletonNode* p = sk.find(n.parent)) length += store_.voxel_space().distance(n.pos, p->pos);
    rows.push_back({AnnotationKind::kSkeleton, info.id, "",
                    "skeleton " + std::to_string(info.id) + " '" + info.name + "': " + std::to_string(sk.size()) +
                        " nodes, " + length_text(length, unit)});
  }
  VXR_ASSIGN_OR_RETURN(std::vector<annotate::Track> tracks, store_.tracks());
  for (const annotate::Track& t : tracks)
    rows.push_back({AnnotationKind::kTrack, t.id, "",
                    "track " + std::to_string(t.id) + ": " + std::to_string(t.markers.size()) + " timepoint(s)"});
  VXR_ASSIGN_OR_RETURN(std::vector<annotate::Roi> rois, store_.rois());
  for (const annotate::Roi& r : rois)
    rows.push_back({AnnotationKind::kRoi, r.id, "",
                    "box " + std::to_string(r.id) + " " + point_text(r.min) + " - " + point_text(r.max)});
  return rows;
}

Status ViewerTools::remove(AnnotationKind kind, annotate::Id id) {
  const annotate::ToolLiveState& live = palette_->live();
  bool live_gone = false;  // the palette's live state names what is removed
  switch (kind) {
    case AnnotationKind::kMarker: VXR_RETURN_IF_ERROR(store_.delete_marker(id)); break;
    case AnnotationKind::kMeasurement: VXR_RETURN_IF_ERROR(store_.delete_measurement(id)); break;
    case AnnotationKind::kSkeleton:
      VXR_RETURN_IF_ERROR(store_.delete_skeleton(id));
      live_gone = live.skeleton == id;
      break;
    case AnnotationKind::kTrack:
      VXR_RETURN_IF_ERROR(store_.delete_track(id));
      live_gone = live.track == id;
      break;
    case AnnotationKind::kRoi:
      VXR_RETURN_IF_ERROR(store_.delete_roi(id));
      live_gone = live.roi && live.roi->id == id;
      break;
  }
  if (live_gone) restart_palette();
  ++revision_;
  return Status::ok();
}

void ViewerTools::restart_palette() {
  ++events_;
  const annotate::Tool tool = palette_->tool();
  palette_ = std::make_unique<annotate::ToolPalette>(store_);
  palette_->select_tool(tool);
  palette_->set_class(cls_, class_colour(cls_));
}

}  // namespace vxr::xr
