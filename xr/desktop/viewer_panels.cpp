#include "xr/desktop/viewer_panels.h"

#include <imgui.h>

#include <algorithm>
#include <cfloat>
#include <cmath>
#include <cstdio>

#include "render/colormap.h"

namespace vxr::xr {
namespace {

constexpr const char* kModelLabels[] = {"emission-absorption", "emission", "MIP", "MinIP", "average", "isosurface"};
constexpr OpticalModel kModelOrder[] = {OpticalModel::kEmissionAbsorption, OpticalModel::kEmission, OpticalModel::kMip,
                                        OpticalModel::kMinIp, OpticalModel::kAverage, OpticalModel::kIsosurface};

// Pixels within which a click or right click takes an opacity point.
constexpr float kHandleRadius = 6.0f;

// The histogram of the channel's data across the whole canvas (bins over the data range), grey.
void histogram_bars(ImDrawList* draw, ImVec2 p0, ImVec2 size, const std::vector<float>& bins) {
  const float top = *std::max_element(bins.begin(), bins.end());
  if (!(top > 0)) return;
  const float w = size.x / float(bins.size());
  for (size_t i = 0; i < bins.size(); ++i) {
    const float h = size.y * bins[i] / top;
    draw->AddRectFilled(ImVec2(p0.x + w * float(i), p0.y + size.y - h), ImVec2(p0.x + w * float(i + 1), p0.y + size.y),
                        IM_COL32(90, 90, 90, 255));
  }
}

}  // namespace

void draw_opacity_editor(ViewerState& state, size_t c, const std::vector<float>* histogram) {
  const ImVec2 p0 = ImGui::GetCursorScreenPos();
  const ImVec2 size(std::max(64.0f, ImGui::GetContentRegionAvail().x), 72.0f);
  ImGui::InvisibleButton("##opacity", size, ImGuiButtonFlags_MouseButtonLeft | ImGuiButtonFlags_MouseButtonRight);
  ImDrawList* draw = ImGui::GetWindowDrawList();
  draw->AddRectFilled(p0, ImVec2(p0.x + size.x, p0.y + size.y), IM_COL32(25, 25, 25, 255));
  if (histogram && !histogram->empty()) histogram_bars(draw, p0, size, *histogram);
  const std::vector<OpacityPoint> points = state.opacity_curve(c);
  auto at = [&](double x, double a) { return ImVec2(p0.x + float(x) * size.x, p0.y + (1.0f - float(a)) * size.y); };
  std::vector<ImVec2> line{at(0.0, points.front().opacity)};
  for (const OpacityPoint& p : points) line.push_back(at(p.x, p.opacity));
  line.push_back(at(1.0, points.back().opacity));
  draw->AddPolyline(line.data(), int(line.size()), IM_COL32(255, 200, 0, 255), 0, 2.0f);
  const ImVec2 mouse = ImGui::GetIO().MousePos;
  int hovered = -1;
  for (size_t i = 0; i < points.size(); ++i) {
    const ImVec2 h = at(points[i].x, points[i].opacity);
    if (std::hypot(mouse.x - h.x, mouse.y - h.y) <= kHandleRadius) hovered = int(i);
    draw->AddCircleFilled(h, 4.0f, IM_COL32(255, 255, 255, 255));
  }
  const double x = std::clamp(double((mouse.x - p0.x) / size.x), 0.0, 1.0);
  const double a = std::clamp(double(1.0f - (mouse.y - p0.y) / size.y), 0.0, 1.0);
  // The point being dragged lives in ImGui's storage: it survives frames, one per channel.
  ImGuiStorage* storage = ImGui::GetStateStorage();
  const ImGuiID key = ImGui::GetID("##opacity-dragged");
  int dragged = storage->GetInt(key, -1);
  if (ImGui::IsItemActivated() && ImGui::IsMouseClicked(ImGuiMouseButton_Left)) {
    if (hovered >= 0) {
      dragged = hovered;
    } else if (auto added = state.add_opacity_point(c, x, a)) {
      dragged = int(*added);
    }
  }
  if (ImGui::IsItemActive() && dragged >= 0 && ImGui::IsMouseDown(ImGuiMouseButton_Left))
    (void)state.move_opacity_point(c, size_t(dragged), x, a);
  if (!ImGui::IsItemActive()) dragged = -1;
  if (hovered >= 0 && ImGui::IsItemHovered() && ImGui::IsMouseClicked(ImGuiMouseButton_Right))
    (void)state.remove_opacity_point(c, size_t(hovered));
  storage->SetInt(key, dragged);
  if (ImGui::SmallButton("ramp")) (void)state.set_opacity_points(c, {});
  ImGui::SameLine();
  ImGui::TextDisabled("opacity: drag, click adds, right click removes");
}

namespace {

void channel_panel(ViewerState& state, const PanelInputs& in) {
  const std::vector<std::string> maps = colormap_names();
  const auto range = state.data_range();
  for (size_t c = 0; c < state.channel_count(); ++c) {
    const ChannelSettings& ch = state.render().channels[c];
    ImGui::PushID(static_cast<int>(c));
    bool visible = ch.enabled;
    if (ImGui::Checkbox(("channel " + std::to_string(c)).c_str(), &visible)) (void)state.set_channel_visible(c, visible);
    if (ImGui::BeginCombo("colour map", ch.colormap.c_str())) {
      for (const std::string& name : maps)
        if (ImGui::Selectable(name.c_str(), name == ch.colormap)) (void)state.set_colormap(c, name);
      ImGui::EndCombo();
    }
    if (c < in.histograms.size() && !in.histograms[c].empty())
      ImGui::PlotHistogram("##histogram", in.histograms[c].data(), static_cast<int>(in.histograms[c].size()), 0,
                           nullptr, 0.0f, FLT_MAX, ImVec2(0, 48));
    float lo = static_cast<float>(ch.window_lo), hi = static_cast<float>(ch.window_hi);
    // A range drag; set_window refuses an empty window, so the old one stays.
    if (ImGui::DragFloatRange2("window", &lo, &hi, static_cast<float>((range[1] - range[0]) / 500.0),
                               static_cast<float>(range[0]), static_cast<float>(range[1])))
      (void)state.set_window(c, lo, hi);
    float gamma = static_cast<float>(ch.gamma);
    if (ImGui::SliderFloat("gamma", &gamma, 0.1f, 5.0f, "%.2f", ImGuiSliderFlags_Logarithmic))
      (void)state.set_gamma(c, gamma);
    draw_opacity_editor(state, c, c < in.histograms.size() ? &in.histograms[c] : nullptr);
    ImGui::PopID();
    ImGui::Separator();
  }
}

// Which way a cut's normal points when it lies along an axis: 0..2 = +x +y +z, 3..5 = -x -y -z; -1: oblique.
int cut_axis_choice(const ClipSettings& c) {
  for (int a = 0; a < 3; ++a)
    if (std::abs(c.cut_normal[a]) == 1.0) return c.cut_normal[a] > 0 ? a : a + 3;
  return -1;
}

}  // namespace

void draw_clip_controls(ViewerState& state) {
  const ClipSettings& c = state.render().clip;
  bool cut = c.cut;
  if (ImGui::Checkbox("cut plane", &cut)) state.set_cut_enabled(cut);
  static const char* const kSides[] = {"keep +x", "keep +y", "keep +z", "keep -x", "keep -y", "keep -z", "oblique"};
  const int axis = cut_axis_choice(c);
  // Along an axis the slider is the plane's coordinate on it: offset -p keeps f >= p, offset p keeps f <= p.
  float position = axis < 0 ? 0.5f : float(axis < 3 ? -c.cut_offset : c.cut_offset);
  int choice = axis < 0 ? 6 : axis;
  if (ImGui::Combo("side", &choice, kSides, axis < 0 ? 7 : 6) && choice < 6)
    (void)state.set_cut_axis(choice % 3, choice < 3, std::clamp(position, 0.0f, 1.0f));
  if (axis >= 0) {
    if (ImGui::SliderFloat("position", &position, 0.0f, 1.0f, "%.3f")) (void)state.set_cut_axis(axis % 3, axis < 3, position);
  } else {
    float n[3] = {float(c.cut_normal[0]), float(c.cut_normal[1]), float(c.cut_normal[2])};
    float offset = float(c.cut_offset);
    const bool normal_edited = ImGui::InputFloat3("normal", n, "%.3f", ImGuiInputTextFlags_EnterReturnsTrue);
    const bool offset_edited = ImGui::SliderFloat("offset", &offset, -1.8f, 1.8f, "%.3f");
    if (normal_edited || offset_edited) (void)state.set_cut_plane({n[0], n[1], n[2]}, offset);
  }
  bool roi = c.roi;
  if (ImGui::Checkbox("clip box", &roi)) state.set_roi_enabled(roi);
  static const char* const kAxes[] = {"x range", "y range", "z range"};
  for (int a = 0; a < 3; ++a) {
    float lo = float(c.roi_lo[a]), hi = float(c.roi_hi[a]);
    if (ImGui::DragFloatRange2(kAxes[a], &lo, &hi, 0.002f, 0.0f, 1.0f, "%.3f")) {
      std::array<double, 3> new_lo = c.roi_lo, new_hi = c.roi_hi;
      new_lo[a] = lo;
      new_hi[a] = hi;
      (void)state.set_roi(new_lo, new_hi);  // refused (lo >= hi): the box stays
    }
  }
}

namespace {

void clip_panel(ViewerState& state) {
  if (ImGui::CollapsingHeader("clipping")) draw_clip_controls(state);  // closed at first: the panel stays short
}

void render_panel(ViewerState& state) {
  int model = 0;
  for (int i = 0; i < int(std::size(kModelOrder)); ++i)
    if (kModelOrder[i] == state.render().model) model = i;
  if (ImGui::Combo("model", &model, kModelLabels, int(std::size(kModelLabels)))) state.set_model(kModelOrder[model]);
  float step = static_cast<float>(state.render().step_voxels);
  if (ImGui::SliderFloat("step (voxels)", &step, 1.0f / 64, 8.0f, "%.3f", ImGuiSliderFlags_Logarithmic))
    (void)state.set_step(step);
  float density = static_cast<float>(state.render().density);
  if (ImGui::SliderFloat("density", &density, 0.001f, 10.0f, "%.3f", ImGuiSliderFlags_Logarithmic))
    (void)state.set_density(density);
  if (state.render().model == OpticalModel::kIsosurface) {  // the surface's value, over the data's range
    const auto range = state.data_range();
    float iso = static_cast<float>(state.render().iso_value);
    if (ImGui::SliderFloat("iso value", &iso, static_cast<float>(range[0]), static_cast<float>(range[1]), "%.4g"))
      (void)state.set_iso_value(iso);
  }
  clip_panel(state);
  if (state.timepoints() > 1) {
    int t = static_cast<int>(state.scene().timepoint);
    if (ImGui::SliderInt("time", &t, 0, static_cast<int>(state.timepoints()) - 1))
      (void)state.set_timepoint(static_cast<uint32_t>(t));
    const PlaybackClock& clock = state.playback();
    if (ImGui::Button(clock.playing() ? "pause" : "play")) clock.playing() ? state.pause() : state.play();
    ImGui::SameLine();
    if (ImGui::ArrowButton("##back", ImGuiDir_Left)) state.step_time(-1);
    ImGui::SameLine();
    if (ImGui::ArrowButton("##on", ImGuiDir_Right)) state.step_time(1);
    ImGui::SameLine();
    bool loop = clock.loop();
    if (ImGui::Checkbox("loop", &loop)) state.set_loop(loop);
    float speed = static_cast<float>(clock.speed());
    if (ImGui::SliderFloat("speed", &speed, 1.0f / 16, 16.0f, "%.3gx", ImGuiSliderFlags_Logarithmic))
      (void)state.set_speed(speed);
    const PlaybackCounters& c = clock.counters();
    ImGui::TextDisabled("%.3g timepoints/s: %llu shown, %llu dropped, %llu waits for data",
                        clock.fps() * clock.speed(), static_cast<unsigned long long>(c.shown),
                        static_cast<unsigned long long>(c.dropped), static_cast<unsigned long long>(c.stalls));
  }
}

void read_store(ViewerTools& tools, ToolPanel& panel, uint32_t timepoint) {
  if (panel.read_revision == tools.revision() && panel.read_timepoint == timepoint &&
      panel.read_events == tools.events())
    return;
  panel.read_revision = tools.revision();
  panel.read_timepoint = timepoint;
  panel.read_events = tools.events();
  annotate::AnnotationStore& store = tools.store();
  auto counts = store.counts();
  auto measurements = store.measurements();
  auto cards = store.cards();
  auto status = tools.status(timepoint);
  auto rows = tools.annotation_list();
  for (const Status& s : {counts.status(), measurements.status(), cards.status(), status.status(), rows.status()})
    if (!s) {
      panel.message = store.path() + ": " + s.message();
      return;
    }
  panel.counts = *counts;
  panel.lengths.clear();
  for (const annotate::Measurement& m : *measurements)
    panel.lengths.emplace_back(m.label.empty() ? std::string("#").append(std::to_string(m.id)) : m.label,
                               store.length(m));
  panel.cards = *cards;
  panel.status = *status;
  panel.rows = *rows;
}

void tool_choice(ViewerTools& tools, ToolPanel& panel) {
  static const char* const kLabels[] = {"navigate", "count", "measure", "trace", "track", "roi"};
  int mode = static_cast<int>(panel.mode);
  for (int i = 0; i < int(std::size(kLabels)); ++i) {
    if (i % 3 != 0) ImGui::SameLine();
    ImGui::RadioButton(kLabels[i], &mode, i);
  }
  if (mode != static_cast<int>(panel.mode)) {
    tools.cancel();
    panel.mode = static_cast<ToolPanel::Mode>(mode);
  }
}

// What the chosen tool is doing: the measurement or box being drawn, the trace, the track.
void live_tool(ViewerTools& tools, ToolPanel& panel) {
  const std::string& unit = tools.store().voxel_space().unit;
  const ToolStatus& st = panel.status;
  const annotate::ToolLiveState& live = tools.palette().live();
  switch (panel.mode) {
    case ToolPanel::Mode::kNavigate: return;
    case ToolPanel::Mode::kCount:
    case ToolPanel::Mode::kTrack: ImGui::InputText("class", panel.cls, sizeof panel.cls); break;
    default: break;
  }
  ImGui::TextDisabled(panel.mode == ToolPanel::Mode::kRoi ? "drag a box over the volume (through it along the view)"
                                                          : "click the volume (on the plane through the orbit centre)");
  if (panel.mode == ToolPanel::Mode::kMeasure && live.measuring)
    ImGui::Text("measuring: %.3f %s", live.measuring_length, unit.c_str());
  if (panel.mode == ToolPanel::Mode::kTrace) {
    if (st.skeleton == 0)
      ImGui::TextUnformatted("no skeleton traced yet");
    else
      ImGui::Text("skeleton %llu: %zu node(s), traced length %.3f %s", static_cast<unsigned long long>(st.skeleton),
                  st.nodes, st.traced_length, unit.c_str());
    if (st.current_node != annotate::kNoParent)
      ImGui::Text("next node below node %lld", static_cast<long long>(st.current_node));
    else if (st.skeleton != 0)
      ImGui::TextUnformatted("next node: a new root");
  }
  if (panel.mode == ToolPanel::Mode::kTrack) {
    if (st.track == 0)
      ImGui::TextUnformatted("no active track: the next click starts one");
    else
      ImGui::Text("track %llu: %zu marker(s), timepoints %u..%u (%u long)", static_cast<unsigned long long>(st.track),
                  st.track_markers, st.first_timepoint, st.last_timepoint, st.last_timepoint - st.first_timepoint + 1);
  }
  if (panel.mode == ToolPanel::Mode::kRoi && st.roi) {
    const annotate::Roi& r = *st.roi;
    const std::string id = r.id ? std::string(" ").append(std::to_string(r.id)) : std::string();
    ImGui::Text("box%s (%.1f, %.1f, %.1f) - (%.1f, %.1f, %.1f)", id.c_str(), r.min[0], r.min[1], r.min[2], r.max[0],
                r.max[1], r.max[2]);
    ImGui::Text("%zu marker(s) inside at this timepoint", st.roi_markers);
  }
  if (panel.mode == ToolPanel::Mode::kTrace || panel.mode == ToolPanel::Mode::kTrack) {
    if (ImGui::Button("finish (Enter)")) panel.finish = true;
  }
}

// Every stored annotation, markers under their class, each with remove.
void annotation_list(ToolPanel& panel) {
  if (!ImGui::CollapsingHeader("annotations")) return;
  std::string open_group;
  bool group_open = true;
  for (const AnnotationRow& row : panel.rows) {
    if (row.kind == AnnotationKind::kMarker && row.group != open_group) {
      if (!open_group.empty() && group_open) ImGui::TreePop();
      open_group = row.group;
      const auto n = panel.counts.find(row.group);
      group_open = ImGui::TreeNode(row.group.c_str(), "%s: %zu marker(s)", row.group.c_str(),
                                   n == panel.counts.end() ? size_t(0) : n->second);
    }
    if (row.kind != AnnotationKind::kMarker && !open_group.empty()) {
      if (group_open) ImGui::TreePop();
      open_group.clear();
      group_open = true;
    }
    if (row.kind == AnnotationKind::kMarker && !group_open) continue;
    ImGui::PushID(static_cast<int>(row.kind) * 1000003 + static_cast<int>(row.id));
    if (ImGui::SmallButton("remove")) panel.remove = std::pair{row.kind, row.id};
    ImGui::SameLine();
    ImGui::TextUnformatted(row.text.c_str());
    ImGui::PopID();
  }
  if (!open_group.empty() && group_open) ImGui::TreePop();
}

}  // namespace

void draw_tools_panel(ViewerTools& tools, ToolPanel& panel, uint32_t timepoint) {
  read_store(tools, panel, timepoint);
  panel.save_card = false;
  panel.restore.reset();
  panel.finish = false;
  panel.remove.reset();
  const ImVec2 size = ImGui::GetIO().DisplaySize;
  ImGui::SetNextWindowPos(ImVec2(size.x - 10, 10), ImGuiCond_FirstUseEver, ImVec2(1, 0));
  ImGui::SetNextWindowSize(ImVec2(320, 0), ImGuiCond_FirstUseEver);
  ImGui::SetNextWindowCollapsed(true, ImGuiCond_FirstUseEver);  // a title bar until the user opens it
  if (ImGui::Begin("Tools and cards")) {
    tool_choice(tools, panel);
    live_tool(tools, panel);
    for (const auto& [cls, n] : panel.counts) ImGui::BulletText("%s: %zu marker(s)", cls.c_str(), n);
    for (const auto& [label, length] : panel.lengths)
      ImGui::BulletText("measurement %s: %.3f %s", label.c_str(), length, tools.store().voxel_space().unit.c_str());
    annotation_list(panel);
    ImGui::Separator();
    ImGui::InputText("title", panel.card_title, sizeof panel.card_title);
    ImGui::InputTextMultiline("note", panel.card_note, sizeof panel.card_note, ImVec2(0, 48));
    if (ImGui::Button("save card")) panel.save_card = true;
    for (const annotate::Card& c : panel.cards) {
      ImGui::PushID(static_cast<int>(c.id));
      if (ImGui::SmallButton("restore")) panel.restore = c.id;
      ImGui::SameLine();
      ImGui::TextUnformatted(c.title.empty() ? "(untitled)" : c.title.c_str());
      ImGui::PopID();
    }
    if (!panel.message.empty()) ImGui::TextWrapped("%s", panel.message.c_str());
  }
  ImGui::End();
}

void draw_movie_panel(MoviePanel& panel) {
  panel.add_keyframe = panel.clear_keyframes = panel.start_export = false;
  const ImVec2 size = ImGui::GetIO().DisplaySize;
  ImGui::SetNextWindowPos(ImVec2(size.x - 10, size.y - 10), ImGuiCond_FirstUseEver, ImVec2(1, 1));
  ImGui::SetNextWindowSize(ImVec2(320, 0), ImGuiCond_FirstUseEver);
  ImGui::SetNextWindowCollapsed(true, ImGuiCond_FirstUseEver);
  if (ImGui::Begin("Movie")) {
    ImGui::Text("%zu keyframe(s)", panel.keyframes);
    if (ImGui::Button("add keyframe")) panel.add_keyframe = true;
    ImGui::SameLine();
    if (ImGui::Button("clear")) panel.clear_keyframes = true;
    ImGui::InputText("output", panel.output, sizeof panel.output);
    ImGui::TextDisabled("NAME.mp4 (ffmpeg) or a folder for PNG frames");
    ImGui::InputInt("frames", &panel.frames);
    panel.frames = std::clamp(panel.frames, 2, 100000);
    ImGui::InputFloat("fps", &panel.fps, 1.0f, 10.0f, "%.3g");
    panel.fps = std::clamp(panel.fps, 0.1f, 1000.0f);
    if (panel.progress) {
      ImGui::ProgressBar(float(*panel.progress), ImVec2(-1, 0));
    } else {
      ImGui::BeginDisabled(panel.keyframes < 2);
      if (ImGui::Button("export")) panel.start_export = true;
      ImGui::EndDisabled();
    }
    if (!panel.message.empty()) ImGui::TextWrapped("%s", panel.message.c_str());
  }
  ImGui::End();
}

void draw_open_panel(OpenPanel& panel) {
  panel.open = false;
  const ImVec2 size = ImGui::GetIO().DisplaySize;
  ImGui::SetNextWindowPos(ImVec2(10, size.y - 10), ImGuiCond_FirstUseEver, ImVec2(0, 1));
  ImGui::SetNextWindowSize(ImVec2(360, 0), ImGuiCond_FirstUseEver);
  ImGui::SetNextWindowCollapsed(true, ImGuiCond_FirstUseEver);
  if (ImGui::Begin("Open")) {
    ImGui::InputText("path", panel.path, sizeof panel.path);
    ImGui::TextDisabled("a .vxc, a project NAME.vxr, OME-Zarr or any importable file");
    if (ImGui::Button("open")) panel.open = true;
    if (!panel.message.empty()) ImGui::TextWrapped("%s", panel.message.c_str());
  }
  ImGui::End();
}

std::string viewer_window_title(const std::string& dataset, double frame_ms) {
  char ms[32];
  std::snprintf(ms, sizeof ms, "%.1f ms", frame_ms);
  return "vxr - " + (dataset.empty() ? std::string("(no data)") : dataset) + " - " + ms;
}

void draw_viewer_panels(ViewerState& state, const PanelInputs& in) {
  if (!state.ui_visible()) return;
  ImGui::SetNextWindowPos(ImVec2(10, 10), ImGuiCond_FirstUseEver);
  ImGui::SetNextWindowSize(ImVec2(340, 0), ImGuiCond_FirstUseEver);
  if (ImGui::Begin("Channels")) {
    if (!in.dataset.empty()) ImGui::TextUnformatted(in.dataset.c_str());
    channel_panel(state, in);
  }
  ImGui::End();
  // Bottom left, whatever the window's height.
  ImGui::SetNextWindowPos(ImVec2(10, ImGui::GetIO().DisplaySize.y - 10), ImGuiCond_FirstUseEver, ImVec2(0, 1));
  ImGui::SetNextWindowSize(ImVec2(340, 0), ImGuiCond_FirstUseEver);
  if (ImGui::Begin("Rendering")) render_panel(state);
  ImGui::End();
  if (state.help_visible()) {
    if (ImGui::Begin("Help")) {
      for (const ShortcutHelp& s : viewer_shortcuts()) ImGui::BulletText("%s: %s", s.keys, s.action);
    }
    ImGui::End();
  }
}

}  // namespace vxr::xr
