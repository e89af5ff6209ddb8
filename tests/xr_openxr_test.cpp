// vxr's OpenXR path end to end, through Debian's Khronos loader, the
// XR_APILAYER_LUNARG_core_validation layer and the test runtime
// (xr/test_runtime), on the same Vulkan device as every other test.
#include <doctest/doctest.h>

#include <cmath>
#include <cstring>

#include "assets/assets.h"
#include "golden.h"
#include "gpu_fixture.h"
#include "volume/dense_chunk_source.h"
#include "xr/openxr/openxr_target.h"
#include "xr/target_factory.h"
#include "xr/view_session.h"
#include "xr_test_util.h"

using namespace vxr;
using namespace vxr::xr;

namespace {

DenseVolume sample() {
  auto v = assets::sample_volume();
  REQUIRE(v.is_ok());
  return std::move(v).value();
}

TargetFactory openxr() {
  return []() -> Result<std::unique_ptr<FrameTarget>> {
    auto t = OpenXrTarget::create({});
    if (!t) return t.status();
    return std::unique_ptr<FrameTarget>(std::move(t).value());
  };
}

Result<ViewStats> run(const DenseVolume& v, uint64_t frames, bool skip_empty = true, uint32_t chunk_size = 64) {
  ViewOptions o;
  o.frames = frames;
  o.settings = default_view_settings();
  o.frame.lod.skip_empty = skip_empty;
  auto source = DenseChunkSource::create({v}, chunk_size);
  if (!source) return source.status();
  return run_view(openxr(), *source, o, default_volume_transform({v.dims, v.voxel_size}));
}

bool has_state(const nlohmann::json& session, const std::string& state) {
  for (const auto& s : session["states"])
    if (s == state) return true;
  return false;
}

}  // namespace

TEST_CASE("openxr: a session reaches FOCUSED, renders 32 stereo frames, eye images match goldens") {
  test::GpuTestScope scope;
  const std::string dir = test::xr_out_dir("golden");
  // An asymmetric fov and a head that drifts and turns: off-axis views, poses per frame.
  // UNORM swapchains: the golden holds the renderer's bytes. Into an sRGB
  // swapchain lavapipe encodes with the CPU's approximate rsqrt
  // (lp_build_linear_to_srgb), whose last bits differ between CPU models (one
  // machine: 21 and 25 pixels off by 1); frame_path_test checks that encoding.
  test::use_test_runtime(dir, R"({
    "view": {"width": 128, "height": 128, "ipd_m": 0.064,
             "fov_deg": {"left": -45, "right": 40, "up": 42, "down": -45}},
    "no_srgb": true,
    "keys": [{"frame": 0, "head": {"position": [0, 1.6, 0], "orientation": [0, 0, 0, 1]}},
             {"frame": 40, "head": {"position": [0.05, 1.62, -0.08], "orientation": [0, 0.0871557, 0, 0.9961947]}}],
    "dump_frames": [32]})");
  const DenseVolume v = sample();
  auto stats = run(v, 32);
  REQUIRE_MESSAGE(stats.is_ok(), stats.status().to_string());
  CHECK(stats->frames_rendered == 32);
  CHECK(stats->restarts == 0);
  CHECK(stats->target.find("STAGE space") != std::string::npos);
  CHECK(stats->target.find("depth layers") != std::string::npos);

  const nlohmann::json report = test::runtime_report(dir);
  REQUIRE(report.size() == 1);
  CHECK(has_state(report[0], "FOCUSED"));
  CHECK(has_state(report[0], "EXITING"));  // orderly exit: STOPPING -> xrEndSession -> IDLE -> EXITING
  CHECK(report[0]["frames_with_layers"].get<int>() >= 30);
  CHECK(report[0]["frames_with_depth"] == report[0]["frames_with_layers"]);
  CHECK(report[0]["layer_space"] == "STAGE");

  for (const char* eye : {"left", "right"}) {
    auto img = read_png(dir + "/dump/frame000032_" + eye + ".png");
    REQUIRE_MESSAGE(img.is_ok(), img.status().to_string());
    CHECK(test::looks_non_blank(*img));
    auto r = test::check_golden(std::string("xr_openxr_frame32_") + eye, *img, stats->device_fingerprint, 2,
                                "the sample head seen through the test runtime's scripted headset at frame 32 "
                                "(asymmetric fov, head turned 10 degrees left): read back from the swapchain");
    INFO(r.message);
    CHECK(r.passed);
  }
  CHECK_MESSAGE(test::core_validation_messages(dir).empty(), test::core_validation_messages(dir));
}

TEST_CASE("openxr: with skipping off (vxr view --no-skip) the headset's eyes are the same bytes, no brick skipped") {
  test::GpuTestScope scope;
  // Mostly air: a bright ball in one corner of a 128^3 volume.
  DenseVolume v;
  v.dims = {128, 128, 128};
  v.data.resize(v.voxel_count());
  for (uint32_t z = 0, i = 0; z < 128; ++z)
    for (uint32_t y = 0; y < 128; ++y)
      for (uint32_t x = 0; x < 128; ++x, ++i) {
        const double d = std::sqrt(double((x - 30) * (x - 30) + (y - 34) * (y - 34) + (z - 40) * (z - 40)));
        v.data[i] = d < 24.0 ? uint8_t(255.0 * (1.0 - d / 24.0)) : 0;
      }
  std::vector<ImageRgba8> eyes;
  std::vector<uint64_t> skipped;
  for (bool skip : {true, false}) {
    INFO("skipping " << (skip ? "on" : "off"));
    const std::string dir = test::xr_out_dir(skip ? "skip_on" : "skip_off");
    test::use_test_runtime(dir, R"({"view": {"width": 96, "height": 96}, "no_srgb": true, "dump_frames": [4]})");
    auto stats = run(v, 4, skip, 16);
    REQUIRE_MESSAGE(stats.is_ok(), stats.status().to_string());
    skipped.push_back(stats->bricks_skipped_empty);
    for (const char* eye : {"left", "right"}) {
      auto img = read_png(dir + "/dump/frame000004_" + eye + ".png");
      REQUIRE_MESSAGE(img.is_ok(), img.status().to_string());
      CHECK(test::looks_non_blank(*img));
      eyes.push_back(std::move(img).value());
    }
    CHECK(test::core_validation_messages(dir).empty());
  }
  // The air is skipped with skipping on, and only then.
  CHECK(skipped[0] > 0);
  CHECK(skipped[1] == 0);
  REQUIRE(eyes.size() == 4);
  CHECK(eyes[0].pixels == eyes[2].pixels);
  CHECK(eyes[1].pixels == eyes[3].pixels);
}

TEST_CASE("openxr: scripted grab-move and two-hand pinch through the runtime move and scale the volume") {
  test::GpuTestScope scope;
  const std::string dir = test::xr_out_dir("interaction");
  test::use_test_runtime(dir, R"({
    "view": {"width": 32, "height": 32},
    "profile": "/interaction_profiles/valve/index_controller",
    "keys": [
      {"frame": 0,  "left": {"grip": {"position": [-0.1, 1.4, -0.4]}, "squeeze": 0},
                    "right": {"grip": {"position": [0.1, 1.4, -0.4]}, "squeeze": 0}},
      {"frame": 4,  "left": {"squeeze": 1}},
      {"frame": 14, "left": {"grip": {"position": [0.0, 1.5, -0.4]}}},
      {"frame": 16, "left": {"squeeze": 0}},
      {"frame": 20, "left": {"grip": {"position": [-0.1, 1.4, -0.4]}, "squeeze": 1}, "right": {"squeeze": 1}},
      {"frame": 30, "left": {"grip": {"position": [-0.2, 1.4, -0.4]}}, "right": {"grip": {"position": [0.2, 1.4, -0.4]}}}
    ]})");
  const DenseVolume v = sample();
  const xr::VolumeTransform t0 = default_volume_transform({v.dims, v.voxel_size});
  auto stats = run(v, 36);
  REQUIRE_MESSAGE(stats.is_ok(), stats.status().to_string());
  const xr::VolumeTransform& t = stats->transform;
  // One hand moved the volume by (0.1, 0.1, 0); the pinch doubled the hand distance
  // about the fixed midpoint (0, 1.4, -0.4): x' = mid + 2 (x - mid).
  const glm::dvec3 moved = t0.position + glm::dvec3(0.1, 0.1, 0.0);
  const glm::dvec3 mid(0.0, 1.4, -0.4);
  const glm::dvec3 expected = mid + 2.0 * (moved - mid);
  CHECK(t.position.x == doctest::Approx(expected.x).epsilon(1e-5));
  CHECK(t.position.y == doctest::Approx(expected.y).epsilon(1e-5));
  CHECK(t.position.z == doctest::Approx(expected.z).epsilon(1e-5));
  CHECK(t.scale == doctest::Approx(2.0 * t0.scale).epsilon(1e-5));
  CHECK(glm::length(glm::dvec4(t.orientation.x - t0.orientation.x, t.orientation.y - t0.orientation.y,
                               t.orientation.z - t0.orientation.z, t.orientation.w - t0.orientation.w)) < 1e-6);
  const nlohmann::json report = test::runtime_report(dir);
  REQUIRE(report.size() == 1);
  CHECK(report[0]["profile"] == "/interaction_profiles/valve/index_controller");
  CHECK(report[0]["haptic_pulses"] == 3);  // left grab, then both hands for the pinch
  CHECK(test::core_validation_messages(dir).empty());
}

TEST_CASE("openxr: every suggested controller profile delivers grab, grip pose and haptics") {
  test::GpuTestScope scope;
  const DenseVolume v = sample();
  const xr::VolumeTransform t0 = default_volume_transform({v.dims, v.voxel_size});
  for (const char* profile : {"khr/simple_controller", "oculus/touch_controller", "htc/vive_controller",
                              "valve/index_controller", "microsoft/motion_controller"}) {
    INFO(std::string(profile));
    const std::string dir = test::xr_out_dir(std::string("profile_") + (std::strchr(profile, '/') + 1));
    test::use_test_runtime(dir, std::string(R"({"view": {"width": 16, "height": 16},
      "profile": "/interaction_profiles/)") + profile + R"(",
      "keys": [{"frame": 0, "right": {"grip": {"position": [0.1, 1.4, -0.4]}, "squeeze": 0}},
               {"frame": 3, "right": {"squeeze": 1}},
               {"frame": 8, "right": {"grip": {"position": [0.2, 1.4, -0.4]}}}]})");
    auto stats = run(v, 10);
    REQUIRE_MESSAGE(stats.is_ok(), stats.status().to_string());
    CHECK(stats->transform.position.x == doctest::Approx(t0.position.x + 0.1).epsilon(1e-5));
    CHECK(stats->target.find(std::string("controllers /interaction_profiles/") + profile) != std::string::npos);
    const nlohmann::json report = test::runtime_report(dir);
    REQUIRE(report.size() == 1);
    CHECK(report[0]["haptic_pulses"] == 1);
    CHECK(test::core_validation_messages(dir).empty());
  }
}

TEST_CASE("openxr: without a STAGE space the session uses LOCAL, without the depth extension no depth layers") {
  test::GpuTestScope scope;
  const std::string dir = test::xr_out_dir("local");
  test::use_test_runtime(dir, R"({"view": {"width": 32, "height": 32}, "no_stage": true, "no_depth": true})");
  auto stats = run(sample(), 3);
  REQUIRE_MESSAGE(stats.is_ok(), stats.status().to_string());
  CHECK(stats->target.find("LOCAL space") != std::string::npos);
  CHECK(stats->target.find("no depth layers") != std::string::npos);
  const nlohmann::json report = test::runtime_report(dir);
  REQUIRE(report.size() == 1);
  CHECK(report[0]["layer_space"] == "LOCAL");
  CHECK(report[0]["frames_with_layers"] == 3);
  CHECK(report[0]["frames_with_depth"] == 0);
  CHECK(test::core_validation_messages(dir).empty());
}

TEST_CASE("openxr: a lost session is rebuilt by the restart loop and the frame count continues") {
  test::GpuTestScope scope;
  const std::string dir = test::xr_out_dir("loss");
  test::use_test_runtime(dir, R"({"view": {"width": 32, "height": 32}, "session_loss_at_frame": 6})");
  auto stats = run(sample(), 10);
  REQUIRE_MESSAGE(stats.is_ok(), stats.status().to_string());
  CHECK(stats->restarts == 1);
  CHECK(stats->frames_rendered == 10);
  const nlohmann::json report = test::runtime_report(dir);
  REQUIRE(report.size() == 2);
  CHECK(report[0]["lost"] == true);
  CHECK(has_state(report[0], "LOSS_PENDING"));
  CHECK(has_state(report[1], "FOCUSED"));
  CHECK(has_state(report[1], "EXITING"));
  CHECK(test::core_validation_messages(dir).empty());
}

TEST_CASE("openxr: no headset: the probe says so and vxr view falls back") {
  const std::string dir = test::xr_out_dir("no_headset");
  test::use_test_runtime(dir, R"({"no_headset": true})");
  auto probe = probe_openxr();
  REQUIRE(!probe.is_ok());
  CHECK(probe.status().message().find("XR_ERROR_FORM_FACTOR_UNAVAILABLE") != std::string::npos);
  unsetenv("DISPLAY");
  TargetRequest req;
  auto choice = choose_target(req);
  REQUIRE(choice.is_ok());
  CHECK(choice->kind == TargetKind::kHeadless);
  CHECK(choice->reason.find("no OpenXR headset") != std::string::npos);
  CHECK(choice->reason.find("DISPLAY") != std::string::npos);
}

TEST_CASE("openxr: core_validation is really in front of the runtime (negative control)") {
  const std::string dir = test::xr_out_dir("core_validation_control");
  test::use_test_runtime(dir, R"({})");
  XrInstanceCreateInfo ci{XR_TYPE_INSTANCE_CREATE_INFO};
  std::strcpy(ci.applicationInfo.applicationName, "vxr-test");
  ci.applicationInfo.apiVersion = XR_CURRENT_API_VERSION;
  const char* ext = XR_KHR_VULKAN_ENABLE2_EXTENSION_NAME;
  ci.enabledExtensionCount = 1;
  ci.enabledExtensionNames = &ext;
  XrInstance instance = XR_NULL_HANDLE;
  REQUIRE(xrCreateInstance(&ci, &instance) == XR_SUCCESS);
  XrSystemGetInfo bad{XR_TYPE_SESSION_CREATE_INFO};  // wrong structure type on purpose
  bad.formFactor = XR_FORM_FACTOR_HEAD_MOUNTED_DISPLAY;
  XrSystemId system = XR_NULL_SYSTEM_ID;
  CHECK(XR_FAILED(xrGetSystem(instance, &bad, &system)));
  xrDestroyInstance(instance);
  CHECK(!test::core_validation_messages(dir).empty());
}
