#include "xr/desktop/viewer_panels.h"

#include <imgui.h>

#include <algorithm>
#include <cfloat>
#include <cstdio>

#include "render/colormap.h"

namespace vxr::xr {
namespace {

constexpr const char* kModelLabels[] = {"emission-absorption", "emission", "MIP", "MinIP", "average", "isosurface"};
constexpr OpticalModel kModelOrder[] = {OpticalModel::kEmissionAbsorption, OpticalModel::kEmission, OpticalModel::kMip,
                                        OpticalModel::kMinIp, OpticalModel::kAverage, OpticalModel::kIsosurface};

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
    ImGui::PopID();
    ImGui::Separator();
  }
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

void read_store(ViewerTools& tools, ToolPanel& panel) {
  if (panel.read_revision == tools.revision()) return;
  panel.read_revision = tools.revision();
  annotate::AnnotationStore& store = tools.store();
  auto counts = store.counts();
  auto measurements = store.measurements();
  auto cards = store.cards();
  if (!counts || !measurements || !cards) {
    panel.message = store.path() + ": " + (!counts ? counts.status() : !measurements ? measurements.status()
                                                                                      : cards.status())
                                              .message();
    return;
  }
  panel.counts = *counts;
  panel.lengths.clear();
  for (const annotate::Measurement& m : *measurements)
    panel.lengths.emplace_back(m.label.empty() ? "#" + std::to_string(m.id) : m.label, store.length(m));
  panel.cards = *cards;
}

}  // namespace

void draw_tools_panel(ViewerTools& tools, ToolPanel& panel) {
  read_store(tools, panel);
  panel.save_card = false;
  panel.restore.reset();
  const ImVec2 size = ImGui::GetIO().DisplaySize;
  ImGui::SetNextWindowPos(ImVec2(size.x - 10, 10), ImGuiCond_FirstUseEver, ImVec2(1, 0));
  ImGui::SetNextWindowSize(ImVec2(300, 0), ImGuiCond_FirstUseEver);
  ImGui::SetNextWindowCollapsed(true, ImGuiCond_FirstUseEver);  // a title bar until the user opens it
  if (ImGui::Begin("Tools and cards")) {
    int mode = static_cast<int>(panel.mode);
    ImGui::RadioButton("navigate", &mode, 0);
    ImGui::SameLine();
    ImGui::RadioButton("count", &mode, 1);
    ImGui::SameLine();
    ImGui::RadioButton("measure", &mode, 2);
    if (mode != static_cast<int>(panel.mode)) {
      tools.cancel();
      panel.mode = static_cast<ToolPanel::Mode>(mode);
    }
    if (panel.mode == ToolPanel::Mode::kCount) ImGui::InputText("class", panel.cls, sizeof panel.cls);
    if (panel.mode != ToolPanel::Mode::kNavigate)
      ImGui::TextDisabled("click the volume (on the plane through the orbit centre)");
    const annotate::ToolLiveState& live = tools.palette().live();
    if (live.measuring)
      ImGui::Text("measuring: %.3f %s", live.measuring_length, tools.store().voxel_space().unit.c_str());
    for (const auto& [cls, n] : panel.counts) ImGui::BulletText("%s: %zu marker(s)", cls.c_str(), n);
    for (const auto& [label, length] : panel.lengths)
      ImGui::BulletText("measurement %s: %.3f %s", label.c_str(), length, tools.store().voxel_space().unit.c_str());
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
