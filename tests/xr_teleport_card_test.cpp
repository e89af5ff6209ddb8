// Teleport (xr/teleport.h) and a card's pose restored in a headset
// (transform_placing_camera, ViewOptions::place_for_camera): the transform
// numbers by hand, then through the OpenXR test runtime; the card's picture
// through `vxr view --card --xr` against the card's own snapshot.
#include <doctest/doctest.h>

#include <cmath>
#include <cstring>
#include <filesystem>
#include <fstream>

#include "annotate/annotation_store.h"
#include "assets/assets.h"
#include "cli_runner.h"
#include "core/image.h"
#include "core/output_file.h"
#include "golden.h"
#include "gpu_fixture.h"
#include "volume/dense_chunk_source.h"
#include "xr/interaction.h"
#include "xr/openxr/openxr_target.h"
#include "xr/teleport.h"
#include "xr/view_session.h"
#include "xr_test_util.h"

using namespace vxr;
using namespace vxr::xr;
namespace fs = std::filesystem;

namespace {

// 64 x 32 x 16 voxels of 0.5 x 1 x 2: a 32-unit cube, centred on 0 in the volume frame.
const VolumePlacement kPlacement{{64, 32, 16}, {0.5, 1.0, 2.0}};

xr::VolumeTransform turned() {
  xr::VolumeTransform t;
  t.position = {0.2, 1.4, -0.9};
  t.orientation = glm::angleAxis(0.5, glm::dvec3(0, 1, 0));
  t.scale = 0.01;
  return t;
}

// The head at (0.1, 1.7, 0.3), turned 30 degrees left and looking 20 degrees down.
Pose head() {
  Pose h;
  h.position = {0.1, 1.7, 0.3};
  h.orientation = glm::angleAxis(glm::radians(30.0), glm::dvec3(0, 1, 0)) *
                  glm::angleAxis(glm::radians(-20.0), glm::dvec3(1, 0, 0));
  return h;
}

// The right hand's aim ray along the volume's -z through volume point (3, -4, 40):
// it enters the box at (3, -4, 16).
InputState aiming(const xr::VolumeTransform& t, bool click) {
  InputState in;
  in.hands[kLeft].tracked = in.hands[kRight].tracked = true;
  in.hands[kRight].aim.position = t.to_reference({3.0, -4.0, 40.0});
  in.hands[kRight].aim.orientation = t.orientation;  // its -z is the volume's -z
  in.hands[kRight].grip = in.hands[kRight].aim;
  in.hands[kRight].stick_click = click;
  return in;
}

void check_vec(const glm::dvec3& a, const glm::dvec3& b, double eps) {
  INFO("got (" << a.x << ", " << a.y << ", " << a.z << "), want (" << b.x << ", " << b.y << ", " << b.z << ")");
  CHECK(glm::length(a - b) < eps);
}

}  // namespace

TEST_CASE("teleport: hold aims at where the ray enters the volume, release brings that point 0.4 m before the eyes") {
  xr::VolumeTransform t = turned();
  const xr::VolumeTransform t0 = t;
  Teleport teleport(kPlacement);
  CHECK(!teleport.update(aiming(t, false), head(), t).moved);
  CHECK(!teleport.update(aiming(t, true), head(), t).moved);  // pressed: aiming
  REQUIRE(teleport.target().has_value());
  check_vec(*teleport.target(), {3.0, -4.0, 16.0}, 1e-12);
  CHECK(!teleport.update(aiming(t, true), head(), t).moved);  // held: the volume stays
  CHECK(t.position == t0.position);
  const TeleportFrame released = teleport.update(aiming(t, false), head(), t);
  CHECK(released.moved);
  CHECK(released.hand == kRight);
  CHECK(!teleport.target().has_value());
  // The spot by hand: 0.4 m along the head's forward made level, (-sin 30, 0, -cos 30), at eye height.
  const glm::dvec3 spot = glm::dvec3(0.1, 1.7, 0.3) + 0.4 * glm::dvec3(-0.5, 0.0, -std::sqrt(3.0) / 2.0);
  const glm::dvec3 entry = t0.orientation * (0.01 * glm::dvec3(3.0, -4.0, 16.0)) + t0.position;
  check_vec(t.position, t0.position + (spot - entry), 1e-12);
  check_vec(t.to_reference({3.0, -4.0, 16.0}), spot, 1e-12);
  CHECK(t.orientation == t0.orientation);  // translation only
  CHECK(t.scale == t0.scale);
}

TEST_CASE("teleport: a ray that misses, lost tracking and a second hand never move the volume") {
  xr::VolumeTransform t = turned();
  const xr::VolumeTransform t0 = t;
  Teleport teleport(kPlacement);
  // Aimed away from the volume (turned half a turn): no target, release does nothing.
  InputState away = aiming(t, true);
  away.hands[kRight].aim.orientation = t.orientation * glm::angleAxis(glm::pi<double>(), glm::dvec3(0, 1, 0));
  teleport.update(away, head(), t);
  CHECK(!teleport.target().has_value());
  away.hands[kRight].stick_click = false;
  CHECK(!teleport.update(away, head(), t).moved);
  // Tracking lost while aiming: cancelled, and the release later does nothing.
  teleport.update(aiming(t, true), head(), t);
  REQUIRE(teleport.target().has_value());
  InputState lost = aiming(t, true);
  lost.hands[kRight].tracked = false;
  teleport.update(lost, head(), t);
  CHECK(!teleport.aiming());
  CHECK(!teleport.update(aiming(t, false), head(), t).moved);
  // The left hand presses while the right aims: the right's release decides.
  teleport.update(aiming(t, true), head(), t);
  InputState both = aiming(t, true);
  both.hands[kLeft].stick_click = true;
  teleport.update(both, head(), t);
  both.hands[kLeft].stick_click = false;
  CHECK(!teleport.update(both, head(), t).moved);
  CHECK(t.position == t0.position);
  CHECK(teleport.update(aiming(t, false), head(), t).moved);
}

TEST_CASE("teleport: a pressed thumbstick aims and does not fly") {
  xr::VolumeTransform t = turned();
  GrabInteraction grab;
  InputState in = aiming(t, true);
  in.hands[kRight].thumbstick = {0.0, 1.0};
  grab.update(in, t, 0.1);
  CHECK(t.position == turned().position);
  in.hands[kRight].stick_click = false;  // released: the push flies
  grab.update(in, t, 0.1);
  CHECK(t.position != turned().position);
}

TEST_CASE("card in a headset: the placed volume makes the head's view the card camera's, at the scale given") {
  Camera card;
  card.eye = {40.0, -120.0, 150.0};
  card.target = {2.0, 3.0, -1.0};
  card.up = {0.0, 0.2, 1.0};  // not orthogonal to the view direction: the camera's own up is derived
  const Pose h = head();
  const xr::VolumeTransform t = transform_placing_camera(card, h, 0.002);
  CHECK(t.scale == 0.002);
  ViewSpec view{h, Fov{}, 64, 64};
  const Camera got = camera_for_view(view, t);
  check_vec(got.eye, card.eye, 1e-9);
  const glm::dvec3 f = glm::normalize(card.target - card.eye);
  check_vec(glm::normalize(got.target - got.eye), f, 1e-12);
  const glm::dvec3 r = glm::normalize(glm::cross(f, card.up));
  check_vec(glm::normalize(got.up), glm::cross(r, f), 1e-12);
  // The head between two eyes is their midpoint, looking as they look.
  const std::vector<ViewSpec> eyes = stereo_views(h, 0.064, Fov{}, 8, 8);
  const Pose between = head_of_views(eyes);
  check_vec(between.position, h.position, 1e-15);
  CHECK(glm::length(glm::dvec4(between.orientation.x - h.orientation.x, between.orientation.y - h.orientation.y,
                               between.orientation.z - h.orientation.z, between.orientation.w - h.orientation.w)) <
        1e-15);
}

// ---- through the OpenXR test runtime ----

namespace {

TargetFactory openxr() {
  return []() -> Result<std::unique_ptr<FrameTarget>> {
    auto t = OpenXrTarget::create({});
    if (!t) return t.status();
    return std::unique_ptr<FrameTarget>(std::move(t).value());
  };
}

}  // namespace

TEST_CASE("teleport through the OpenXR test runtime: the right thumbstick click held then released moves the volume") {
  test::GpuTestScope scope;
  const std::string dir = test::xr_out_dir("teleport");
  // The head at (0, 1.6, 0) looking along -z; the right hand at the head pointing along -z, straight
  // at the volume's centre (0, 1.6, -0.5); the click held from frame 12 to 16.
  // Frames 10 (before) and 14 (aiming) are dumped: the same pose, so they differ only by the marker.
  test::use_test_runtime(dir, R"({"view": {"width": 48, "height": 48, "ipd_m": 0}, "dump_frames": [10, 14],
    "keys": [{"frame": 0, "head": {"position": [0, 1.6, 0], "orientation": [0, 0, 0, 1]},
                          "right": {"aim": {"position": [0, 1.6, 0]}, "thumbstick_click": false}},
             {"frame": 12, "right": {"thumbstick_click": true}},
             {"frame": 16, "right": {"thumbstick_click": false}}]})");
  auto v = assets::sample_volume();
  REQUIRE(v.is_ok());
  const VolumePlacement placement{v->dims, v->voxel_size};
  auto source = DenseChunkSource::create({*v});
  REQUIRE(source.is_ok());
  ViewOptions o;
  o.frames = 20;
  const xr::VolumeTransform t0 = default_volume_transform(placement);
  auto stats = run_view(openxr(), *source, o, t0);
  REQUIRE_MESSAGE(stats.is_ok(), stats.status().to_string());
  CHECK(stats->teleports == 1);
  // The default transform turns the volume's -y towards the viewer: the ray enters the face at
  // z = -0.5 + scale * extent.y / 2, which comes to 0.4 m before the head: z = -0.4.
  const double half_depth = t0.scale * 0.5 * placement.extent().y;
  const glm::dvec3 expected{0.0, 1.6, -0.4 - half_depth};
  CHECK(glm::length(stats->transform.position - expected) < 1e-5);  // OpenXR poses are float
  CHECK(stats->transform.scale == t0.scale);
  const nlohmann::json report = test::runtime_report(dir);
  REQUIRE(report.size() == 1);
  CHECK(report[0]["haptic_pulses"].get<int>() == 1);
  CHECK_MESSAGE(test::core_validation_messages(dir).empty(), test::core_validation_messages(dir));
  // The aim's marker: the ray runs along the view axis, so it shows at the centre of the eye.
  auto before = read_png(dir + "/dump/frame000010_left.png");
  auto aiming = read_png(dir + "/dump/frame000014_left.png");
  REQUIRE(before.is_ok());
  REQUIRE(aiming.is_ok());
  size_t near = 0, elsewhere = 0;
  for (uint32_t y = 0; y < 48; ++y)
    for (uint32_t x = 0; x < 48; ++x) {
      const size_t i = (size_t(y) * 48 + x) * 4;
      if (std::memcmp(&before->pixels[i], &aiming->pixels[i], 4) == 0) continue;
      const double dx = x + 0.5 - 24.0, dy = y + 0.5 - 24.0;
      (dx * dx + dy * dy < 4.0 * 4.0 ? near : elsewhere) += 1;
    }
  CHECK(near > 0);
  CHECK(elsewhere == 0);
}

TEST_CASE("teleport headless: a pose script's thumbstick_click held then released, vxr view prints the moved volume") {
  const fs::path dir = test::scratch_dir("xr", "teleport_headless");
  std::ofstream(dir / "teleport.json") << R"({"view": {"width": 16, "height": 16},
    "keys": [{"frame": 0, "head": {"position": [0, 1.6, 0], "orientation": [0, 0, 0, 1]},
                          "right": {"aim": {"position": [0, 1.6, 0]}}},
             {"frame": 2, "right": {"thumbstick_click": true}},
             {"frame": 4, "right": {"thumbstick_click": false}},
             {"frame": 6}]})";
  test::CliRun r = test::run_vxr("view --sample --headless --script " + test::shell_quote((dir / "teleport.json").string()),
                                 dir, 180);
  INFO("stdout: " << r.out << "\nstderr: " << r.err);
  REQUIRE(r.rc == 0);
  auto v = assets::sample_volume();
  REQUIRE(v.is_ok());
  const VolumePlacement placement{v->dims, v->voxel_size};
  const double scale = default_volume_transform(placement).scale;
  // As through the runtime: the volume's near face comes to 0.4 m before the head.
  char line[128];
  std::snprintf(line, sizeof line, "volume at (%.6f, %.6f, %.6f)", 0.0, 1.6, -0.4 - scale * 0.5 * placement.extent().y);
  CHECK(r.out.find(line) != std::string::npos);
}

TEST_CASE("card in a headset: vxr view --card --xr shows the card's picture in the first frame's eye") {
  const fs::path dir = test::scratch_dir("xr", "card_in_headset");
  const fs::path store = dir / "store";
  const std::string input = std::string(VXR_TESTDATA_DIR) + "/tiff/mri-stack-calibrated.tif";
  {
    fs::create_directories(store.parent_path());
    auto s = annotate::AnnotationStore::open(store.string(), true);
    REQUIRE(s.is_ok());
  }
  // A moved, turned and scaled volume seen from a chosen pose, 64x64 at 40 degrees.
  const fs::path scene = dir / "scene.json";
  REQUIRE(write_file_atomically(scene.string(),
                                R"({"transform": {"position": [4, -6, 10], "rotation": [0.9, 0.1, 0.3, 0.2], "scale": 1.3},
                                    "camera": {"eye": [40, -120, 150], "target": [0, 0, 0], "up": [0, 0, 1], "fov_y_deg": 40}})")
              .is_ok());
  test::CliRun r = test::run_vxr("render " + test::shell_quote(input) + " --settings " + test::shell_quote(scene.string()) +
                                     " --size 64x64 -o " + test::shell_quote((dir / "card.png").string()) +
                                     " --save-card " + test::shell_quote(store.string()),
                                 dir, 180);
  REQUIRE_MESSAGE(r.rc == 0, r.err);
  // The headset: its eyes 64x64 with the card's fov (+-20 degrees), no eye separation, so an eye
  // is the head; the head somewhere else, turned. UNORM swapchains: the dump holds the renderer's bytes.
  const std::string xr_dir = test::xr_out_dir("card_in_headset_runtime");
  std::string frames;
  for (int f = 0; f < 12; ++f) frames += (f ? "," : "") + std::to_string(f);
  test::use_test_runtime(xr_dir, R"({"view": {"width": 64, "height": 64, "ipd_m": 0,
      "fov_deg": {"left": -20, "right": 20, "up": 20, "down": -20}},
    "no_srgb": true, "dump_frames": [)" + frames + R"(],
    "keys": [{"frame": 0, "head": {"position": [0.3, 1.5, 0.2], "orientation": [0.1, 0.3, 0.05, 0.948]}}]})");
  r = test::run_vxr("view --card " + test::shell_quote(store.string() + ":1") + " --xr --frames 4", dir, 180);
  INFO("stdout: " << r.out << "\nstderr: " << r.err);
  REQUIRE(r.rc == 0);
  CHECK(r.out.find("using OpenXR") != std::string::npos);
  fs::path first;
  for (int f = 0; f < 12 && first.empty(); ++f) {
    char name[64];
    std::snprintf(name, sizeof name, "frame%06d_left.png", f);
    if (fs::exists(fs::path(xr_dir) / "dump" / name)) first = fs::path(xr_dir) / "dump" / name;
  }
  REQUIRE_MESSAGE(!first.empty(), "no eye image was dumped");
  auto eye = read_png(first.string());
  auto card = read_png((dir / "card.png").string());
  REQUIRE(eye.is_ok());
  REQUIRE(card.is_ok());
  REQUIRE(eye->width == card->width);
  REQUIRE(eye->height == card->height);
  int max_diff = 0;
  size_t differing = 0;
  for (size_t i = 0; i < eye->pixels.size(); ++i) {
    const int d = std::abs(int(eye->pixels[i]) - int(card->pixels[i]));
    max_diff = std::max(max_diff, d);
    differing += d != 0;
  }
  INFO("max difference " << max_diff << ", differing channels " << differing << " of " << eye->pixels.size());
  CHECK(test::looks_non_blank(*card));
  CHECK(max_diff <= 1);
  CHECK(differing * 100 <= eye->pixels.size());
  CHECK_MESSAGE(test::core_validation_messages(xr_dir).empty(), test::core_validation_messages(xr_dir));
}
