// `vxr view [INPUT]`: explore a volume in a headset (OpenXR), a desktop
// window, or headless, and say which. Only flags live here: what they do is
// xr/view_command.h (the session: render/volume_session.h, the frame loop:
// xr/view_session.h).
//
// Auto choice: OpenXR when a runtime answers and has a headset, else the
// desktop window when a display is there, else headless. --xr / --desktop /
// --headless force one; --frames N renders N frames and exits cleanly.
#include <cstdio>

#include "command.h"
#include "volume_flags.h"
#include "xr/view_command.h"

namespace vxr::cli {
namespace {

struct Options {
  xr::ViewCommandOptions view;
  bool force_xr = false, force_desktop = false, force_headless = false;
};

int run(const Options& given) {
  xr::ViewCommandOptions o = given.view;
  o.target = given.force_xr        ? xr::TargetKind::kOpenXr
             : given.force_desktop ? xr::TargetKind::kDesktop
             : given.force_headless ? xr::TargetKind::kHeadless
                                    : xr::TargetKind::kAuto;
  const xr::ViewReport report{[](const std::string& line) {
                                std::printf("vxr view: %s\n", line.c_str());
                                std::fflush(stdout);
                              },
                              [](const std::string& line) { std::fprintf(stderr, "vxr view: %s\n", line.c_str()); }};
  xr::ViewFailure failure = xr::ViewFailure::kWork;
  if (Status st = xr::run_view_command(o, report, &failure); !st)
    return fail(st, failure == xr::ViewFailure::kUsage ? kExitUsage : kExitFailure);
  return kExitOk;
}

}  // namespace

void add_view_command(CLI::App& app, Invocation& inv) {
  auto* cmd = app.add_subcommand("view", "explore a volume in a headset (OpenXR), a desktop window, or headless");
  auto o = std::make_shared<Options>();
  cmd->add_option("input", o->view.input,
                  "dataset to view: a .vxc, anything vxr imports, or procedural:vessels:SIDE (default: the bundled "
                  "sample)");
  cmd->add_flag("--sample", o->view.sample, "view the bundled sample volume (an MRI head)");
  auto* fx = cmd->add_flag("--xr", o->force_xr, "use OpenXR (fail if no runtime or headset)");
  auto* fd = cmd->add_flag("--desktop", o->force_desktop, "use a desktop window");
  auto* fh = cmd->add_flag("--headless", o->force_headless, "render without a display");
  fx->excludes(fd, fh);
  fd->excludes(fh);
  cmd->add_option("--frames", o->view.frames, "render N frames, then exit cleanly (0: until closed)")
      ->check(CLI::Range(uint64_t(0), uint64_t(10000000)));
  cmd->add_option("--script", o->view.script, "headless: pose script (JSON; see xr/script.h)");
  cmd->add_option("--png-dir", o->view.png_dir, "headless: write the eye images of the last frame here");
  cmd->add_flag("--png-every-frame", o->view.png_every_frame, "headless: write every frame's eye images");
  cmd->add_option("--width", o->view.width, "eye width in pixels (OpenXR: at most this)")->check(CLI::Range(1, 4096));
  cmd->add_option("--height", o->view.height, "eye height in pixels (OpenXR: at most this)")->check(CLI::Range(1, 4096));
  cmd->add_flag("--lens-warp", o->view.lens_warp, "cast rays on the lens-warped grid (denser at each eye's centre)");
  cmd->add_flag("--stereo", o->view.stereo, "desktop: side-by-side stereo");
  cmd->add_flag("--mirror", o->view.mirror, "OpenXR: also show both eyes in a desktop window");
  cmd->add_option("--screenshot", o->view.screenshot, "desktop/mirror: at exit, save what the X server shows in the window (PNG)");
  cmd->add_option("--frame-budget-ms", o->view.frame_budget_ms,
                  "let the LOD bias follow the frame time towards this many milliseconds");
  cmd->add_option("--lod-bias", o->view.lod_bias, "log2 voxel-to-pixel ratio (start value with --frame-budget-ms)");
  cmd->add_flag("--no-skip", o->view.no_skip, "march empty space too (no brick or cell skipping; same image, for timing)");
  cmd->add_option("--json", o->view.json,
                  "write frame figures here: p50/p99 frame ms, frames complete, pipelines after frame 1, readbacks");
  cmd->add_option("--movie", o->view.movie,
                  "headless: render the pose script's camera path (one view) and write it as an MP4 (needs ffmpeg)");
  cmd->add_option("--fps", o->view.fps, "--movie: frames per second (default 30)")->check(CLI::Range(0.001, 1000.0));
  cmd->add_flag("--no-ui", o->view.no_ui, "desktop: the bare window, without panels");
  cmd->add_option("--ui-script", o->view.ui_script,
                  "desktop: run this scripted session (JSON list of steps: viewer commands, play/pause, screenshot "
                  "PATH, count, measure, tool, click, drag, finish, remove, card, panel-card, restore-card, keyframe, "
                  "export-movie, and last, open PATH; see xr/desktop/ui_script.h), then close");
  add_annotations_option(cmd, o->view.flags.annotations);
  cmd->add_option("--tool", o->view.tool, "the right trigger's starting tool (headset, pose script; the menu button cycles)")
      ->check(CLI::IsMember({"count", "measure", "trace", "track", "roi"}));
  cmd->add_option("--class", o->view.tool_class, "the class count markers get (default cell)");
  cmd->add_option("--card", o->view.card,
                  "STORE:ID (or ID of the --annotations store or the input project's): restore a card's volume, "
                  "settings, channels, timepoint and annotations; its camera: headless exactly (and its size), "
                  "in the window as an orbit, in a headset by placing the volume so the first frame's head "
                  "pose is the card's camera");
  add_session_flags(cmd, &o->view.flags);
  cmd->callback([&inv, o, cmd] {
    o->view.lod_bias_given = cmd->count("--lod-bias") > 0;
    note_session_flags(cmd, &o->view.flags);
    o->view.tool_given = cmd->count("--tool") + cmd->count("--class") > 0;
    inv.run = [o] { return run(*o); };
  });
}

}  // namespace vxr::cli
