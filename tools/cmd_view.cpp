// `vxr view [INPUT]`: explore a volume in a headset (OpenXR), a desktop
// window, or headless, and say which. Only flags live here: the session
// (source, settings) is render/volume_session.h, the frame loop
// xr/view_session.h.
//
// Auto choice: OpenXR when a runtime answers and has a headset, else the
// desktop window when a display is there, else headless. --xr / --desktop /
// --headless force one; --frames N renders N frames and exits cleanly.
#include <stdlib.h>

#include <cstdio>
#include <filesystem>
#include <optional>
#include <nlohmann/json.hpp>

#include "command.h"
#include "volume_flags.h"
#include "core/output_file.h"
#include "render/annotation_renderer.h"
#include "render/volume_session.h"
#include "xr/desktop/viewer_setup.h"
#include "xr/headless/headless_target.h"
#include "xr/headless/movie.h"
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
  double frame_budget_ms = 0.0, lod_bias = 0.0;
  std::string json;
  std::string movie;
  double fps = 30.0;
  bool no_ui = false;
  std::string ui_script;
  SessionFlags flags;  // shared with vxr render; its timepoint is shown first (the desktop viewer plays from it)
  std::string card;    // STORE:ID or ID
  bool lod_bias_given = false;
  std::string tool = "count", tool_class = "cell";  // the hands' starting tool and count class
  bool tool_given = false;
};

// The value range the window/level sliders span: the dtype's, or around the
// window for float data.
std::array<double, 2> slider_range(const VolumeInfo& info, const RenderSettings& s) {
  switch (info.dtype) {
    case DType::kU8: return {0.0, 255.0};
    case DType::kI8: return {-128.0, 127.0};
    case DType::kU16: return {0.0, 65535.0};
    case DType::kI16: return {-32768.0, 32767.0};
    case DType::kU32: return {0.0, 4294967295.0};
    case DType::kI32: return {-2147483648.0, 2147483647.0};
    case DType::kF32: break;
  }
  double lo = 0.0, hi = 1.0;
  for (const ChannelSettings& c : s.channels) {
    lo = std::min(lo, c.window_lo);
    hi = std::max(hi, c.window_hi);
  }
  const double pad = hi - lo;
  return {lo - pad, hi + pad};
}

// The desktop viewer's setup: panels over the session's settings, the UI
// script checked against them, the annotation store (--annotations or the project's) for the tools.
// `pose`: a card's (or a --settings Scene's) camera, where the window starts.
Result<std::shared_ptr<const xr::ViewerSetup>> viewer_setup(const Options& o, const VolumeSession& session,
                                                            const xr::VolumeTransform& transform,
                                                            const VolumePlacement& placement,
                                                            const std::optional<Scene>& pose) {
  auto setup = std::make_shared<xr::ViewerSetup>();
  const VolumeInfo& info = session.source->info();
  setup->dataset = o.sample || o.input.empty() ? std::string("sample (MRI head)")
                                               : std::filesystem::path(o.input).filename().string();
  if (setup->dataset.empty()) setup->dataset = o.input;  // a folder given with a trailing slash
  std::error_code ec;
  setup->scene.volume = o.sample || o.input.empty() || o.input.rfind("procedural:", 0) == 0
                            ? o.input
                            : std::filesystem::absolute(o.input, ec).string();
  setup->scene.render = session.settings;  // a card's or --settings' with the flags applied
  setup->scene.timepoint = session.timepoint;
  setup->scene.channels = session.channels;  // a card saved in the window restores the channels drawn
  if (auto vs = parse_voxel_size_flag(o.flags.voxel_size); vs.is_ok() && vs->has_value()) setup->scene.voxel_size = **vs;
  setup->timepoints = info.timepoints;
  setup->data_range = slider_range(info, session.settings);
  setup->placement = placement;
  setup->transform = transform;
  if (pose) setup->start_orbit = xr::scene_orbit(*pose, placement);
  for (uint32_t c : session.channels) {
    auto histogram = xr::coarse_histogram(*session.source, c, session.timepoint, setup->data_range);
    if (!histogram) return histogram.status();
    setup->histograms.push_back(std::move(histogram).value());
  }
  // --annotations (or the project's store): the viewer's tools edit it.
  const std::string& store_path = session.annotation_store;
  if (!store_path.empty()) {
    auto store = annotate::AnnotationStore::open(store_path, true);
    if (!store) return Status(store.status().code(), store_path + ": " + store.status().message());
    setup->store = std::move(store).value();
  }
  if (!o.ui_script.empty()) {
    const xr::ViewerState state(setup->scene, setup->timepoints, setup->data_range);
    auto script = xr::load_ui_script(o.ui_script, state, {o.input, o.ui_script, store_path}, setup->store != nullptr);
    if (!script) return script.status();
    setup->script = std::move(script).value();
  }
  return std::shared_ptr<const xr::ViewerSetup>(std::move(setup));
}

// --movie: a scratch folder for the frames, beside the movie ("<dir>/.<name>.frames.XXXXXX").
Result<std::string> movie_scratch_dir(const std::string& movie) {
  const std::filesystem::path out(movie);
  std::string templ = ((out.has_parent_path() ? out.parent_path() : std::filesystem::path(".")) /
                       ("." + out.filename().string() + ".frames.XXXXXX"))
                          .string();
  if (!::mkdtemp(templ.data())) return io_error(movie + ": cannot create a scratch folder for the frames beside it");
  return templ;
}

int run(const Options& given) {
  Options o = given;
  std::optional<Scene> pose;  // a card's, or a --settings Scene's with a camera: the headless view's camera and size
  if (!o.card.empty()) {
    if (!o.flags.colormap.empty() || !o.flags.window.empty() || !o.flags.model.empty() || o.flags.step != 0.0 ||
        !o.flags.channel.empty() || !o.flags.settings.empty())
      return fail(invalid_argument("--card restores the card's render settings; drop --colormap/--window/--model/--step/"
                                   "--channel/--settings (vxr render --card takes them as overrides)"),
                  kExitUsage);
    if (!o.movie.empty()) return fail(invalid_argument("--card and --movie: give one"), kExitUsage);
    if (o.flags.timepoint_given)
      return fail(invalid_argument("--card restores the card's timepoint; drop --timepoint"), kExitUsage);
    auto sc = load_card_scene(o.card, o.flags.annotations, o.input);
    if (!sc) {
      const ErrorCode c = sc.status().code();
      return fail(sc.status(), c == ErrorCode::kInvalidArgument || c == ErrorCode::kNotFound ? kExitUsage : kExitFailure);
    }
    if (o.input.empty() && !o.sample) o.input = sc->volume;
    if (!o.lod_bias_given) o.lod_bias = sc->lod_bias;
    if (sc->renderer == "dense")
      std::fprintf(stderr, "vxr view: note: card %s was drawn by the dense renderer; the view draws it out of core\n",
                   o.card.c_str());
    pose = *sc;
    o.flags.start = SettingsStart{*sc, /*is_scene=*/true, /*has_window=*/true};  // a card holds resolved windows
  }
  if (!o.flags.settings.empty()) {
    if (Status st = check_input(o.flags.settings); !st) return fail(st, kExitUsage);
  }
  // --settings read once (its camera is the headless view's too), a Scene's or card's choices adopted.
  auto completed = complete_session_flags(o.flags);
  if (!completed) return fail(completed.status(), kExitUsage);
  o.flags = std::move(completed).value();
  if (!pose && o.flags.start && o.flags.start->is_scene && o.flags.start->scene.has_camera && o.movie.empty() &&
      o.script.empty())
    pose = o.flags.start->scene;
  if (o.frame_budget_ms < 0.0) return fail(invalid_argument("--frame-budget-ms: must be > 0 milliseconds"), kExitUsage);
  if (!o.json.empty()) {
    const std::string inputs[] = {o.input};
    if (Status st = check_output(o.json, inputs, "--json"); !st) return fail(st, kExitUsage);
  }
  if (!o.movie.empty()) {
    const std::string inputs[] = {o.input, o.script};
    if (Status st = check_output(o.movie, inputs, "--movie"); !st) return fail(st, kExitUsage);
    if (std::filesystem::path(o.movie).extension() != ".mp4")
      return fail(invalid_argument("--movie " + o.movie + ": give a .mp4 name (for PNG frames use --png-dir)"),
                  kExitUsage);
    if (o.force_xr || o.force_desktop)
      return fail(invalid_argument("--movie renders headless; drop --xr/--desktop"), kExitUsage);
    if (!o.png_dir.empty()) return fail(invalid_argument("--movie and --png-dir: give one"), kExitUsage);
    if (xr::find_ffmpeg().empty())  // say so before rendering anything
      return fail(unsupported(o.movie + ": writing MP4 needs ffmpeg, which is not installed (apt-get install "
                                        "ffmpeg); or write the PNG sequence with --png-dir DIR --png-every-frame"));
  }
  if (!o.ui_script.empty() && !o.force_desktop)
    return fail(invalid_argument("--ui-script runs in the desktop window: add --desktop"), kExitUsage);
  if (!o.ui_script.empty() && o.no_ui) return fail(invalid_argument("--ui-script and --no-ui: give one"), kExitUsage);
  auto session = open_volume_session(o.sample ? "" : o.input, o.flags);
  if (!session) {
    const ErrorCode c = session.status().code();  // a wrong path or argument is a usage error
    return fail(session.status(), c == ErrorCode::kInvalidArgument || c == ErrorCode::kNotFound ? kExitUsage
                                                                                                  : kExitFailure);
  }
  if (o.tool_given && session->annotation_store.empty())
    return fail(invalid_argument("--tool/--class: the tools edit an annotation store; give --annotations STORE or a "
                                 "project"),
                kExitUsage);
  if (o.tool_class.empty()) return fail(invalid_argument("--class: give a class name"), kExitUsage);
  for (const std::string& n : session->notes)
    std::fprintf(stderr, "vxr view: %s: %s\n", o.input.c_str(), n.c_str());
  if (const VolumeInfo& info = session->source->info(); info.channels > 1 || info.timepoints > 1) {
    std::string shown;
    for (uint32_t c : session->channels) shown += (shown.empty() ? "" : ",") + std::to_string(c);
    std::fprintf(stderr, "vxr view: %s: showing channel(s) %s of timepoint %u (of %u channels, %u timepoints)\n",
                 o.input.c_str(), shown.c_str(), unsigned(session->timepoint), unsigned(info.channels),
                 unsigned(info.timepoints));
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
  std::string movie_frames;
  if (!o.movie.empty()) {
    auto dir = movie_scratch_dir(o.movie);
    if (!dir) return fail(dir.status());
    movie_frames = *dir;
    req.kind = xr::TargetKind::kHeadless;
    req.headless.png_dir = movie_frames;
    req.headless.png_every_frame = true;
    req.headless.stereo = false;  // one view from the head: the camera
  }
  if (o.frames) req.headless.end_frame = o.frames;
  req.desktop_stereo = o.stereo;
  req.desktop_screenshot = o.screenshot;
  req.mirror = o.mirror;
  req.max_eye_width = o.width;
  req.max_eye_height = o.height;

  const VolumeInfo& info = session->source->info();
  const VolumePlacement placement{{uint32_t(info.dims[0]), uint32_t(info.dims[1]), uint32_t(info.dims[2])},
                                  info.voxel_size};
  const xr::VolumeTransform start = xr::default_volume_transform(placement);
  if (!o.no_ui && o.movie.empty() && !o.force_xr && !o.force_headless) {
    auto setup = viewer_setup(o, *session, start, placement, pose);
    if (!setup) {
      const ErrorCode c = setup.status().code();
      return fail(setup.status(), c == ErrorCode::kInvalidArgument || c == ErrorCode::kNotFound ? kExitUsage
                                                                                                  : kExitFailure);
    }
    req.viewer = *setup;
    // The window opens at the size it had last time (1280x800 at first) unless given.
    if (!o.width && !o.height && !o.stereo) {
      const std::string config = xr::viewer_config_path();
      auto size = config.empty() ? Result<xr::WindowGeometry>(xr::WindowGeometry{}) : xr::load_window_geometry(config);
      if (!size) std::fprintf(stderr, "vxr view: %s (using 1280x800)\n", size.status().message().c_str());
      const xr::WindowGeometry g = size ? *size : xr::WindowGeometry{};
      req.headless.script.width = g.width;
      req.headless.script.height = g.height;
    }
  }

  if (pose) {
    // One view with the card's (or --settings Scene's) camera and size, as
    // vxr render draws it (a headset or window keeps its own eye size).
    req.headless.stereo = false;
    if (!o.width && pose->viewport[0] > 0) req.headless.script.width = pose->viewport[0];
    if (!o.height && pose->viewport[1] > 0) req.headless.script.height = pose->viewport[1];
    req.headless.camera = scene_camera(*pose, placement, info.dims[2] == 1);
  }

  auto choice = xr::choose_target(req);
  if (!choice) return fail(choice.status(), kExitFailure);
  std::printf("vxr view: %s\n", choice->reason.c_str());
  std::fflush(stdout);

  xr::ViewOptions vo;
  vo.frames = o.frames;
  vo.settings = session->settings;
  vo.channels = session->channels;
  vo.warp.enabled = o.lens_warp;
  vo.frame.lod.lod_bias = o.lod_bias;
  vo.frame.lod.timepoint = session->timepoint;
  vo.frame_budget_ms = o.frame_budget_ms;
  // A headset keeps its own head pose and fov: the volume is placed so the head
  // sees what the card's (or a --settings Scene's) camera saw; headless draws the camera itself.
  if (pose && choice->kind == xr::TargetKind::kOpenXr) vo.place_for_camera = req.headless.camera;
  // The desktop viewer holds the store open itself (its tools edit it) and draws its markers over the volume.
  const bool viewer_has_store = choice->kind == xr::TargetKind::kDesktop && req.viewer && req.viewer->store;
  if (viewer_has_store && o.tool_given)
    std::fprintf(stderr, "vxr view: note: --tool/--class set the controllers' tools; the window's tools panel picks "
                         "its own\n");
  // Otherwise the session holds it (the one opened for a window not chosen, one LevelDB lock):
  // the hands' tools edit it and it is drawn from there.
  if (!session->annotation_store.empty() && !viewer_has_store) {
    vo.tool_store = req.viewer ? req.viewer->store : nullptr;
    if (!vo.tool_store) {
      auto store = annotate::AnnotationStore::open(session->annotation_store, false);
      if (!store) return fail(store.status());
      vo.tool_store = std::move(store).value();
    }
    vo.hand_tools.tool = *annotate::tool_from_name(o.tool);  // checked by the flag
    vo.hand_tools.count_class = o.tool_class;
    vo.on_tool_report = [](const std::string& line) {
      std::printf("vxr view: %s\n", line.c_str());
      std::fflush(stdout);
    };
  }
  auto stats = xr::run_view(choice->factory, session->source, vo, start);
  if (!stats) return fail(stats.status());
  if (!o.movie.empty()) {
    if (Status st = xr::encode_movie(movie_frames, o.fps, o.movie); !st) return fail(st);
    std::error_code ec;
    std::filesystem::remove_all(movie_frames, ec);
    std::printf("vxr view: movie %s: %llu frames at %.6g fps\n", o.movie.c_str(),
                static_cast<unsigned long long>(stats->frames_rendered), o.fps);
  }
  if (!o.json.empty()) {
    nlohmann::json j = xr::view_stats_json(*stats, vo);
    j["input"] = session->description;
    if (Status st = write_file_atomically(o.json, j.dump(2) + "\n"); !st) return fail(st);
  }
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
                  "dataset to view: a .vxc, anything vxr imports, or procedural:vessels:SIDE (default: the bundled "
                  "sample)");
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
  cmd->add_option("--frame-budget-ms", o->frame_budget_ms,
                  "let the LOD bias follow the frame time towards this many milliseconds");
  cmd->add_option("--lod-bias", o->lod_bias, "log2 voxel-to-pixel ratio (start value with --frame-budget-ms)");
  cmd->add_option("--json", o->json,
                  "write frame figures here: p50/p99 frame ms, frames complete, pipelines after frame 1, readbacks");
  cmd->add_option("--movie", o->movie,
                  "headless: render the pose script's camera path (one view) and write it as an MP4 (needs ffmpeg)");
  cmd->add_option("--fps", o->fps, "--movie: frames per second (default 30)")->check(CLI::Range(0.001, 1000.0));
  cmd->add_flag("--no-ui", o->no_ui, "desktop: the bare window, without panels");
  cmd->add_option("--ui-script", o->ui_script,
                  "desktop: run this scripted session (JSON list of steps: viewer commands, play/pause, screenshot "
                  "PATH, count, measure, tool, click, drag, finish, remove, card, keyframe, export-movie; see "
                  "xr/desktop/ui_script.h), then close");
  add_annotations_option(cmd, o->flags.annotations);
  cmd->add_option("--tool", o->tool, "the right trigger's starting tool (headset, pose script; the menu button cycles)")
      ->check(CLI::IsMember({"count", "measure", "trace", "track", "roi"}));
  cmd->add_option("--class", o->tool_class, "the class count markers get (default cell)");
  cmd->add_option("--card", o->card,
                  "STORE:ID (or ID of the --annotations store or the input project's): restore a card's volume, "
                  "settings, channels, timepoint and annotations; its camera: headless exactly (and its size), "
                  "in the window as an orbit, in a headset by placing the volume so the first frame's head "
                  "pose is the card's camera");
  add_session_flags(cmd, &o->flags);
  cmd->callback([&inv, o, cmd] {
    o->lod_bias_given = cmd->count("--lod-bias") > 0;
    note_session_flags(cmd, &o->flags);
    o->tool_given = cmd->count("--tool") + cmd->count("--class") > 0;
    inv.run = [o] { return run(*o); };
  });
}

}  // namespace vxr::cli
