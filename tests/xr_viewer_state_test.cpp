// The desktop viewer's UI model: every edit lands in the Scene/RenderSettings
// the renderer takes, bad edits are refused without changing anything, and the
// navigation camera keeps its invariants.
#include <doctest/doctest.h>

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <fstream>

#include <GLFW/glfw3.h>

#include <imgui.h>
#include <imgui_internal.h>  // ImGui::FindWindowByName: a panel's content height

#include "annotate/annotation_store.h"
#include "render/volume_renderer.h"
#include "xr/desktop/viewer_keys.h"
#include "xr/desktop/viewer_panels.h"
#include "xr/desktop/viewer_state.h"

using namespace vxr;
using namespace vxr::xr;

namespace {
ViewerState two_channels(uint32_t timepoints = 3) {
  Scene s;
  s.render.channels.resize(2);
  return ViewerState(s, timepoints, {0, 4095});
}
double dot(const std::array<double, 3>& a, const std::array<double, 3>& b) {
  return a[0] * b[0] + a[1] * b[1] + a[2] * b[2];
}
double dist(const std::array<double, 3>& a, const std::array<double, 3>& b) {
  const std::array<double, 3> d{a[0] - b[0], a[1] - b[1], a[2] - b[2]};
  return std::sqrt(dot(d, d));
}
}  // namespace

TEST_CASE("viewer state: channel edits reach the render settings and bump the revision") {
  ViewerState v = two_channels();
  const uint64_t r0 = v.revision();
  REQUIRE(v.set_colormap(1, "viridis").is_ok());
  CHECK(v.render().channels[1].colormap == "viridis");
  CHECK(v.render().channels[0].colormap == "gray");
  CHECK(v.revision() == r0 + 1);
  REQUIRE(v.set_colormap(1, "viridis").is_ok());
  CHECK(v.revision() == r0 + 1);  // no change, no re-upload
  REQUIRE(v.set_window(0, 100, 900).is_ok());
  CHECK(v.render().channels[0].window_lo == 100);
  CHECK(v.render().channels[0].window_hi == 900);
  REQUIRE(v.set_window_level(0, 2000, 1000).is_ok());
  CHECK(v.render().channels[0].window_lo == 1500);
  CHECK(v.render().channels[0].window_hi == 2500);
  REQUIRE(v.set_channel_visible(1, false).is_ok());
  CHECK_FALSE(v.render().channels[1].enabled);
  REQUIRE(v.set_step(0.25).is_ok());
  CHECK(v.render().step_voxels == 0.25);
  v.set_model(OpticalModel::kMip);
  CHECK(v.render().model == OpticalModel::kMip);
  REQUIRE(v.set_timepoint(2).is_ok());
  CHECK(v.scene().timepoint == 2);
}

TEST_CASE("viewer state: bad edits are refused and change nothing") {
  ViewerState v = two_channels();
  const Scene before = v.scene();
  const uint64_t r0 = v.revision();
  CHECK(v.set_colormap(0, "no-such-map").code() == ErrorCode::kInvalidArgument);
  CHECK(v.set_colormap(2, "gray").code() == ErrorCode::kOutOfRange);
  CHECK(v.set_window(0, 5, 5).code() == ErrorCode::kInvalidArgument);
  CHECK(v.set_window(0, 9, 1).code() == ErrorCode::kInvalidArgument);
  CHECK(v.set_window(0, 0, NAN).code() == ErrorCode::kInvalidArgument);
  CHECK(v.set_window_level(0, 10, 0).code() == ErrorCode::kInvalidArgument);
  CHECK(v.set_step(0).code() == ErrorCode::kInvalidArgument);
  CHECK(v.set_step(100).code() == ErrorCode::kInvalidArgument);
  CHECK(v.set_timepoint(3).code() == ErrorCode::kOutOfRange);
  CHECK(v.set_gamma(0, -1).code() == ErrorCode::kInvalidArgument);
  CHECK(v.scene() == before);
  CHECK(v.revision() == r0);
}

TEST_CASE("viewer state: choosing a colour map drops explicit colour points") {
  Scene s;
  s.render.channels[0].color_points = {{0, {1, 0, 0}}, {1, {0, 0, 1}}};
  ViewerState v(s, 1, {0, 255});
  REQUIRE(v.set_colormap(0, "gray").is_ok());
  CHECK(v.render().channels[0].color_points.empty());
}

TEST_CASE("viewer state: cycling models and colour maps visits every one and wraps") {
  ViewerState v = two_channels();
  const OpticalModel first = v.render().model;
  int steps = 0;
  do {
    v.cycle_model(1);
    ++steps;
  } while (v.render().model != first && steps < 100);
  CHECK(steps == 6);
  v.cycle_model(-1);
  CHECK(v.render().model == OpticalModel::kIsosurface);

  REQUIRE(v.set_colormap(0, "viridis").is_ok());
  REQUIRE(v.cycle_colormap(0, 1).is_ok());
  const std::string next = v.render().channels[0].colormap;
  CHECK(next != "viridis");
  REQUIRE(v.cycle_colormap(0, -1).is_ok());
  CHECK(v.render().channels[0].colormap == "viridis");
}

TEST_CASE("viewer state: orbit keeps the distance, the up vector orthogonal and the pitch bounded") {
  ViewerState v = two_channels();
  const CameraState home = v.camera();
  const double d0 = dist(home.eye, home.target);
  v.orbit_drag(120, 45);
  const CameraState c = v.camera();
  CHECK(dist(c.eye, c.target) == doctest::Approx(d0));
  const std::array<double, 3> fwd{c.target[0] - c.eye[0], c.target[1] - c.eye[1], c.target[2] - c.eye[2]};
  CHECK(dot(fwd, c.up) == doctest::Approx(0).epsilon(1e-9));
  CHECK(dist(c.eye, home.eye) > 0.1);
  v.orbit_drag(0, 1e6);  // past the pole: clamped, never flips
  CHECK(v.orbit().pitch < 3.14159265 / 2);
  v.reset_view();
  CHECK(v.camera() == home);
}

TEST_CASE("viewer state: zoom moves toward the focus, pan moves the focus across the view") {
  ViewerState v = two_channels();
  const double d0 = v.orbit().distance;
  v.zoom(3);
  CHECK(v.orbit().distance < d0);
  v.zoom(-3);
  CHECK(v.orbit().distance == doctest::Approx(d0));
  v.pan_drag(100, 0, 800);  // drag right: the scene follows, the focus moves to -x (camera on +z)
  CHECK(v.orbit().focus[0] < 0);
  CHECK(v.orbit().focus[1] == doctest::Approx(0));
}

TEST_CASE("viewer state: axis views look along each axis at the volume centre") {
  ViewerState v = two_channels();
  for (int axis = 0; axis < 3; ++axis) {
    v.orbit_drag(77, 13);
    REQUIRE(v.axis_view(axis).is_ok());
    const CameraState c = v.camera();
    std::array<double, 3> dir{c.eye[0] - c.target[0], c.eye[1] - c.target[1], c.eye[2] - c.target[2]};
    const double n = std::sqrt(dot(dir, dir));
    CHECK(dir[axis] / n == doctest::Approx(1).epsilon(1e-3));
    CHECK(dist(c.target, {0, 0, 0}) == doctest::Approx(0));
  }
  CHECK(v.axis_view(3).code() == ErrorCode::kInvalidArgument);
}

TEST_CASE("viewer state: keys step time within range and record toggles") {
  ViewerState v = two_channels(2);
  v.handle_key(ViewerKey::kTimePrev);
  CHECK(v.scene().timepoint == 0);
  v.handle_key(ViewerKey::kTimeNext);
  v.handle_key(ViewerKey::kTimeNext);
  CHECK(v.scene().timepoint == 1);
  CHECK_FALSE(v.help_visible());
  v.handle_key(ViewerKey::kToggleHelp);
  CHECK(v.help_visible());
  CHECK_FALSE(v.quit_requested());
  v.handle_key(ViewerKey::kQuit);
  CHECK(v.quit_requested());
  CHECK(viewer_shortcuts().size() >= 8);
}

TEST_CASE("viewer state: playback (fake clock) advances in order, keys pause, step and change the speed") {
  ViewerState v = two_channels(7);
  v.tick(100.0);
  v.handle_key(ViewerKey::kPlayPause);
  CHECK(v.playback().playing());
  // 10 timepoints/s: frames every 40 ms show 0, 0, 1, 1, 2, ... never back, never beyond the last.
  std::vector<uint32_t> shown;
  uint64_t revision = v.revision();
  for (int i = 0; i <= 25; ++i) {
    v.tick(100.0 + 0.04 * i);
    if (shown.empty() || shown.back() != v.scene().timepoint) {
      shown.push_back(v.scene().timepoint);
      if (shown.size() > 1) CHECK(v.revision() > revision);  // the renderer hears of each new timepoint
      revision = v.revision();
    }
  }
  CHECK(shown == std::vector<uint32_t>{0, 1, 2, 3, 4, 5, 6});
  CHECK_FALSE(v.playback().playing());  // not looping: stops at the last
  // Space at the end starts over; '.' pauses and steps; ',' steps back. (Keys act at the latest tick.)
  v.tick(110.0);
  v.handle_key(ViewerKey::kPlayPause);
  v.tick(110.0);
  CHECK(v.scene().timepoint == 0);
  v.tick(110.15);
  CHECK(v.scene().timepoint == 1);
  v.handle_key(ViewerKey::kStepForward);
  CHECK_FALSE(v.playback().playing());
  CHECK(v.scene().timepoint == 2);
  v.tick(111.0);
  CHECK(v.scene().timepoint == 2);
  v.handle_key(ViewerKey::kStepBack);
  v.handle_key(ViewerKey::kStepBack);
  v.handle_key(ViewerKey::kStepBack);
  CHECK(v.scene().timepoint == 0);  // clamped without looping
  // ']' doubles the speed: 20 timepoints/s.
  v.handle_key(ViewerKey::kFaster);
  CHECK(v.playback().speed() == 2.0);
  v.tick(112.0);
  v.handle_key(ViewerKey::kPlayPause);
  v.tick(112.0);
  v.tick(112.101);
  CHECK(v.scene().timepoint == 2);
  v.handle_key(ViewerKey::kSlower);
  v.handle_key(ViewerKey::kSlower);
  CHECK(v.playback().speed() == 0.5);
  // A timepoint set by hand (slider, arrows, "time") pauses and playback goes on from there.
  REQUIRE(v.set_timepoint(5).is_ok());
  CHECK_FALSE(v.playback().playing());
  CHECK(v.playback().timepoint() == 5);
  REQUIRE(v.apply_command("loop on").is_ok());
  REQUIRE(v.apply_command("speed 1").is_ok());
  v.tick(113.0);
  REQUIRE(v.apply_command("play").is_ok());
  v.tick(113.0);
  CHECK(v.scene().timepoint == 5);
  v.tick(113.101);
  CHECK(v.scene().timepoint == 6);
  v.tick(113.201);
  CHECK(v.scene().timepoint == 0);  // looping wraps
  REQUIRE(v.apply_command("pause").is_ok());
  v.tick(120.0);
  CHECK(v.scene().timepoint == 0);
  CHECK_FALSE(v.apply_command("speed 100").is_ok());
  CHECK_FALSE(v.apply_command("loop maybe").is_ok());
  ViewerState one = two_channels(1);
  CHECK(one.apply_command("play").message().find("nothing to play") != std::string::npos);
}

TEST_CASE("viewer state: a card's camera goes back to the orbit that made it, restore checks the card") {
  ViewerState v = two_channels(4);
  v.orbit_drag(120, -80);
  v.pan_drag(30, 10, 600);
  v.zoom(2);
  const OrbitCamera made = v.orbit();
  CameraState world = made.camera();
  for (int i = 0; i < 3; ++i) {  // as viewer_world_camera stores it: longest side 2.5 world units
    world.eye[i] *= 2.5;
    world.target[i] *= 2.5;
  }
  const OrbitCamera back = orbit_for_camera(world, 2.5);
  CHECK(back.distance == doctest::Approx(made.distance));
  CHECK(back.yaw == doctest::Approx(made.yaw));
  CHECK(back.pitch == doctest::Approx(made.pitch));
  for (int i = 0; i < 3; ++i) CHECK(back.focus[i] == doctest::Approx(made.focus[i]));
  CHECK(dist(back.camera().up, made.camera().up) < 1e-9);

  ViewerState w = two_channels(4);
  RenderSettings one_channel;
  one_channel.channels.resize(1);
  CHECK_FALSE(w.restore(one_channel, 1, back).is_ok());  // another channel count
  RenderSettings saved = v.render();
  saved.channels[1].colormap = "viridis";
  CHECK_FALSE(w.restore(saved, 4, back).is_ok());  // no such timepoint
  CHECK(w.orbit() == two_channels(4).orbit());     // refused: nothing changed
  REQUIRE(w.apply_command("play").is_ok());
  REQUIRE(w.restore(saved, 3, back).is_ok());
  CHECK(w.render() == saved);
  CHECK(w.scene().timepoint == 3);
  CHECK(w.playback().timepoint() == 3);
  CHECK_FALSE(w.playback().playing());
  CHECK(w.orbit().distance == doctest::Approx(made.distance));
}

TEST_CASE("viewer state: script commands drive the same edits and bad lines are named") {
  ViewerState v = two_channels();
  REQUIRE(v.apply_command("colormap 1 magma").is_ok());
  REQUIRE(v.apply_command("window 0 10 200").is_ok());
  REQUIRE(v.apply_command("model mip").is_ok());
  REQUIRE(v.apply_command("step 0.125").is_ok());
  REQUIRE(v.apply_command("iso 87.5").is_ok());
  REQUIRE(v.apply_command("time 1").is_ok());
  REQUIRE(v.apply_command("visible 0 off").is_ok());
  REQUIRE(v.apply_command("  # a comment").is_ok());
  REQUIRE(v.apply_command("view 2").is_ok());
  CHECK(v.render().channels[1].colormap == "magma");
  CHECK(v.render().channels[0].window_hi == 200);
  CHECK(v.render().model == OpticalModel::kMip);
  CHECK(v.render().step_voxels == 0.125);
  CHECK(v.render().iso_value == 87.5);
  CHECK(v.scene().timepoint == 1);
  CHECK_FALSE(v.render().channels[0].enabled);
  const Scene before = v.scene();
  for (const char* line : {"window 0 10", "window 0 x 3", "colormap 0 nope", "model fancy", "frobnicate 1",
                           "time -1", "view 4", "visible 0 maybe", "step 1e999", "iso", "iso high", "iso 1e999"}) {
    const Status s = v.apply_command(line);
    CAPTURE(line);
    CHECK(s.code() == ErrorCode::kInvalidArgument);
    CHECK(s.message().find(line) != std::string::npos);
  }
  CHECK(v.scene() == before);
}

TEST_CASE("viewer state: window geometry round-trips and a malformed file is refused") {
  const std::filesystem::path dir = std::filesystem::path(VXR_TEST_OUT_DIR) / "viewer_state_config";
  std::filesystem::remove_all(dir);
  const std::string path = (dir / "vxr" / "desktop.json").string();
  auto first = load_window_geometry(path);
  REQUIRE(first.is_ok());
  CHECK(first.value() == WindowGeometry{});
  REQUIRE(save_window_geometry(path, {1600, 900}).is_ok());
  auto back = load_window_geometry(path);
  REQUIRE(back.is_ok());
  CHECK(back.value() == WindowGeometry{1600, 900});
  std::ofstream(path) << "{\"width\": -3}";
  CHECK(load_window_geometry(path).status().code() == ErrorCode::kInvalidArgument);
  std::ofstream(path) << "not json";
  CHECK(load_window_geometry(path).status().code() == ErrorCode::kInvalidArgument);

  const char* old = std::getenv("XDG_CONFIG_HOME");
  const std::string saved = old ? old : "";
  setenv("XDG_CONFIG_HOME", dir.c_str(), 1);
  CHECK(viewer_config_path() == path);
  if (old)
    setenv("XDG_CONFIG_HOME", saved.c_str(), 1);
  else
    unsetenv("XDG_CONFIG_HOME");
}

TEST_CASE("viewer keys: GLFW presses map to viewer keys, releases and repeats of toggles do not") {
  CHECK(viewer_key_from_glfw(GLFW_KEY_ESCAPE, GLFW_PRESS) == ViewerKey::kQuit);
  CHECK_FALSE(viewer_key_from_glfw(GLFW_KEY_ESCAPE, GLFW_RELEASE).has_value());
  CHECK_FALSE(viewer_key_from_glfw(GLFW_KEY_ESCAPE, GLFW_REPEAT).has_value());
  CHECK(viewer_key_from_glfw(GLFW_KEY_R, GLFW_PRESS) == ViewerKey::kResetView);
  CHECK(viewer_key_from_glfw(GLFW_KEY_2, GLFW_PRESS) == ViewerKey::kAxisY);
  CHECK(viewer_key_from_glfw(GLFW_KEY_RIGHT, GLFW_REPEAT) == ViewerKey::kTimeNext);
  CHECK(viewer_key_from_glfw(GLFW_KEY_SPACE, GLFW_PRESS) == ViewerKey::kPlayPause);
  CHECK_FALSE(viewer_key_from_glfw(GLFW_KEY_SPACE, GLFW_REPEAT).has_value());
  CHECK(viewer_key_from_glfw(GLFW_KEY_PERIOD, GLFW_REPEAT) == ViewerKey::kStepForward);
  CHECK(viewer_key_from_glfw(GLFW_KEY_COMMA, GLFW_PRESS) == ViewerKey::kStepBack);
  CHECK(viewer_key_from_glfw(GLFW_KEY_RIGHT_BRACKET, GLFW_PRESS) == ViewerKey::kFaster);
  CHECK(viewer_key_from_glfw(GLFW_KEY_LEFT_BRACKET, GLFW_PRESS) == ViewerKey::kSlower);
  CHECK_FALSE(viewer_key_from_glfw(GLFW_KEY_H, GLFW_REPEAT).has_value());
  CHECK_FALSE(viewer_key_from_glfw(GLFW_KEY_Z, GLFW_PRESS).has_value());
  CHECK(viewer_key_from_glfw(GLFW_KEY_ENTER, GLFW_PRESS) == ViewerKey::kFinishTool);  // the tools' finish
  CHECK_FALSE(viewer_key_from_glfw(GLFW_KEY_ENTER, GLFW_REPEAT).has_value());
}

namespace {
// One headless ImGui frame (no backend: the font atlas is built but never uploaded).
int panel_vertices(ViewerState& state) {
  ImGuiIO& io = ImGui::GetIO();
  io.DisplaySize = ImVec2(1280, 800);
  io.DeltaTime = 1.0f / 60;
  unsigned char* pixels = nullptr;
  int w = 0, h = 0;
  io.Fonts->GetTexDataAsRGBA32(&pixels, &w, &h);
  ImGui::NewFrame();
  PanelInputs in;
  in.dataset = "test.zarr";
  in.histograms = {std::vector<float>(64, 1.0f)};
  draw_viewer_panels(state, in);
  ImGui::Render();
  return ImGui::GetDrawData()->TotalVtxCount;
}
}  // namespace

TEST_CASE("viewer panels: draw without touching the state, the help panel adds, Tab hides all") {
  ImGuiContext* ctx = ImGui::CreateContext();
  ImGui::GetIO().IniFilename = nullptr;
  ViewerState v = two_channels(4);
  const uint64_t r0 = v.revision();
  panel_vertices(v);  // first frame lays the windows out
  const int panels = panel_vertices(v);
  CHECK(panels > 0);
  CHECK(v.revision() == r0);
  v.handle_key(ViewerKey::kToggleHelp);
  panel_vertices(v);  // a new auto-sized window stays hidden for its first frame
  const int with_help = panel_vertices(v);
  CHECK(with_help > panels);
  // The isosurface adds its value's slider to the Rendering panel (a row
  // more of content; the panel may clip it), and drawing it changes nothing.
  auto rendering_height = [&] {
    panel_vertices(v);  // a window's content size is the last frame's
    panel_vertices(v);
    return ImGui::FindWindowByName("Rendering")->ContentSize.y;
  };
  v.set_model(OpticalModel::kAverage);
  const float average = rendering_height();
  v.set_model(OpticalModel::kIsosurface);
  const uint64_t r1 = v.revision();
  const float iso = rendering_height();
  CHECK(iso >= average + ImGui::GetFrameHeight());
  CHECK(v.revision() == r1);
  v.handle_key(ViewerKey::kToggleUi);
  CHECK(panel_vertices(v) == 0);
  ImGui::DestroyContext(ctx);
  CHECK(viewer_window_title("head.zarr", 12.345) == "vxr - head.zarr - 12.3 ms");
}

TEST_CASE("tools panel: the live trace, track and box follow every tool event, stored or not, and the list every annotation") {
  const std::filesystem::path dir = std::filesystem::path(VXR_TEST_OUT_DIR) / "xr" / "tools_panel";
  std::filesystem::remove_all(dir);
  std::filesystem::create_directories(dir);
  auto store = annotate::AnnotationStore::open((dir / "store").string(), true);
  REQUIRE(store.is_ok());
  ViewerTools tools(**store);
  ToolPanel panel;
  ImGuiContext* ctx = ImGui::CreateContext();
  ImGui::GetIO().IniFilename = nullptr;
  auto frame = [&](uint32_t timepoint) {
    ImGuiIO& io = ImGui::GetIO();
    io.DisplaySize = ImVec2(1280, 800);
    io.DeltaTime = 1.0f / 60;
    unsigned char* pixels = nullptr;
    int w = 0, h = 0;
    io.Fonts->GetTexDataAsRGBA32(&pixels, &w, &h);
    ImGui::NewFrame();
    ImGui::SetWindowCollapsed("Tools and cards", false);  // the user opened it
    draw_tools_panel(tools, panel, timepoint);
    ImGui::Render();
    return ImGui::GetDrawData()->TotalVtxCount;
  };
  panel.mode = ToolPanel::Mode::kTrace;
  frame(0);
  const int empty = frame(0);
  REQUIRE(tools.trace_click({10, 10, 1}, 0).is_ok());
  REQUIRE(tools.trace_click({30, 10, 1}, 0).is_ok());
  CHECK(frame(0) > empty);
  CHECK(panel.status.nodes == 2);
  CHECK(panel.status.traced_length == doctest::Approx(20.0));
  CHECK(panel.status.current_node != annotate::kNoParent);
  REQUIRE(tools.finish(0).is_ok());  // stores nothing: the panel still shows it
  frame(0);
  CHECK(panel.status.current_node == annotate::kNoParent);
  REQUIRE(tools.track_click({5, 5, 1}, "cell", 0).is_ok());
  REQUIRE(tools.track_click({6, 5, 1}, "cell", 2).is_ok());
  REQUIRE(tools.roi_drag(annotate::ToolAction::kPress, {0, 0, 0}, 2).is_ok());
  REQUIRE(tools.roi_drag(annotate::ToolAction::kMove, {8, 8, 2}, 2).is_ok());  // being dragged, not stored
  panel.mode = ToolPanel::Mode::kRoi;
  frame(2);
  REQUIRE(panel.status.roi.has_value());
  CHECK(panel.status.roi->id == 0);
  CHECK(panel.status.roi_markers == 1);
  CHECK(panel.status.track_markers == 2);
  CHECK(panel.status.last_timepoint == 2);
  size_t markers = 0, skeletons = 0, tracks = 0;
  for (const AnnotationRow& r : panel.rows) {
    markers += r.kind == AnnotationKind::kMarker;
    skeletons += r.kind == AnnotationKind::kSkeleton;
    tracks += r.kind == AnnotationKind::kTrack;
  }
  CHECK(markers == 2);
  CHECK(skeletons == 1);
  CHECK(tracks == 1);
  CHECK_FALSE(panel.remove.has_value());  // nothing pressed
  ImGui::DestroyContext(ctx);
}

TEST_CASE("viewer state: the opacity curve is edited point by point from the ramp and refuses bad curves") {
  ViewerState v = two_channels();
  CHECK(v.opacity_curve(0) == std::vector<OpacityPoint>{{0, 0}, {1, 1}});  // no points: the ramp
  const uint64_t r0 = v.revision();
  auto added = v.add_opacity_point(0, 0.5, 0.1);
  REQUIRE(added.is_ok());
  CHECK(*added == 1);
  CHECK(v.render().channels[0].opacity_points == std::vector<OpacityPoint>{{0, 0}, {0.5, 0.1}, {1, 1}});
  CHECK(v.render().channels[1].opacity_points.empty());
  CHECK(v.revision() == r0 + 1);
  // A dragged point stops at its neighbours and inside 0..1.
  REQUIRE(v.move_opacity_point(0, 1, 1.5, 2.0).is_ok());
  CHECK(v.render().channels[0].opacity_points[1] == OpacityPoint{1.0, 1.0});
  REQUIRE(v.move_opacity_point(0, 1, 0.25, 0.3).is_ok());
  CHECK(v.render().channels[0].opacity_points[1] == OpacityPoint{0.25, 0.3});
  CHECK_FALSE(v.move_opacity_point(0, 3, 0.5, 0.5).is_ok());
  REQUIRE(v.remove_opacity_point(0, 0).is_ok());
  CHECK(v.render().channels[0].opacity_points == std::vector<OpacityPoint>{{0.25, 0.3}, {1, 1}});
  const uint64_t r1 = v.revision();
  CHECK_FALSE(v.remove_opacity_point(0, 0).is_ok());  // two points left: a curve keeps them
  CHECK_FALSE(v.set_opacity_points(0, {{0.5, 0.2}, {0.4, 0.3}}).is_ok());  // x falls
  CHECK_FALSE(v.set_opacity_points(0, {{0.5, 1.2}}).is_ok());
  CHECK_FALSE(v.set_opacity_points(2, {}).is_ok());
  CHECK(v.revision() == r1);
  // Script: pairs, and "ramp" back to no points.
  REQUIRE(v.apply_command("opacity 1 0:0,0.5:0.2,1:1").is_ok());
  CHECK(v.render().channels[1].opacity_points == std::vector<OpacityPoint>{{0, 0}, {0.5, 0.2}, {1, 1}});
  REQUIRE(v.apply_command("opacity 1 ramp").is_ok());
  CHECK(v.render().channels[1].opacity_points.empty());
  for (const char* bad : {"opacity 0", "opacity 0 0:0,1", "opacity 0 0.5:0,0.2:1", "opacity 0 0:2", "opacity 5 0:0",
                          "opacity 0 a:b"}) {
    const Status s = v.apply_command(bad);
    CHECK_MESSAGE(!s.is_ok(), bad);
    CHECK(s.message().find(bad) != std::string::npos);
  }
}

TEST_CASE("viewer state: cut plane and clip box land in the settings' clip, in volume fractions") {
  ViewerState v = two_channels();
  CHECK_FALSE(v.render().clip.cut);
  CHECK_FALSE(v.render().clip.roi);
  REQUIRE(v.apply_command("cut z 0.25").is_ok());
  const ClipSettings& c = v.render().clip;
  CHECK(c.cut);
  CHECK(c.cut_normal == std::array<double, 3>{0, 0, 1});
  CHECK(c.cut_offset == -0.25);  // keeps z >= 0.25
  REQUIRE(v.apply_command("cut -x 0.75").is_ok());
  CHECK(c.cut_normal == std::array<double, 3>{-1, 0, 0});
  CHECK(c.cut_offset == 0.75);  // keeps x <= 0.75
  REQUIRE(v.apply_command("cut 3 4 0 -0.5").is_ok());
  CHECK(c.cut_normal[0] == doctest::Approx(0.6));
  CHECK(c.cut_normal[1] == doctest::Approx(0.8));
  CHECK(c.cut_offset == -0.5);
  REQUIRE(v.apply_command("cut off").is_ok());
  CHECK_FALSE(c.cut);
  CHECK(c.cut_normal[1] == doctest::Approx(0.8));  // off keeps the plane for "cut on"
  REQUIRE(v.apply_command("clip 0.1 0.2 0 0.9 0.8 1").is_ok());
  CHECK(c.roi);
  CHECK(c.roi_lo == std::array<double, 3>{0.1, 0.2, 0});
  CHECK(c.roi_hi == std::array<double, 3>{0.9, 0.8, 1});
  const uint64_t r = v.revision();
  for (const char* bad : {"cut", "cut w 0.5", "cut z 1.5", "cut 0 0 0 1", "cut z", "clip 0.5 0 0 0.4 1 1",
                          "clip 0 0 0 1 1 2", "clip 0 0 0 1 1", "clip maybe"}) {
    const Status s = v.apply_command(bad);
    CHECK_MESSAGE(!s.is_ok(), bad);
    CHECK(s.message().find(bad) != std::string::npos);
  }
  CHECK(v.revision() == r);
  REQUIRE(v.apply_command("clip off").is_ok());
  CHECK_FALSE(c.roi);
  // The settings carry the clip through JSON (cards, --settings), and leave it out when off.
  REQUIRE(v.apply_command("cut y 0.5").is_ok());
  REQUIRE(v.apply_command("clip on").is_ok());
  auto back = render_settings_from_json(render_settings_to_json(v.render()));
  REQUIRE(back.is_ok());
  CHECK(back->clip == v.render().clip);
  CHECK(render_settings_to_json(RenderSettings{}).find("clip") == std::string::npos);
  // In level-0 voxels for the traversal: a fraction f is the point f * dims.
  LodSettings lod;
  apply_clip(v.render().clip, {100, 200, 50}, lod);
  CHECK(lod.cut.enabled);
  CHECK(glm::dot(lod.cut.normal, glm::dvec3(10, 100, 7)) + lod.cut.offset == doctest::Approx(0.0));  // y = 0.5 * 200
  CHECK(lod.roi.enabled);
  CHECK(lod.roi.lo == glm::dvec3(10, 40, 0));
  CHECK(lod.roi.hi == glm::dvec3(90, 160, 50));
}

TEST_CASE("viewer state: fly moves the orbit centre and the eye together along the view, and keys name the directions") {
  ViewerState v = two_channels();
  REQUIRE(v.axis_view(2).is_ok());  // looking along -z
  const CameraState before = v.camera();
  v.fly({1, 0, 0}, 0.2);
  CameraState c = v.camera();
  CHECK(c.target[2] == doctest::Approx(before.target[2] - 0.2));
  CHECK(c.eye[2] == doctest::Approx(before.eye[2] - 0.2));
  CHECK(dist(c.eye, c.target) == doctest::Approx(dist(before.eye, before.target)));
  v.fly({0, 1, 1}, 0.1);  // right is +x, up is +y looking along -z
  c = v.camera();
  CHECK(c.target[0] == doctest::Approx(before.target[0] + 0.1));
  CHECK(c.target[1] == doctest::Approx(before.target[1] + 0.1));
  // Held keys: half the orbit distance per second, a stalled frame capped at 0.1 s.
  const double d = v.orbit().distance;
  const auto focus = v.orbit().focus;
  v.fly_for({-1, 0, 0}, 5.0);
  CHECK(v.orbit().focus[2] == doctest::Approx(focus[2] + 0.5 * d * 0.1));
  const uint64_t r = v.revision();
  v.fly_for({}, 0.05);  // nothing held: nothing changes
  CHECK(v.revision() == r);
  REQUIRE(v.apply_command("fly 0 0 0.3").is_ok());
  CHECK(v.orbit().focus[1] == doctest::Approx(focus[1] + 0.3));
  CHECK_FALSE(v.apply_command("fly 1 0").is_ok());
  // W/S, D/A, E/Q as the window polls them, and the help table lists them.
  auto held = [](std::initializer_list<int> keys) {
    return held_fly_keys([keys](int k) { return std::find(keys.begin(), keys.end(), k) != keys.end(); });
  };
  CHECK(held({GLFW_KEY_W}).forward == 1);
  CHECK(held({GLFW_KEY_S}).forward == -1);
  CHECK(held({GLFW_KEY_W, GLFW_KEY_S}).forward == 0);
  CHECK(held({GLFW_KEY_D}).right == 1);
  CHECK(held({GLFW_KEY_A}).right == -1);
  CHECK(held({GLFW_KEY_E}).up == 1);
  CHECK(held({GLFW_KEY_Q}).up == -1);
  CHECK_FALSE(held({GLFW_KEY_R}).any());
  int fly_rows = 0;
  for (const ShortcutHelp& s : viewer_shortcuts()) fly_rows += std::string(s.action).find("fly") == 0;
  CHECK(fly_rows == 3);
}

TEST_CASE("viewer state: the remembered view is keyed by the input, kept inside a project, and a bad file named") {
  namespace fs = std::filesystem;
  const fs::path dir = fs::path(VXR_TEST_OUT_DIR) / "viewer_state_memory";
  fs::remove_all(dir);
  const char* old = std::getenv("XDG_CONFIG_HOME");
  const std::string saved = old ? old : "";
  setenv("XDG_CONFIG_HOME", (dir / "config").c_str(), 1);
  const std::string a = remembered_view_path((dir / "a.tif").string());
  const std::string b = remembered_view_path((dir / "b.tif").string());
  CHECK(a.rfind((dir / "config" / "vxr" / "views").string() + "/", 0) == 0);
  CHECK(a != b);
  CHECK(a == remembered_view_path((dir / "a.tif").string()));
  // A project keeps it inside: for the folder and for a file in it.
  fs::create_directories(dir / "brain.vxr");
  std::ofstream(dir / "brain.vxr" / "project.json") << "{}";
  CHECK(remembered_view_path((dir / "brain.vxr").string()) == (dir / "brain.vxr" / "viewer.json").string());
  CHECK(remembered_view_path((dir / "brain.vxr" / "volume.vxc").string()) ==
        (dir / "brain.vxr" / "viewer.json").string());
  if (old)
    setenv("XDG_CONFIG_HOME", saved.c_str(), 1);
  else
    unsetenv("XDG_CONFIG_HOME");

  auto none = load_remembered_view(a);
  REQUIRE(none.is_ok());
  CHECK_FALSE(none->has_value());
  ViewerState v = two_channels();
  REQUIRE(v.apply_command("cut x 0.3").is_ok());
  REQUIRE(v.apply_command("opacity 1 0:0,1:0.4").is_ok());
  Scene s = v.scene();
  s.volume = (dir / "a.tif").string();
  s.camera = v.camera();
  s.has_camera = true;
  REQUIRE(save_remembered_view(a, s).is_ok());
  auto back = load_remembered_view(a);
  REQUIRE(back.is_ok());
  REQUIRE(back->has_value());
  CHECK(**back == s);
  std::ofstream(a) << "[1, 2";
  const Status bad = load_remembered_view(a).status();
  CHECK(bad.code() == ErrorCode::kInvalidArgument);
  CHECK(bad.message().rfind(a + ": not a remembered view", 0) == 0);
}

TEST_CASE("viewer state: the view counts as moving for two ticks and 0.2 s after the user moved it, then still") {
  ViewerState v = two_channels();
  v.tick(10.0);
  CHECK_FALSE(v.moving());  // nothing moved yet
  v.orbit_drag(5, 0);
  CHECK_FALSE(v.moving());  // commands and scripts draw at full detail: only the window's input counts
  v.note_motion();
  CHECK(v.moving());
  v.tick(10.5);
  CHECK(v.moving());  // one tick: the frame after the motion is still coarse, however slow
  v.tick(11.0);
  CHECK_FALSE(v.moving());  // two ticks and 1 s later: full detail
  v.note_motion();
  v.tick(11.01);
  v.tick(11.02);
  v.tick(11.03);
  CHECK(v.moving());  // fast frames: still moving until 0.2 s have passed
  v.tick(11.25);
  CHECK_FALSE(v.moving());
}

TEST_CASE("opacity editor: a click adds a point under the cursor, a drag moves it, a right click removes it") {
  ImGuiContext* ctx = ImGui::CreateContext();
  ImGuiIO& io = ImGui::GetIO();
  io.IniFilename = nullptr;
  ViewerState v = two_channels();
  ImVec2 p0{0, 0};
  float width = 0;
  constexpr float kHeight = 72.0f;  // the editor's canvas
  auto frame = [&](float x, float opacity, bool left, bool right) {
    io.DisplaySize = ImVec2(800, 600);
    io.DeltaTime = 1.0f / 60;
    unsigned char* pixels = nullptr;
    int w = 0, h = 0;
    io.Fonts->GetTexDataAsRGBA32(&pixels, &w, &h);
    io.MousePos = ImVec2(p0.x + x * width, p0.y + (1.0f - opacity) * kHeight);
    io.MouseDown[ImGuiMouseButton_Left] = left;
    io.MouseDown[ImGuiMouseButton_Right] = right;
    ImGui::NewFrame();
    ImGui::SetNextWindowPos(ImVec2(0, 0));
    ImGui::SetNextWindowSize(ImVec2(400, 300));
    ImGui::Begin("editor", nullptr, ImGuiWindowFlags_NoDecoration);
    p0 = ImGui::GetCursorScreenPos();
    width = std::max(64.0f, ImGui::GetContentRegionAvail().x);
    draw_opacity_editor(v, 1, nullptr);
    ImGui::End();
    ImGui::Render();
  };
  frame(0.5f, 0.8f, false, false);  // lays the window out: the canvas's place is known from here on
  frame(0.5f, 0.8f, false, false);
  CHECK(v.render().channels[1].opacity_points.empty());  // hovering edits nothing
  frame(0.5f, 0.8f, true, false);                        // press away from the two points: a new one
  auto points = v.render().channels[1].opacity_points;
  REQUIRE(points.size() == 3);
  CHECK(points[1].x == doctest::Approx(0.5).epsilon(0.01));
  CHECK(points[1].opacity == doctest::Approx(0.8).epsilon(0.02));
  frame(0.25f, 0.4f, true, false);  // held and moved: the new point follows
  frame(0.25f, 0.4f, false, false);
  points = v.render().channels[1].opacity_points;
  REQUIRE(points.size() == 3);
  CHECK(points[1].x == doctest::Approx(0.25).epsilon(0.02));
  CHECK(points[1].opacity == doctest::Approx(0.4).epsilon(0.02));
  CHECK(v.render().channels[0].opacity_points.empty());  // another channel's curve
  frame(0.25f, 0.4f, false, true);  // right click on it: gone
  frame(0.25f, 0.4f, false, false);
  CHECK(v.render().channels[1].opacity_points == std::vector<OpacityPoint>{{0, 0}, {1, 1}});
  ImGui::DestroyContext(ctx);
}

TEST_CASE("clip controls: clicking the cut plane box turns the plane on and off, drawing alone changes nothing") {
  ImGuiContext* ctx = ImGui::CreateContext();
  ImGuiIO& io = ImGui::GetIO();
  io.IniFilename = nullptr;
  ViewerState v = two_channels();
  REQUIRE(v.apply_command("cut -y 0.3").is_ok());
  REQUIRE(v.apply_command("cut off").is_ok());
  ImVec2 p0{0, 0};
  auto frame = [&](bool left) {
    io.DisplaySize = ImVec2(800, 600);
    io.DeltaTime = 1.0f / 60;
    unsigned char* pixels = nullptr;
    int w = 0, h = 0;
    io.Fonts->GetTexDataAsRGBA32(&pixels, &w, &h);
    io.MousePos = ImVec2(p0.x + 6, p0.y + 6);  // inside the first widget's box: the "cut plane" checkbox
    io.MouseDown[ImGuiMouseButton_Left] = left;
    ImGui::NewFrame();
    ImGui::SetNextWindowPos(ImVec2(0, 0));
    ImGui::SetNextWindowSize(ImVec2(400, 400));
    ImGui::Begin("clip", nullptr, ImGuiWindowFlags_NoDecoration);
    p0 = ImGui::GetCursorScreenPos();
    draw_clip_controls(v);
    ImGui::End();
    ImGui::Render();
  };
  const uint64_t r0 = v.revision();
  frame(false);
  frame(false);
  CHECK(v.revision() == r0);
  frame(true);
  frame(false);  // a click: press, release
  CHECK(v.render().clip.cut);
  CHECK(v.render().clip.cut_normal == std::array<double, 3>{0, -1, 0});  // the plane it had
  CHECK(v.render().clip.cut_offset == 0.3);
  frame(true);
  frame(false);
  CHECK_FALSE(v.render().clip.cut);
  REQUIRE(v.apply_command("cut 1 1 1 -0.9").is_ok());  // oblique: normal and offset controls instead
  frame(false);
  CHECK(v.render().clip.cut);
  ImGui::DestroyContext(ctx);
}
