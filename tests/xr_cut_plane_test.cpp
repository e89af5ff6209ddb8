// The headset's cut plane tool (xr/cut_plane_tool.h): scripted InputStates
// give the exact plane in voxel coordinates (through the tip, normal along
// the aim, scaled by the voxel size), a grabbed volume carries the plane, the
// menu cycles roi -> cut -> count, and a Scene keeps the plane through JSON;
// then end to end, headless (`vxr view` with a pose script) and through the
// OpenXR test runtime: the half the plane cuts away is background.
#include <doctest/doctest.h>

#include <cmath>
#include <cstring>
#include <filesystem>
#include <fstream>

#include "annotate/annotation_store.h"
#include "assets/assets.h"
#include "cli_runner.h"
#include "core/image.h"
#include "gpu_fixture.h"
#include "scene/render_settings.h"
#include "volume/dense_chunk_source.h"
#include "xr/cut_plane_tool.h"
#include "xr/hand_tools.h"
#include "xr/openxr/openxr_target.h"
#include "xr/view_session.h"
#include "xr_test_util.h"

using namespace vxr;
using namespace vxr::xr;
using annotate::Tool;
namespace fs = std::filesystem;

namespace {

const VolumePlacement kPlacement{{64, 32, 16}, {0.5, 1.0, 2.0}};

// The volume 1 mm per unit, centred at (0, 1.5, -0.5), axes as the reference's.
xr::VolumeTransform plain() {
  xr::VolumeTransform t;
  t.position = {0.0, 1.5, -0.5};
  t.scale = 0.001;
  return t;
}

// The turn taking the controller's aim (-z) to `aim` (a unit vector).
glm::dquat turn_to(const glm::dvec3& aim) {
  const glm::dvec3 from(0, 0, -1);
  const glm::dvec3 axis = glm::cross(from, aim);
  if (glm::length(axis) < 1e-12) return glm::dquat(1, 0, 0, 0);  // (never asked to turn around)
  return glm::angleAxis(std::acos(glm::clamp(glm::dot(from, aim), -1.0, 1.0)), glm::normalize(axis));
}

// Right hand with its tip (5 cm along the aim) at `tip`, aiming along `aim` (a unit vector).
InputState right_aiming(const glm::dvec3& tip, const glm::dvec3& aim, double trigger) {
  InputState s;
  s.hands[kLeft].tracked = s.hands[kRight].tracked = true;
  s.hands[kLeft].aim.position = {-0.3, 1.0, -0.2};
  s.hands[kRight].aim.orientation = turn_to(aim);
  s.hands[kRight].aim.position = tip - 0.05 * aim;
  s.hands[kRight].trigger = trigger;
  return s;
}

void check_plane(const CutPlane& got, const glm::dvec3& normal, double offset) {
  CHECK(got.enabled);
  CHECK(glm::length(got.normal - normal) < 1e-12);
  CHECK(got.offset == doctest::Approx(offset).epsilon(1e-12));
}

}  // namespace

TEST_CASE("cut plane: a held right trigger puts the plane through the tip, normal along the aim, in voxels") {
  CutPlaneTool cut(kPlacement);
  CHECK(!cut.plane().enabled);
  // Tip 4, 2, 6 mm from the centre: voxel (4 / 0.5 + 32, 2 / 1 + 16, 6 / 2 + 8) = (40, 18, 11).
  const glm::dvec3 tip = plain().position + glm::dvec3(0.004, 0.002, 0.006);
  InputState in = right_aiming(tip, {0, 0, -1}, 0.5);
  CHECK(!cut.update(in, plain(), true).placed);
  CHECK(!cut.plane().enabled);  // 0.5 does not press
  in.hands[kRight].trigger = 0.7;
  cut.update(in, plain(), true);
  CHECK(cut.following());
  check_plane(cut.plane(), {0, 0, -1}, 11.0);  // keeps z <= 11: beyond the tip

  // Held (0.5 is above the release), it follows the hand: aim along (1, 0, -1), the normal scaled
  // by the voxel size (0.5, 1, 2) because the plane stays square to the aim in metres.
  const glm::dvec3 aim = glm::normalize(glm::dvec3(1, 0, -1));
  in = right_aiming(tip, aim, 0.5);
  cut.update(in, plain(), true);
  const glm::dvec3 n = glm::normalize(glm::dvec3(0.5, 0.0, -2.0));
  check_plane(cut.plane(), n, -glm::dot(n, glm::dvec3(40, 18, 11)));

  // Released below 0.4: the plane stays; the hand moving on leaves it there.
  in.hands[kRight].trigger = 0.3;
  CHECK(cut.update(in, plain(), true).placed);
  CHECK(!cut.following());
  in = right_aiming(tip + glm::dvec3(0.01, 0.0, 0.0), {0, 1, 0}, 0.0);
  CHECK(!cut.update(in, plain(), true).placed);
  check_plane(cut.plane(), n, -glm::dot(n, glm::dvec3(40, 18, 11)));

  // Grabbing the volume afterwards (turned, scaled, moved) changes nothing in voxels: the plane moves with it.
  xr::VolumeTransform moved = plain();
  moved.orientation = glm::angleAxis(0.7, glm::normalize(glm::dvec3(1, 2, 3)));
  moved.scale = 0.003;
  moved.position += glm::dvec3(0.2, -0.1, 0.3);
  cut.update(in, moved, true);
  check_plane(cut.plane(), n, -glm::dot(n, glm::dvec3(40, 18, 11)));

  // The left trigger clears it, once per press.
  in.hands[kLeft].trigger = 1.0;
  CHECK(cut.update(in, moved, true).cleared);
  CHECK(!cut.plane().enabled);
  CHECK(!cut.update(in, moved, true).cleared);
}

TEST_CASE("cut plane: placed on a turned, scaled, moved volume, the plane is the hand's in that volume's voxels") {
  // The volume turned 90 degrees about +y (its +x looks along the reference's -z), 2 mm per unit.
  xr::VolumeTransform t;
  t.position = {0.1, 1.4, -0.6};
  t.orientation = glm::angleAxis(glm::radians(90.0), glm::dvec3(0, 1, 0));
  t.scale = 0.002;
  CutPlaneTool cut(kPlacement);
  // Tip (10, 4, -6) mm from the centre: volume frame (6, 4, 10) mm / 2 = (3, 2, 5) units,
  // voxel (3 / 0.5 + 32, 2 / 1 + 16, 5 / 2 + 8) = (38, 18, 10.5). Aim -z = the volume's +x.
  InputState in = right_aiming(t.position + glm::dvec3(0.010, 0.004, -0.006), {0, 0, -1}, 1.0);
  cut.update(in, t, true);
  check_plane(cut.plane(), {1, 0, 0}, -38.0);  // keeps x >= 38
  in.hands[kRight].trigger = 0.0;
  cut.update(in, t, true);
  check_plane(cut.plane(), {1, 0, 0}, -38.0);
}

TEST_CASE("cut plane: inactive (another tool in the cycle) the triggers leave the plane alone") {
  CutPlaneTool cut(kPlacement);
  const glm::dvec3 tip = plain().position;
  InputState in = right_aiming(tip, {0, 0, -1}, 1.0);
  cut.update(in, plain(), true);
  in.hands[kRight].trigger = 0.0;
  cut.update(in, plain(), true);
  const CutPlane placed = cut.plane();
  REQUIRE(placed.enabled);
  in = right_aiming(tip + glm::dvec3(0.005, 0, 0), {1, 0, 0}, 1.0);
  in.hands[kLeft].trigger = 1.0;
  const CutPlaneFrame r = cut.update(in, plain(), false);
  CHECK(!r.placed);
  CHECK(!r.cleared);
  CHECK(cut.plane().normal == placed.normal);
  CHECK(cut.plane().offset == placed.offset);
  // A trigger held into the cut tool must be pressed again.
  cut.update(in, plain(), true);
  CHECK(!cut.following());
  CHECK(cut.plane().normal == placed.normal);
  // Lost tracking while following freezes the plane where it was last seen.
  in.hands[kLeft].trigger = 0.0;
  in.hands[kRight].trigger = 0.0;
  cut.update(in, plain(), true);
  in.hands[kRight].trigger = 1.0;
  cut.update(in, plain(), true);
  REQUIRE(cut.following());
  const CutPlane seen = cut.plane();
  in.hands[kRight].tracked = false;
  in.hands[kRight].aim.position += glm::dvec3(0.05, 0, 0);
  CHECK(!cut.update(in, plain(), true).placed);
  CHECK(cut.plane().offset == seen.offset);
}

TEST_CASE("cut plane: the menu cycles roi -> cut -> count, and while cutting the triggers store nothing") {
  const fs::path p = fs::path(VXR_TEST_OUT_DIR) / "cut_plane" / "menu";
  fs::remove_all(p);
  fs::create_directories(p.parent_path());
  auto store = annotate::AnnotationStore::open(p.string(), true);
  REQUIRE(store.is_ok());
  ViewerTools tools(**store);
  HandToolSettings settings;
  settings.tool = Tool::kTrack;
  HandTools hands(tools, kPlacement, settings);
  InputState in = right_aiming(plain().position, {0, 0, -1}, 0.0);
  auto press_menu = [&] {
    in.hands[kRight].menu = true;
    CHECK(hands.update(in, plain(), 0).tool_changed);
    in.hands[kRight].menu = false;
    hands.update(in, plain(), 0);
  };
  press_menu();
  CHECK(hands.tool() == Tool::kRoi);
  CHECK(!hands.cutting());
  press_menu();
  CHECK(hands.cutting());
  CHECK(hands.report() == "tool cut");
  for (double trigger : {1.0, 0.0, 1.0, 0.0}) {  // right presses, then the left's
    in.hands[kRight].trigger = trigger;
    in.hands[kLeft].trigger = trigger;
    const HandToolFrame r = hands.update(in, plain(), 0);
    CHECK(!r.stored);
    CHECK(r.error.empty());
  }
  auto markers = (*store)->markers();
  REQUIRE(markers.is_ok());
  CHECK(markers->empty());
  auto rois = (*store)->rois();
  REQUIRE(rois.is_ok());
  CHECK(rois->empty());
  press_menu();
  CHECK(!hands.cutting());
  CHECK(hands.tool() == Tool::kCount);
  CHECK(tools.palette().tool() == Tool::kCount);
  // Back on count, a fresh press counts.
  in.hands[kRight].trigger = 1.0;
  CHECK(hands.update(in, plain(), 0).stored);
}

TEST_CASE("cut plane: the settings' clip keeps a plane through JSON exactly, older files have none, a bad one is refused") {
  RenderSettings rs;
  rs.clip.cut = true;
  rs.clip.cut_normal = {0.1, -0.7000000000000001, 1.0 / 3.0};
  rs.clip.cut_offset = -123.456789012345678;
  Scene sc;
  sc.render = rs;
  auto back = scene_from_json(scene_to_json(sc));
  REQUIRE_MESSAGE(back.is_ok(), back.status().to_string());
  CHECK(back->render.clip == rs.clip);
  CHECK(*back == sc);

  auto old = scene_from_json(R"({"volume": "x.vxc", "lod_bias": 1})");
  REQUIRE(old.is_ok());
  CHECK(!old->render.clip.cut);
  CHECK(scene_to_json(Scene{}).find("\"clip\"") == std::string::npos);  // no plane, no key

  for (const char* bad : {R"({"clip": {"cut": {"normal": [0, 0, 0], "offset": 1}}})",
                          R"({"clip": {"cut": {"normal": [1, 0, 0]}}})", R"({"clip": {"cut": [1, 0, 0, 2]}})",
                          R"({"clip": {"cut": {"normal": [1, 0], "offset": 1}}})",
                          R"({"clip": {"roi": {"lo": [0, 0, 0.5], "hi": [1, 1, 0.5]}}})"}) {
    CAPTURE(bad);
    auto r = render_settings_from_json(bad);
    REQUIRE(!r.is_ok());
    CHECK(r.status().message().find("clip") != std::string::npos);
  }
}

// ---- end to end ----

namespace {

std::string q(const fs::path& p) { return test::shell_quote(p.string()); }

// The head at (0, 1.6, 0) looking along -z at the sample (default transform, centre (0, 1.6, -0.5)),
// eyes together (ipd 0). The right hand aims along +x with its tip 1 cm right of the centre.
// The left menu button is pressed at frame base + 1 (the cycle to cut) and the trigger pressed at
// base + 2 and released at base + 4 when `cut`.
const glm::dvec3 kCutTip{0.01, 1.6, -0.5};

std::string cut_script(uint64_t base, bool cut, int size, const std::string& extra = "") {
  auto f = [&](uint64_t n) { return std::to_string(base + n); };
  // Aim -z turned to +x: -90 degrees about +y, [x, y, z, w].
  const std::string aim = R"({"position": [-0.04, 1.6, -0.5], "orientation": [0, -0.70710678118654752, 0, 0.70710678118654752]})";
  return R"({"view": {"width": )" + std::to_string(size) + R"(, "height": )" + std::to_string(size) +
         R"(, "ipd_m": 0})" + extra + R"(,
  "keys": [
    {"frame": 0, "head": {"position": [0, 1.6, 0], "orientation": [0, 0, 0, 1]},
     "right": {"aim": )" + aim + R"(, "trigger": 0}},
    {"frame": )" + f(1) + R"(, "left": {"menu": true}},
    {"frame": )" + f(2) + R"(, "left": {"menu": false}, "right": {"trigger": )" + (cut ? "1" : "0") + R"(}},
    {"frame": )" + f(4) + R"(, "right": {"trigger": 0}},
    {"frame": )" + f(6) + R"(}
  ]})";
}

VolumePlacement sample_placement() {
  auto v = assets::sample_volume();
  REQUIRE(v.is_ok());
  return {v->dims, v->voxel_size};
}

// The sample's default transform keeps the reference's +x as the volume's +x: the plane keeps
// voxels x >= the tip's.
CutPlane expected_cut(const VolumePlacement& p) {
  const xr::VolumeTransform t = default_volume_transform(p);
  const glm::dvec3 v = p.world_to_voxel_point(t.to_volume(kCutTip));
  return {true, {1, 0, 0}, -v.x};
}

bool background(const ImageRgba8& im, uint32_t x, uint32_t y) {
  const uint8_t* px = &im.pixels[(size_t(y) * im.width + x) * 4];
  return px[0] == 0 && px[1] == 0 && px[2] == 0;
}

// With the eye on the axis, every ray of a column left of the middle stays at x < 0, all of it cut
// away: background. Without the plane much of that half shows the volume. Right of the plane the
// picture is the volume's.
void check_cut_half(const ImageRgba8& cut, const ImageRgba8& whole) {
  REQUIRE(cut.width == whole.width);
  REQUIRE(cut.height == whole.height);
  size_t left_shown_whole = 0, left_shown_cut = 0, right_shown_cut = 0;
  for (uint32_t y = 0; y < cut.height; ++y)
    for (uint32_t x = 0; x < cut.width; ++x) {
      if (x < cut.width / 2) {
        left_shown_whole += !background(whole, x, y);
        left_shown_cut += !background(cut, x, y);
      } else if (x > cut.width / 2 + 2) {
        right_shown_cut += !background(cut, x, y);
      }
    }
  INFO("left half: " << left_shown_whole << " volume pixels without the plane, " << left_shown_cut
                     << " with it; right: " << right_shown_cut);
  CHECK(left_shown_whole >= 20);  // the sample is mostly clear: tens of pixels a half at 48^2
  CHECK(left_shown_cut == 0);
  CHECK(right_shown_cut >= 10);
}

}  // namespace

TEST_CASE("cut plane end to end: a headless pose script cuts away the half behind the plane, vxr view says where") {
  const fs::path dir = test::scratch_dir("cut_plane", "headless");
  const VolumePlacement p = sample_placement();
  const CutPlane want = expected_cut(p);
  std::ofstream(dir / "cut.json") << cut_script(0, true, 64);
  std::ofstream(dir / "whole.json") << cut_script(0, false, 64);
  // No store: the menu turns the cut plane on (the cycle is off -> cut), then the trigger places it.
  // The run without the plane presses the menu too, not the trigger.
  // Without a store vxr view reports the plane through log_info: let the children print it.
  struct InfoLog {
    InfoLog() { setenv("VXR_LOG", "info", 1); }
    ~InfoLog() { unsetenv("VXR_LOG"); }
  } info_log;
  test::CliRun with = test::run_vxr("view --sample --headless --script " + q(dir / "cut.json") + " --png-dir " +
                                        q(dir / "with"),
                                    dir, 180);
  INFO("stdout: " << with.out << "\nstderr: " << with.err);
  REQUIRE(with.rc == 0);
  // "cut plane: normal (x, y, z), offset d (voxels)", printed to 6 decimals.
  const std::string all = with.out + with.err;
  const size_t at = all.find("cut plane: normal (");
  REQUIRE(at != std::string::npos);
  glm::dvec3 n;
  double offset = 0.0;
  REQUIRE(std::sscanf(all.c_str() + at, "cut plane: normal (%lf, %lf, %lf), offset %lf", &n.x, &n.y, &n.z, &offset) == 4);
  CHECK(glm::length(n - want.normal) < 2e-6);
  CHECK(std::abs(offset - want.offset) < 2e-6);
  test::CliRun without = test::run_vxr("view --sample --headless --script " + q(dir / "whole.json") + " --png-dir " +
                                           q(dir / "without"),
                                       dir, 180);
  REQUIRE(without.rc == 0);
  CHECK((without.out + without.err).find("cut plane") == std::string::npos);
  CHECK((without.out + without.err).find("tool cut") != std::string::npos);
  auto a = read_png((dir / "with" / "last_left.png").string());
  auto b = read_png((dir / "without" / "last_left.png").string());
  REQUIRE(a.is_ok());
  REQUIRE(b.is_ok());
  check_cut_half(*a, *b);
}

TEST_CASE("cut plane through the OpenXR test runtime: menu to cut, trigger held and released, the eye is cut") {
  test::GpuTestScope scope;
  const std::string dir = test::xr_out_dir("cut_plane");
  // Input is live once the session is FOCUSED: the menu at frame 11 (roi -> cut), the trigger 12..14.
  // Frame 9 shows the whole volume, frame 20 the cut one; UNORM swapchains: the renderer's bytes.
  test::use_test_runtime(dir, cut_script(10, true, 48, R"(, "no_srgb": true, "dump_frames": [9, 20])"));
  auto v = assets::sample_volume();
  REQUIRE(v.is_ok());
  const VolumePlacement placement{v->dims, v->voxel_size};
  const fs::path store_dir = fs::path(dir) / "store";
  auto store = annotate::AnnotationStore::open(store_dir.string(), true);
  REQUIRE(store.is_ok());
  std::shared_ptr<annotate::AnnotationStore> shared(std::move(store).value());
  ViewOptions o;
  o.frames = 22;
  o.tool_store = shared;
  o.hand_tools.tool = Tool::kRoi;
  std::vector<std::string> lines;
  o.on_tool_report = [&](const std::string& line) { lines.push_back(line); };
  auto source = DenseChunkSource::create({*v});
  REQUIRE(source.is_ok());
  const TargetFactory openxr = []() -> Result<std::unique_ptr<FrameTarget>> {
    auto t = OpenXrTarget::create({});
    if (!t) return t.status();
    return std::unique_ptr<FrameTarget>(std::move(t).value());
  };
  auto stats = run_view(openxr, *source, o, default_volume_transform(placement));
  REQUIRE_MESSAGE(stats.is_ok(), stats.status().to_string());
  CHECK(stats->pipelines_after_first_frame == 0);
  const CutPlane want = expected_cut(placement);
  REQUIRE(stats->cut.enabled);
  CHECK(glm::length(stats->cut.normal - want.normal) < 1e-5);  // OpenXR poses are float
  CHECK(std::abs(stats->cut.offset - want.offset) < 0.05);     // voxels
  REQUIRE(lines.size() == 2);
  CHECK(lines[0] == "tool cut");
  CHECK(lines[1].rfind("cut plane: normal (", 0) == 0);
  auto rois = shared->rois();
  REQUIRE(rois.is_ok());
  CHECK(rois->empty());  // the trigger cut; the roi tool stored nothing
  const nlohmann::json report = test::runtime_report(dir);
  REQUIRE(report.size() == 1);
  CHECK(report[0]["haptic_pulses"].get<int>() == 1);  // the release
  CHECK_MESSAGE(test::core_validation_messages(dir).empty(), test::core_validation_messages(dir));
  auto whole = read_png(dir + "/dump/frame000009_left.png");
  auto cut = read_png(dir + "/dump/frame000020_left.png");
  REQUIRE(whole.is_ok());
  REQUIRE(cut.is_ok());
  check_cut_half(*cut, *whole);
}

TEST_CASE("cut plane through the OpenXR test runtime: a starting plane (a card's) is drawn from the first frame") {
  test::GpuTestScope scope;
  const std::string dir = test::xr_out_dir("cut_plane_start");
  test::use_test_runtime(dir, cut_script(100, false, 48, R"(, "no_srgb": true, "dump_frames": [6])"));
  auto v = assets::sample_volume();
  REQUIRE(v.is_ok());
  const VolumePlacement placement{v->dims, v->voxel_size};
  auto source = DenseChunkSource::create({*v});
  REQUIRE(source.is_ok());
  const TargetFactory openxr = []() -> Result<std::unique_ptr<FrameTarget>> {
    auto t = OpenXrTarget::create({});
    if (!t) return t.status();
    return std::unique_ptr<FrameTarget>(std::move(t).value());
  };
  ViewOptions o;
  o.frames = 8;
  auto whole = run_view(openxr, *source, o, default_volume_transform(placement));
  REQUIRE_MESSAGE(whole.is_ok(), whole.status().to_string());
  CHECK(!whole->cut.enabled);
  auto whole_eye = read_png(dir + "/dump/frame000006_left.png");
  REQUIRE(whole_eye.is_ok());
  o.frame.lod.cut = expected_cut(placement);
  auto cut = run_view(openxr, *source, o, default_volume_transform(placement));
  REQUIRE_MESSAGE(cut.is_ok(), cut.status().to_string());
  CHECK(cut->cut.offset == o.frame.lod.cut.offset);
  auto cut_eye = read_png(dir + "/dump/frame000006_left.png");
  REQUIRE(cut_eye.is_ok());
  check_cut_half(*cut_eye, *whole_eye);
  CHECK_MESSAGE(test::core_validation_messages(dir).empty(), test::core_validation_messages(dir));
}

TEST_CASE("cut plane in a card: vxr render draws a Scene's clip plane, --save-card keeps it, --card draws it again") {
  const fs::path dir = test::scratch_dir("cut_plane", "render_card");
  const fs::path store = dir / "store";
  {
    auto s = annotate::AnnotationStore::open(store.string(), true);
    REQUIRE(s.is_ok());
  }
  const std::string input = q(std::string(VXR_TESTDATA_DIR) + "/tiff/mri-stack-calibrated.tif");
  // Keeps the voxels with x >= 93 (the right half of the 186-wide MRI stack; volume fractions).
  std::ofstream(dir / "scene.json") << R"({"render": {"clip": {"cut": {"normal": [1, 0, 0], "offset": -0.5}}}})";
  test::CliRun r = test::run_vxr("render " + input + " --settings " + q(dir / "scene.json") + " --size 48x48 -o " +
                                     q(dir / "cut.png") + " --save-card " + q(store),
                                 dir, 180);
  INFO("stdout: " << r.out << "\nstderr: " << r.err);
  REQUIRE(r.rc == 0);
  r = test::run_vxr("render --card " + q(store.string() + ":1") + " -o " + q(dir / "again.png"), dir, 180);
  REQUIRE(r.rc == 0);
  r = test::run_vxr("render " + input + " --size 48x48 -o " + q(dir / "whole.png"), dir, 180);
  REQUIRE(r.rc == 0);
  auto cut = read_png((dir / "cut.png").string());
  auto again = read_png((dir / "again.png").string());
  auto whole = read_png((dir / "whole.png").string());
  REQUIRE(cut.is_ok());
  REQUIRE(again.is_ok());
  REQUIRE(whole.is_ok());
  CHECK(again->pixels == cut->pixels);  // the card kept the plane
  size_t shown_cut = 0, shown_whole = 0;
  for (uint32_t y = 0; y < 48; ++y)
    for (uint32_t x = 0; x < 48; ++x) {
      shown_cut += !background(*cut, x, y);
      shown_whole += !background(*whole, x, y);
    }
  INFO("volume pixels: " << shown_cut << " cut, " << shown_whole << " whole");
  CHECK(shown_cut > 0);
  CHECK(shown_cut + 48 * 48 / 20 < shown_whole);  // a good part of the head is gone
  // The CPU reference draws the card's plane too: the same half of the head.
  r = test::run_vxr("render --card " + q(store.string() + ":1") + " --reference --reference-step 0.5 -o " +
                        q(dir / "reference.png"),
                    dir, 180);
  REQUIRE(r.rc == 0);
  auto reference = read_png((dir / "reference.png").string());
  REQUIRE(reference.is_ok());
  size_t shown_reference = 0, shown_differently = 0;
  for (uint32_t y = 0; y < 48; ++y)
    for (uint32_t x = 0; x < 48; ++x) {
      shown_reference += !background(*reference, x, y);
      shown_differently += background(*reference, x, y) != background(*cut, x, y);
    }
  INFO("volume pixels in the reference: " << shown_reference << ", shown differently: " << shown_differently);
  CHECK(shown_differently <= 48 * 48 / 100);  // silhouette pixels only
}
