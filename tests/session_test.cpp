// One session for `vxr view` and `vxr render` (engine/render/volume_session.h):
// the same defaults, --channel, --timepoint and --settings resolve the same
// RenderSettings for both commands (and the CPU reference), and the two commands draw the same
// pixels for the same input and flags.
#include <doctest/doctest.h>

#include <filesystem>

#include "cli_runner.h"
#include "core/image.h"
#include "core/output_file.h"
#include "golden.h"
#include "render/volume_session.h"
#include "volume/load_dense.h"
#include "xr/view_command.h"

using namespace vxr;
using namespace vxr::test;
namespace fs = std::filesystem;

namespace {

// Three signed 8-bit channels, 439x167x5: small enough that the session's
// windows come from level 0, the whole volume, as the whole-volume reference's do.
const std::string kThreeChannels = std::string(VXR_TESTDATA_DIR) + "/ome-tiff/multi-channel-z-series.ome.tif";

std::string q(const fs::path& p) { return shell_quote(p.string()); }

VolumeSession open_ok(const SessionFlags& flags) {
  auto session = open_volume_session(kThreeChannels, flags);
  REQUIRE_MESSAGE(session.is_ok(), session.status().to_string());
  return std::move(session).value();
}

// The settings `vxr render --reference` resolves: the whole volume loaded, windows from it.
RenderSettings dense_settings(const SessionFlags& given, std::vector<uint32_t>* channels) {
  auto flags = complete_session_flags(given);
  REQUIRE(flags.is_ok());
  auto loaded = load_for_render(kThreeChannels, 2048, uint64_t(1) << 30);
  REQUIRE(loaded.is_ok());
  auto choice = choose_settings(*flags);
  REQUIRE(choice.is_ok());
  auto drawn = resolve_drawn_settings(*choice, *flags, kThreeChannels, uint32_t(loaded->channels.size()), 1,
                                      [&](uint32_t c) -> Result<std::pair<double, double>> {
                                        return percentile_window(loaded->channels[c]);
                                      });
  REQUIRE_MESSAGE(drawn.is_ok(), drawn.status().to_string());
  *channels = drawn->channels;
  return drawn->settings;
}

void write_text(const fs::path& path, const std::string& text) {
  REQUIRE(write_file_atomically(path.string(), text).is_ok());
}

}  // namespace

TEST_CASE("session: defaults, --channel and --settings resolve the same settings for the out-of-core renderer and the whole-volume reference") {
  const fs::path dir = scratch_dir("session", "resolve");
  auto loaded = load_for_render(kThreeChannels, 2048, uint64_t(1) << 30);
  REQUIRE(loaded.is_ok());
  REQUIRE(loaded->channels.size() == 3);

  // Defaults: every channel (up to 4), a colour each, each window from its own data.
  SessionFlags none;
  VolumeSession s = open_ok(none);
  CHECK(s.channels == std::vector<uint32_t>{0, 1, 2});
  CHECK(s.timepoint == 0);
  REQUIRE(s.settings.channels.size() == 3);
  const char* hues[3] = {"green", "magenta", "cyan"};
  for (size_t c = 0; c < 3; ++c) {
    CAPTURE(c);
    CHECK(s.settings.channels[c].colormap == hues[c]);
    const auto w = percentile_window(loaded->channels[c]);
    CHECK(s.settings.channels[c].window_lo == w.first);
    CHECK(s.settings.channels[c].window_hi == w.second);
  }
  CHECK(s.settings.density == default_view_settings().density);
  std::vector<uint32_t> dense_channels;
  CHECK(dense_settings(none, &dense_channels) == s.settings);
  CHECK(dense_channels == s.channels);

  // --channel 1: that channel alone, the single-channel colour, its own window.
  SessionFlags one;
  one.channel = "1";
  s = open_ok(one);
  CHECK(s.channels == std::vector<uint32_t>{1});
  REQUIRE(s.settings.channels.size() == 1);
  CHECK(s.settings.channels[0].colormap == default_view_settings().channels[0].colormap);
  CHECK(s.settings.channels[0].window_lo == percentile_window(loaded->channels[1]).first);
  CHECK(s.settings.channels[0].window_hi == percentile_window(loaded->channels[1]).second);
  CHECK(dense_settings(one, &dense_channels) == s.settings);
  CHECK(dense_channels == s.channels);

  // --settings (plain RenderSettings): its model and colour; a flag overrides the file.
  const fs::path file = dir / "mip.json";
  write_text(file, R"({"model": "mip", "density": 0.5, "channels": [{"colormap": "viridis"}]})");
  SessionFlags with_file;
  with_file.settings = file.string();
  s = open_ok(with_file);
  CHECK(s.settings.model == OpticalModel::kMip);
  CHECK(s.settings.density == 0.5);
  CHECK(s.settings.channels[0].colormap == "viridis");
  CHECK(s.settings.channels[1].colormap == "magenta");
  CHECK(dense_settings(with_file, &dense_channels) == s.settings);
  with_file.model = "minip";
  with_file.colormap = "gray";
  s = open_ok(with_file);
  CHECK(s.settings.model == OpticalModel::kMinIp);
  CHECK(s.settings.channels[0].colormap == "gray");

  // --iso V: the isosurface at V, and the iso model unless --model says
  // otherwise; without it the iso value is the window's middle.
  SessionFlags iso;
  iso.iso = "42.5";
  s = open_ok(iso);
  CHECK(s.settings.model == OpticalModel::kIsosurface);
  CHECK(s.settings.iso_value == 42.5);
  CHECK(dense_settings(iso, &dense_channels) == s.settings);
  iso.model = "mip";
  s = open_ok(iso);
  CHECK(s.settings.model == OpticalModel::kMip);
  CHECK(s.settings.iso_value == 42.5);
  SessionFlags iso_model;
  iso_model.model = "iso";
  s = open_ok(iso_model);
  CHECK(s.settings.iso_value == 0.5 * (s.settings.channels[0].window_lo + s.settings.channels[0].window_hi));

  // A Scene's channels and timepoint are choices too; --channel wins over them.
  const fs::path scene = dir / "scene.json";
  write_text(scene, R"({"channels": [2], "timepoint": 0, "render": {"model": "average"}})");
  SessionFlags with_scene;
  with_scene.settings = scene.string();
  s = open_ok(with_scene);
  CHECK(s.channels == std::vector<uint32_t>{2});
  CHECK(s.settings.model == OpticalModel::kAverage);
  with_scene.channel = "0,1";
  s = open_ok(with_scene);
  CHECK(s.channels == std::vector<uint32_t>{0, 1});

  // Bad choices: one line naming the flag and the input.
  SessionFlags bad;
  bad.channel = "5";
  SessionStep step = SessionStep::kSettings;
  auto r = open_volume_session(kThreeChannels, bad, &step);
  REQUIRE(!r.is_ok());
  CHECK(step == SessionStep::kChannels);
  CHECK(r.status().code() == ErrorCode::kInvalidArgument);
  CHECK(r.status().message() == "--channel: '5', but " + kThreeChannels + " has 3 channel(s) (0..2)");
  bad.channel = "";
  bad.timepoint = 1;
  r = open_volume_session(kThreeChannels, bad);
  REQUIRE(!r.is_ok());
  CHECK(r.status().message().find("--timepoint: 1, but " + kThreeChannels + " has 1 timepoint(s)") == 0);
  SessionFlags bad_iso;
  bad_iso.iso = "high";
  r = open_volume_session(kThreeChannels, bad_iso, &step);
  REQUIRE(!r.is_ok());
  CHECK(step == SessionStep::kSettings);
  CHECK(r.status().message() == "--iso: expected one number (data units), got 'high'");
  SessionFlags missing;
  missing.settings = (dir / "nowhere.json").string();
  r = open_volume_session(kThreeChannels, missing, &step);
  REQUIRE(!r.is_ok());
  CHECK(step == SessionStep::kSettings);
  CHECK(r.status().message().find("nowhere.json") != std::string::npos);
}

TEST_CASE("session: vxr view --channel --settings draws what vxr render draws, and the choices change the picture") {
  const fs::path dir = scratch_dir("session", "view_render");
  // A Scene seen from above the slices (the view's own start pose sees them edge on), its render settings
  // the Scene defaults; `mip.json` the same camera with another model and colour map.
  const std::string camera = R"("camera": {"eye": [0, 0, 700], "target": [0, 0, 0], "up": [0, 1, 0], "fov_y_deg": 40})";
  write_text(dir / "plain.json", "{" + camera + "}");
  write_text(dir / "mip.json", "{" + camera + R"(, "render": {"model": "mip", "channels": [{"colormap": "viridis"}]}})");
  const auto view = [&](const std::string& flags, const std::string& name) {
    const CliRun r = run_vxr("view " + q(kThreeChannels) + " --headless --frames 20 --width 64 --height 48 " + flags +
                                 " --png-dir " + q(dir / name),
                             dir, 300);
    INFO("vxr view " << flags << "\n" << r.out << r.err);
    REQUIRE(r.rc == 0);
    return read_bytes(dir / name / "last_view.png");
  };
  const auto render = [&](const std::string& flags, const std::string& name) {
    const CliRun r = run_vxr("render " + q(kThreeChannels) + " --size 64x48 " + flags + " -o " + q(dir / name), dir, 300);
    INFO("vxr render " << flags << "\n" << r.out << r.err);
    REQUIRE(r.rc == 0);
    return read_bytes(dir / name);
  };
  const std::string mip_flags = "--settings " + q(dir / "mip.json");
  const std::string c0 = view(mip_flags + " --channel 0", "c0"), c1 = view(mip_flags + " --channel 1", "c1");
  const std::string plain = view("--settings " + q(dir / "plain.json") + " --channel 1", "plain");
  auto shown = read_png((dir / "c1" / "last_view.png").string());
  REQUIRE(shown.is_ok());
  CHECK(looks_non_blank(*shown));
  CHECK(c0 != c1);     // another channel's data
  CHECK(plain != c1);  // the settings file's model and colour map
  // The same session through the other command: the same bytes.
  CHECK(render(mip_flags + " --channel 1", "c1_render.png") == c1);
  CHECK(render("--settings " + q(dir / "plain.json") + " --channel 1", "plain_render.png") == plain);
  CHECK(render(mip_flags + " --channel 2,0 --model ea", "c20_render.png") == view(mip_flags + " --channel 2,0 --model ea", "c20"));

  // A channel the input does not have: exit 2, one line naming the input.
  CliRun bad = run_vxr("view " + q(kThreeChannels) + " --headless --frames 1 --channel 3", dir, 120);
  CHECK(bad.rc == 2);
  CHECK(bad.err.find("--channel: '3', but " + kThreeChannels + " has 3 channel(s) (0..2)") != std::string::npos);
  bad = run_vxr("view " + q(kThreeChannels) + " --headless --frames 1 --settings " + q(dir / "nowhere.json"), dir, 120);
  CHECK(bad.rc == 2);
  CHECK(bad.err.find("nowhere.json") != std::string::npos);
}

TEST_CASE("view command: option errors are usage failures found before any volume is read, a run reports what it drew") {
  std::vector<std::string> info, notes;
  const xr::ViewReport report{[&](const std::string& line) { info.push_back(line); },
                              [&](const std::string& line) { notes.push_back(line); }};
  xr::ViewFailure failure = xr::ViewFailure::kWork;
  xr::ViewCommandOptions o;
  o.input = "/nonexistent/volume.tif";
  o.ui_script = "steps.json";  // the desktop's, without --desktop: refused before the missing input is noticed
  Status st = xr::run_view_command(o, report, &failure);
  REQUIRE_FALSE(st.is_ok());
  CHECK(failure == xr::ViewFailure::kUsage);
  CHECK(st.message().find("--ui-script runs in the desktop window") != std::string::npos);

  o = xr::ViewCommandOptions{};
  o.input = "/nonexistent/volume.tif";
  o.target = xr::TargetKind::kHeadless;
  failure = xr::ViewFailure::kWork;
  st = xr::run_view_command(o, report, &failure);
  REQUIRE_FALSE(st.is_ok());
  CHECK(failure == xr::ViewFailure::kUsage);  // a wrong path is the caller's
  CHECK(st.message().find("volume.tif") != std::string::npos);
  CHECK(info.empty());

  o = xr::ViewCommandOptions{};
  o.input = kThreeChannels;
  o.target = xr::TargetKind::kHeadless;
  o.frames = 2;
  o.width = 32;
  o.height = 24;
  st = xr::run_view_command(o, report, &failure);
  REQUIRE_MESSAGE(st.is_ok(), st.to_string());
  REQUIRE(info.size() == 3);
  CHECK(info[0] == "using headless (--headless)");
  CHECK(info[1].rfind("2 frames rendered on headless", 0) == 0);
  CHECK(info[2].rfind("volume at (", 0) == 0);
  bool shown = false;
  for (const std::string& n : notes) shown = shown || n == kThreeChannels + ": showing channel(s) 0,1,2 of timepoint 0 (of 3 channels, 1 timepoints)";
  CHECK(shown);
}
