// `vxr view [INPUT]`: explore a volume in a headset (OpenXR), a desktop
// window, or headless, and say which.
//
// Auto choice: OpenXR when a runtime answers and has a headset, else the
// desktop window when a display is there, else headless. --xr / --desktop /
// --headless force one; --frames N renders N frames and exits cleanly.
#include <cstdio>

#include "assets/assets.h"
#include "command.h"
#include "volume/load_dense.h"
#include "xr/headless/headless_target.h"
#include "xr/target_factory.h"
#include "xr/view_session.h"

namespace vxr::cli {
namespace {

struct Options {
  std::string input;
  bool sample = false;
  bool force_xr = false, force_desktop = false, force_headless = false;
  uint64_t frames = 0;
  std::string script;
  std::string png_dir;
  bool png_every_frame = false;
  bool lens_warp = false;
  bool stereo = false;
  std::string screenshot;
  bool mirror = false;
  uint32_t width = 0, height = 0;
};

// The whole-volume caster takes one 3D texture: a .vxc gives the finest
// pyramid level that fits, any other input is read whole and averaged down to
// fit (load_for_render, shared with `vxr render`); channel 0, timepoint 0.
Result<DenseVolume> load_input(const Options& o) {
  if (o.sample || o.input.empty()) return assets::sample_volume();
  VXR_ASSIGN_OR_RETURN(LoadedVolume loaded, load_for_render(o.input, 1024, uint64_t(1) << 30));
  for (const std::string& n : loaded.notes) std::fprintf(stderr, "vxr view: %s: %s\n", o.input.c_str(), n.c_str());
  if (loaded.channels.size() > 1)
    std::fprintf(stderr, "vxr view: %s: showing channel 0 of %zu\n", o.input.c_str(), loaded.channels.size());
  if (loaded.channels[0].dtype != DType::kU8 && loaded.channels[0].dtype != DType::kU16)
    return unsupported(o.input + ": vxr view shows u8 or u16 data, this is " + dtype_name(loaded.channels[0].dtype) +
                       "; convert it first");
  return std::move(loaded.channels[0]);
}

int run(const Options& o) {
  auto volume = load_input(o);
  if (!volume) {
    const ErrorCode c = volume.status().code();  // a wrong path or argument is a usage error
    return fail(volume.status(), c == ErrorCode::kInvalidArgument || c == ErrorCode::kNotFound ? kExitUsage
                                                                                                 : kExitFailure);
  }
  xr::TargetRequest req;
  req.kind = o.force_xr        ? xr::TargetKind::kOpenXr
             : o.force_desktop ? xr::TargetKind::kDesktop
             : o.force_headless ? xr::TargetKind::kHeadless
                                : xr::TargetKind::kAuto;
  if (!o.script.empty()) {
    std::string err;
    if (!xr::load_script(o.script, req.headless.script, err)) return fail(invalid_argument(err), kExitUsage);
  }
  if (o.width) req.headless.script.width = o.width;
  if (o.height) req.headless.script.height = o.height;
  req.headless.png_dir = o.png_dir;
  req.headless.png_every_frame = o.png_every_frame;
  if (o.frames) req.headless.end_frame = o.frames;
  req.desktop_stereo = o.stereo;
  req.desktop_screenshot = o.screenshot;
  req.mirror = o.mirror;
  req.max_eye_width = o.width;
  req.max_eye_height = o.height;

  auto choice = xr::choose_target(req);
  if (!choice) return fail(choice.status(), kExitFailure);
  std::printf("vxr view: %s\n", choice->reason.c_str());
  std::fflush(stdout);

  xr::ViewOptions vo;
  vo.frames = o.frames;
  vo.settings = xr::default_view_settings();
  vo.warp.enabled = o.lens_warp;
  const VolumePlacement placement{volume->dims, volume->voxel_size};
  auto stats = xr::run_view(choice->factory, *volume, vo, xr::default_volume_transform(placement));
  if (!stats) return fail(stats.status());
  std::printf("vxr view: %llu frames rendered on %s, %.2f ms mean, %.2f ms max per frame, %d restart(s)\n",
              static_cast<unsigned long long>(stats->frames_rendered), stats->target.c_str(), stats->mean_frame_ms,
              stats->max_frame_ms, stats->restarts);
  const auto& t = stats->transform;
  std::printf("vxr view: volume at (%.6f, %.6f, %.6f), scale %.9g m/unit\n", t.position.x, t.position.y,
              t.position.z, t.scale);
  return kExitOk;
}

}  // namespace

void add_view_command(CLI::App& app, Invocation& inv) {
  auto* cmd = app.add_subcommand("view", "explore a volume in a headset (OpenXR), a desktop window, or headless");
  auto o = std::make_shared<Options>();
  cmd->add_option("input", o->input,
                  "dataset to view: anything vxr imports, up to 1024 per side (default: the bundled sample)");
  cmd->add_flag("--sample", o->sample, "view the bundled sample volume (an MRI head)");
  auto* fx = cmd->add_flag("--xr", o->force_xr, "use OpenXR (fail if no runtime or headset)");
  auto* fd = cmd->add_flag("--desktop", o->force_desktop, "use a desktop window");
  auto* fh = cmd->add_flag("--headless", o->force_headless, "render without a display");
  fx->excludes(fd, fh);
  fd->excludes(fh);
  cmd->add_option("--frames", o->frames, "render N frames, then exit cleanly (0: until closed)")
      ->check(CLI::Range(uint64_t(0), uint64_t(10000000)));
  cmd->add_option("--script", o->script, "headless: pose script (JSON; see xr/script.h)");
  cmd->add_option("--png-dir", o->png_dir, "headless: write the eye images of the last frame here");
  cmd->add_flag("--png-every-frame", o->png_every_frame, "headless: write every frame's eye images");
  cmd->add_option("--width", o->width, "eye width in pixels (OpenXR: at most this)")->check(CLI::Range(1, 4096));
  cmd->add_option("--height", o->height, "eye height in pixels (OpenXR: at most this)")->check(CLI::Range(1, 4096));
  cmd->add_flag("--lens-warp", o->lens_warp, "cast rays on the lens-warped grid (denser at each eye's centre)");
  cmd->add_flag("--stereo", o->stereo, "desktop: side-by-side stereo");
  cmd->add_flag("--mirror", o->mirror, "OpenXR: also show both eyes in a desktop window");
  cmd->add_option("--screenshot", o->screenshot, "desktop/mirror: at exit, save what the X server shows in the window (PNG)");
  cmd->callback([&inv, o] { inv.run = [o] { return run(*o); }; });
}

}  // namespace vxr::cli
