#include "annotate/tools.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <limits>

namespace vxr::annotate {
namespace {

double dist(const Vec3& a, const Vec3& b) { return std::hypot(a[0] - b[0], a[1] - b[1], a[2] - b[2]); }

// Distance from p to the segment a-b (volume coordinates).
double dist_to_segment(const Vec3& p, const Vec3& a, const Vec3& b) {
  Vec3 ab{b[0] - a[0], b[1] - a[1], b[2] - a[2]};
  const double len2 = ab[0] * ab[0] + ab[1] * ab[1] + ab[2] * ab[2];
  double t = 0.0;
  if (len2 > 0.0) t = std::clamp(((p[0] - a[0]) * ab[0] + (p[1] - a[1]) * ab[1] + (p[2] - a[2]) * ab[2]) / len2, 0.0, 1.0);
  return dist(p, {a[0] + t * ab[0], a[1] + t * ab[1], a[2] + t * ab[2]});
}

Roi box_of(const Vec3& a, const Vec3& b) {
  Roi r;
  for (int i = 0; i < 3; ++i) {
    r.min[i] = std::min(a[i], b[i]);
    r.max[i] = std::max(a[i], b[i]);
  }
  return r;
}

std::string at_text(const Vec3& p) {
  char buf[96];
  std::snprintf(buf, sizeof buf, "(%.6g, %.6g, %.6g)", p[0], p[1], p[2]);
  return buf;
}

// The element of `items` nearest the cursor by `distance`, within `radius`.
template <typename T, typename F>
const T* nearest(const std::vector<T>& items, double radius, F distance) {
  const T* best = nullptr;
  double best_d = std::numeric_limits<double>::infinity();
  for (const T& it : items) {
    const double d = distance(it);
    if (d <= radius && d < best_d) {
      best = &it;
      best_d = d;
    }
  }
  return best;
}

Status nothing_near(const char* what, double radius) {
  char buf[128];
  std::snprintf(buf, sizeof buf, "no %s within %.6g voxels of the cursor", what, radius);
  return not_found(buf);
}

}  // namespace

std::optional<Tool> tool_from_name(const std::string& name) {
  for (Tool t : {Tool::kCount, Tool::kMeasure, Tool::kTrace, Tool::kTrack, Tool::kRoi})
    if (name == tool_name(t)) return t;
  return std::nullopt;
}

const char* tool_name(Tool tool) {
  switch (tool) {
    case Tool::kCount: return "count";
    case Tool::kMeasure: return "measure";
    case Tool::kTrace: return "trace";
    case Tool::kTrack: return "track";
    case Tool::kRoi: return "roi";
  }
  return "?";
}

std::optional<ToolAction> tool_action_from_name(const std::string& name) {
  static const std::pair<const char*, ToolAction> names[] = {
      {"press", ToolAction::kPress}, {"move", ToolAction::kMove},     {"release", ToolAction::kRelease},
      {"pick", ToolAction::kPick},   {"remove", ToolAction::kRemove}, {"finish", ToolAction::kFinish}};
  for (const auto& [n, a] : names)
    if (name == n) return a;
  return std::nullopt;
}

ToolPalette::ToolPalette(AnnotationStore& store, double pick_radius) : store_(store), pick_radius_(pick_radius) {}

void ToolPalette::select_tool(Tool tool) {
  tool_ = tool;
  live_.measuring.reset();
  live_.measuring_length = 0.0;
  roi_corner_.reset();
}

void ToolPalette::set_class(const std::string& cls, const std::array<double, 4>& color) {
  cls_ = cls;
  color_ = color;
}

Status ToolPalette::apply(const ToolEvent& e) {
  for (double c : e.cursor)
    if (!std::isfinite(c)) return invalid_argument("tool event: the cursor is not a finite point");
  const ToolLiveState before = live_;
  Status st = [&] {
    switch (tool_) {
      case Tool::kCount: return count(e);
      case Tool::kMeasure: return measure(e);
      case Tool::kTrace: return trace(e);
      case Tool::kTrack: return track(e);
      case Tool::kRoi: return roi(e);
    }
    return internal_error("unknown tool");
  }();
  if (st) st = refresh(e.timepoint);
  if (!st) live_ = before;
  return st;
}

Status ToolPalette::refresh(uint32_t timepoint) {
  VXR_ASSIGN_OR_RETURN(live_.counts, store_.counts(timepoint));
  live_.roi_markers = 0;
  if (live_.roi) {
    VXR_ASSIGN_OR_RETURN(RoiContents inside, store_.query(*live_.roi, timepoint));
    live_.roi_markers = inside.markers.size();
  }
  return Status::ok();
}

Marker ToolPalette::marker_at(const ToolEvent& e) const {
  Marker m;
  m.cls = cls_;
  m.color = color_;
  m.pos = e.cursor;
  m.timepoint = e.timepoint;
  return m;
}

Status ToolPalette::count(const ToolEvent& e) {
  if (e.action == ToolAction::kPress) {
    VXR_ASSIGN_OR_RETURN(Id id, store_.add_marker(marker_at(e)));
    live_.last_edit = "marker " + std::to_string(id) + " (" + cls_ + ") at " + at_text(e.cursor);
  } else if (e.action == ToolAction::kRemove) {
    VXR_ASSIGN_OR_RETURN(std::vector<Marker> all, store_.markers());
    std::erase_if(all, [&](const Marker& m) { return m.timepoint != e.timepoint; });
    const Marker* m = nearest(all, pick_radius_, [&](const Marker& x) { return dist(x.pos, e.cursor); });
    if (!m) return nothing_near("marker", pick_radius_);
    VXR_RETURN_IF_ERROR(store_.delete_marker(m->id));
    live_.last_edit = "removed marker " + std::to_string(m->id);
  }
  return Status::ok();
}

Status ToolPalette::measure(const ToolEvent& e) {
  switch (e.action) {
    case ToolAction::kPress:
      live_.measuring = Measurement{0, "", e.cursor, e.cursor, e.timepoint};
      live_.measuring_length = 0.0;
      break;
    case ToolAction::kMove:
    case ToolAction::kRelease: {
      if (!live_.measuring) break;
      live_.measuring->b = e.cursor;
      live_.measuring_length = store_.length(*live_.measuring);
      if (e.action == ToolAction::kMove) break;
      const Measurement m = *live_.measuring;
      live_.measuring.reset();
      if (live_.measuring_length == 0.0) {
        live_.last_edit = "measurement dropped: both ends at one point";
        break;
      }
      VXR_ASSIGN_OR_RETURN(Id id, store_.add_measurement(m));
      char buf[64];
      std::snprintf(buf, sizeof buf, "%.6g", live_.measuring_length);
      live_.last_edit = "measurement " + std::to_string(id) + ": " + buf + " " + store_.voxel_space().unit;
      break;
    }
    case ToolAction::kRemove: {
      VXR_ASSIGN_OR_RETURN(std::vector<Measurement> all, store_.measurements());
      const Measurement* m =
          nearest(all, pick_radius_, [&](const Measurement& x) { return dist_to_segment(e.cursor, x.a, x.b); });
      if (!m) return nothing_near("measurement", pick_radius_);
      VXR_RETURN_IF_ERROR(store_.delete_measurement(m->id));
      live_.last_edit = "removed measurement " + std::to_string(m->id);
      break;
    }
    default: break;
  }
  return Status::ok();
}

Status ToolPalette::trace(const ToolEvent& e) {
  switch (e.action) {
    case ToolAction::kPress: {
      if (live_.skeleton == 0) {
        VXR_ASSIGN_OR_RETURN(live_.skeleton, store_.add_skeleton(Skeleton(0, "traced")));
        live_.current_node = kNoParent;
      }
      SkeletonNode n;
      n.pos = e.cursor;
      n.radius = node_radius_;
      n.parent = live_.current_node;
      VXR_ASSIGN_OR_RETURN(int64_t id, store_.add_node(live_.skeleton, n));
      live_.last_edit = "node " + std::to_string(id) + " of skeleton " + std::to_string(live_.skeleton) +
                        (n.parent == kNoParent ? " (a root)" : " below node " + std::to_string(n.parent));
      live_.current_node = id;
      break;
    }
    case ToolAction::kPick: {
      if (live_.skeleton == 0) return nothing_near("traced node", pick_radius_);
      VXR_ASSIGN_OR_RETURN(Skeleton sk, store_.skeleton(live_.skeleton));
      std::vector<SkeletonNode> nodes;
      for (const auto& [id, n] : sk.nodes()) nodes.push_back(n);
      const SkeletonNode* n = nearest(nodes, pick_radius_, [&](const SkeletonNode& x) { return dist(x.pos, e.cursor); });
      if (!n) return nothing_near("traced node", pick_radius_);
      live_.current_node = n->id;
      live_.last_edit = "tracing from node " + std::to_string(n->id);
      break;
    }
    case ToolAction::kRemove: {
      if (live_.current_node == kNoParent) return invalid_argument("no current node to remove");
      VXR_ASSIGN_OR_RETURN(Skeleton sk, store_.skeleton(live_.skeleton));
      const SkeletonNode* n = sk.find(live_.current_node);
      const int64_t parent = n ? n->parent : kNoParent;
      VXR_RETURN_IF_ERROR(store_.delete_node(live_.skeleton, live_.current_node));
      live_.last_edit = "removed node " + std::to_string(live_.current_node);
      live_.current_node = parent;
      break;
    }
    case ToolAction::kFinish:
      live_.current_node = kNoParent;
      live_.last_edit = "the next node starts a new branch root";
      break;
    default: break;
  }
  return Status::ok();
}

Status ToolPalette::track(const ToolEvent& e) {
  switch (e.action) {
    case ToolAction::kPress: {
      VXR_ASSIGN_OR_RETURN(Id id, store_.add_marker(marker_at(e)));
      Status st = Status::ok();
      if (live_.track == 0) {
        Result<Id> t = store_.add_track("tracked", {id});
        if (t) live_.track = *t;
        else st = t.status();
      } else {
        st = store_.add_to_track(live_.track, id);
      }
      if (!st) {
        (void)store_.delete_marker(id);  // the marker belongs to no track: take it back
        return st;
      }
      live_.last_edit = "marker " + std::to_string(id) + " at timepoint " + std::to_string(e.timepoint) +
                        " in track " + std::to_string(live_.track);
      break;
    }
    case ToolAction::kRemove: {
      if (live_.track == 0) return invalid_argument("no active track");
      VXR_ASSIGN_OR_RETURN(Track t, store_.track(live_.track));
      std::vector<Marker> ms;
      for (Id id : t.markers) {
        VXR_ASSIGN_OR_RETURN(Marker m, store_.marker(id));
        if (m.timepoint == e.timepoint) ms.push_back(m);
      }
      const Marker* m = nearest(ms, pick_radius_, [&](const Marker& x) { return dist(x.pos, e.cursor); });
      if (!m) return nothing_near("marker of the track at this timepoint", pick_radius_);
      VXR_RETURN_IF_ERROR(store_.delete_marker(m->id));
      live_.last_edit = "removed marker " + std::to_string(m->id) + " from track " + std::to_string(live_.track);
      break;
    }
    case ToolAction::kFinish:
      live_.track = 0;
      live_.last_edit = "the next marker starts a new track";
      break;
    default: break;
  }
  return Status::ok();
}

Status ToolPalette::roi(const ToolEvent& e) {
  switch (e.action) {
    case ToolAction::kPress:
      roi_corner_ = e.cursor;
      live_.roi = box_of(e.cursor, e.cursor);
      break;
    case ToolAction::kMove:
    case ToolAction::kRelease: {
      if (!roi_corner_) break;
      const Vec3 corner = *roi_corner_;
      live_.roi = box_of(corner, e.cursor);
      if (e.action == ToolAction::kMove) break;
      roi_corner_.reset();
      if (corner == e.cursor) {
        live_.roi.reset();
        live_.last_edit = "box dropped: both corners at one point";
        break;
      }
      VXR_ASSIGN_OR_RETURN(live_.roi->id, store_.add_roi(*live_.roi));
      live_.last_edit = "box " + std::to_string(live_.roi->id) + " from " + at_text(live_.roi->min) + " to " +
                        at_text(live_.roi->max);
      break;
    }
    case ToolAction::kRemove: {
      VXR_ASSIGN_OR_RETURN(std::vector<Roi> all, store_.rois());
      // The smallest stored box holding the cursor.
      const Roi* hit = nullptr;
      double hit_volume = std::numeric_limits<double>::infinity();
      for (const Roi& r : all) {
        const double v = (r.max[0] - r.min[0]) * (r.max[1] - r.min[1]) * (r.max[2] - r.min[2]);
        if (r.contains(e.cursor) && v < hit_volume) {
          hit = &r;
          hit_volume = v;
        }
      }
      if (!hit) return not_found("no stored box holds the cursor");
      VXR_RETURN_IF_ERROR(store_.delete_roi(hit->id));
      if (live_.roi && live_.roi->id == hit->id) live_.roi.reset();
      live_.last_edit = "removed box " + std::to_string(hit->id);
      break;
    }
    default: break;
  }
  return Status::ok();
}

}  // namespace vxr::annotate
