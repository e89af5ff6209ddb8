#include "xr/view_command.h"

#include <cstdio>
#include <filesystem>
#include <nlohmann/json.hpp>
#include <optional>

#include "annotate/annotation_store.h"
#include "core/output_file.h"
#include "render/card_scene.h"
#include "annotate/tools.h"
#include "xr/desktop/ui_script.h"
#include "xr/desktop/viewer_setup.h"
#include "xr/desktop/viewer_state.h"
#include "xr/headless/movie.h"
#include "xr/script.h"
#include "xr/view_session.h"
#include "xr/volume_transform.h"

namespace vxr::xr {
namespace {

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

bool is_usage_code(const Status& s) {
  return s.code() == ErrorCode::kInvalidArgument || s.code() == ErrorCode::kNotFound;  // a wrong path or argument
}

// One run of `vxr view`, step by step; every step that fails says whether the
// options or the work were at fault.
class ViewCommand {
 public:
  ViewCommand(ViewCommandOptions options, const ViewReport& report, std::shared_ptr<std::string> open_request)
      : o_(std::move(options)), report_(report), open_request_(std::move(open_request)) {}

  Status run();
  ViewFailure failed() const { return failed_; }

 private:
  Status usage(Status s) {
    failed_ = ViewFailure::kUsage;
    return s;
  }
  Status work(Status s) {
    failed_ = ViewFailure::kWork;
    return s;
  }
  Status by_code(Status s) { return is_usage_code(s) ? usage(std::move(s)) : work(std::move(s)); }
  bool forced(TargetKind k) const { return o_.target == k; }

  Status start_from_card();
  Status start_from_settings();
  Status check_outputs();
  Status open_session();
  Status build_request();
  Status build_viewer_setup();
  Status choose();
  Status hand_tools(ViewOptions& vo);
  Status write_outputs(const ViewStats& stats, const ViewOptions& vo);

  ViewCommandOptions o_;
  const ViewReport& report_;
  ViewFailure failed_ = ViewFailure::kWork;
  std::optional<Scene> pose_;  // a card's, or a --settings Scene's with a camera: the headless view's camera and size
  std::optional<VolumeSession> session_;
  VolumePlacement placement_{};
  VolumeTransform start_{};
  TargetRequest req_;
  std::string movie_frames_;
  std::optional<TargetChoice> choice_;
  std::shared_ptr<std::string> open_request_;  // the window's Open panel writes the next input here
};

// --card: the card's Scene is the start (settings, channels, timepoint, annotations) and its pose the headless view's.
Status ViewCommand::start_from_card() {
  if (o_.card.empty()) return Status::ok();
  const SessionFlags& f = o_.flags;
  if (!f.colormap.empty() || !f.window.empty() || !f.model.empty() || f.step != 0.0 || !f.channel.empty() ||
      !f.settings.empty())
    return usage(invalid_argument("--card restores the card's render settings; drop --colormap/--window/--model/--step/"
                                  "--channel/--settings (vxr render --card takes them as overrides)"));
  if (!o_.movie.empty()) return usage(invalid_argument("--card and --movie: give one"));
  if (f.timepoint_given) return usage(invalid_argument("--card restores the card's timepoint; drop --timepoint"));
  auto sc = load_card_scene(o_.card, f.annotations, o_.input);
  if (!sc) return by_code(sc.status());
  if (o_.input.empty() && !o_.sample) o_.input = sc->volume;
  if (!o_.lod_bias_given) o_.lod_bias = sc->lod_bias;
  if (sc->renderer == "dense")
    report_.note("note: card " + o_.card + " was drawn by the dense renderer; the view draws it out of core");
  pose_ = *sc;
  o_.flags.start = SettingsStart{*sc, /*is_scene=*/true, /*has_window=*/true};  // a card holds resolved windows
  return Status::ok();
}

// --settings read once (its camera is the headless view's too), a Scene's or card's choices adopted.
Status ViewCommand::start_from_settings() {
  if (!o_.flags.settings.empty())
    if (Status st = check_input(o_.flags.settings); !st) return usage(st);
  auto completed = complete_session_flags(o_.flags);
  if (!completed) return usage(completed.status());
  o_.flags = std::move(completed).value();
  const auto& start = o_.flags.start;
  if (!pose_ && start && start->is_scene && start->scene.has_camera && o_.movie.empty() && o_.script.empty())
    pose_ = start->scene;
  return Status::ok();
}

// Outputs and the flags that go with them, checked before any volume is read.
Status ViewCommand::check_outputs() {
  if (o_.frame_budget_ms < 0.0) return usage(invalid_argument("--frame-budget-ms: must be > 0 milliseconds"));
  if (!o_.json.empty()) {
    const std::string inputs[] = {o_.input};
    if (Status st = check_output(o_.json, inputs, "--json"); !st) return usage(st);
  }
  if (!o_.movie.empty()) {
    const std::string inputs[] = {o_.input, o_.script};
    if (Status st = check_output(o_.movie, inputs, "--movie"); !st) return usage(st);
    if (std::filesystem::path(o_.movie).extension() != ".mp4")
      return usage(invalid_argument("--movie " + o_.movie + ": give a .mp4 name (for PNG frames use --png-dir)"));
    if (forced(TargetKind::kOpenXr) || forced(TargetKind::kDesktop))
      return usage(invalid_argument("--movie renders headless; drop --xr/--desktop"));
    if (!o_.png_dir.empty()) return usage(invalid_argument("--movie and --png-dir: give one"));
    if (find_ffmpeg().empty())  // say so before rendering anything
      return work(unsupported(o_.movie + ": writing MP4 needs ffmpeg, which is not installed (apt-get install "
                                         "ffmpeg); or write the PNG sequence with --png-dir DIR --png-every-frame"));
  }
  if (!o_.ui_script.empty() && !forced(TargetKind::kDesktop))
    return usage(invalid_argument("--ui-script runs in the desktop window: add --desktop"));
  if (!o_.ui_script.empty() && o_.no_ui) return usage(invalid_argument("--ui-script and --no-ui: give one"));
  return Status::ok();
}

Status ViewCommand::open_session() {
  auto session = open_volume_session(o_.sample ? "" : o_.input, o_.flags);
  if (!session) return by_code(session.status());
  session_ = std::move(session).value();
  if (o_.tool_given && session_->annotation_store.empty())
    return usage(invalid_argument("--tool/--class: the tools edit an annotation store; give --annotations STORE or a "
                                  "project"));
  if (o_.tool_class.empty()) return usage(invalid_argument("--class: give a class name"));
  for (const std::string& n : session_->notes) report_.note(o_.input + ": " + n);
  const VolumeInfo& info = session_->source->info();
  if (info.channels > 1 || info.timepoints > 1) {
    std::string shown;
    for (uint32_t c : session_->channels) {
      if (!shown.empty()) shown += ',';
      shown += std::to_string(c);
    }
    report_.note(o_.input + ": showing channel(s) " + shown + " of timepoint " + std::to_string(session_->timepoint) +
                 " (of " + std::to_string(info.channels) + " channels, " + std::to_string(info.timepoints) +
                 " timepoints)");
  }
  placement_ = VolumePlacement{{uint32_t(info.dims[0]), uint32_t(info.dims[1]), uint32_t(info.dims[2])},
                               info.voxel_size};
  start_ = default_volume_transform(placement_);
  return Status::ok();
}

// What choose_target gets: the forced kind, the headless script, sizes, movie frames.
Status ViewCommand::build_request() {
  req_.kind = o_.target;
  if (!o_.script.empty()) {
    std::string err;
    if (!load_script(o_.script, req_.headless.script, err)) return usage(invalid_argument(err));
  }
  if (o_.width) req_.headless.script.width = o_.width;
  if (o_.height) req_.headless.script.height = o_.height;
  req_.headless.png_dir = o_.png_dir;
  req_.headless.png_every_frame = o_.png_every_frame;
  if (!o_.movie.empty()) {
    auto dir = movie_scratch_dir(o_.movie);
    if (!dir) return work(dir.status());
    movie_frames_ = *dir;
    req_.kind = TargetKind::kHeadless;
    req_.headless.png_dir = movie_frames_;
    req_.headless.png_every_frame = true;
    req_.headless.stereo = false;  // one view from the head: the camera
  }
  if (o_.frames) req_.headless.end_frame = o_.frames;
  req_.desktop_stereo = o_.stereo;
  req_.desktop_screenshot = o_.screenshot;
  req_.mirror = o_.mirror;
  req_.max_eye_width = o_.width;
  req_.max_eye_height = o_.height;
  return Status::ok();
}

// The desktop viewer's setup: panels over the session's settings, the UI
// script checked against them, the annotation store (--annotations or the
// project's) for the tools. Only where a window may be chosen.
Status ViewCommand::build_viewer_setup() {
  if (o_.no_ui || !o_.movie.empty() || forced(TargetKind::kOpenXr) || forced(TargetKind::kHeadless))
    return Status::ok();
  const VolumeSession& session = *session_;
  auto setup = std::make_shared<ViewerSetup>();
  const VolumeInfo& info = session.source->info();
  const bool sample = o_.sample || o_.input.empty();
  setup->dataset = sample ? std::string("sample (MRI head)") : std::filesystem::path(o_.input).filename().string();
  if (setup->dataset.empty()) setup->dataset = o_.input;  // a folder given with a trailing slash
  std::error_code ec;
  setup->scene.volume = sample || o_.input.rfind("procedural:", 0) == 0 ? o_.input
                                                                         : std::filesystem::absolute(o_.input, ec).string();
  setup->scene.render = session.settings;  // a card's or --settings' with the flags applied
  setup->scene.timepoint = session.timepoint;
  setup->scene.channels = session.channels;  // a card saved in the window restores the channels drawn
  if (auto vs = parse_voxel_size_flag(o_.flags.voxel_size); vs.is_ok() && vs->has_value()) setup->scene.voxel_size = **vs;
  setup->timepoints = info.timepoints;
  setup->data_range = slider_range(info, session.settings);
  setup->placement = placement_;
  setup->transform = start_;
  if (pose_) setup->start_orbit = scene_orbit(*pose_, placement_);  // the window starts at the card's camera
  for (uint32_t c : session.channels) {
    auto histogram = coarse_histogram(*session.source, c, session.timepoint, setup->data_range);
    if (!histogram) return by_code(histogram.status());
    setup->histograms.push_back(std::move(histogram).value());
  }
  const std::string& store_path = session.annotation_store;
  if (!store_path.empty()) {
    auto store = annotate::AnnotationStore::open(store_path, true);
    if (!store) return by_code(Status(store.status().code(), store_path + ": " + store.status().message()));
    setup->store = std::move(store).value();
  }
  if (!o_.ui_script.empty()) {
    const ViewerState state(setup->scene, setup->timepoints, setup->data_range);
    auto script = load_ui_script(o_.ui_script, state, {o_.input, o_.ui_script, store_path}, setup->store != nullptr);
    if (!script) return by_code(script.status());
    setup->script = std::move(script).value();
  }
  setup->open_request = open_request_;
  // The dataset's last view comes back unless the look was asked for (a card, --settings or a look flag).
  setup->view_memory = remembered_view_path(o_.input);
  const SessionFlags& f = o_.flags;
  const bool look_given = !o_.card.empty() || !f.settings.empty() || !f.colormap.empty() || !f.window.empty() ||
                          !f.model.empty() || f.step != 0.0 || !f.iso.empty() || !f.channel.empty() || f.timepoint_given ||
                          !f.opacity.empty() || !f.opacity_unit_distance.empty() || !f.voxel_size.empty();
  setup->restore_view = !look_given;
  req_.viewer = std::move(setup);
  // The window opens at the size it had last time (1280x800 at first) unless given.
  if (!o_.width && !o_.height && !o_.stereo) {
    const std::string config = viewer_config_path();
    auto size = config.empty() ? Result<WindowGeometry>(WindowGeometry{}) : load_window_geometry(config);
    if (!size) report_.note(size.status().message() + " (using 1280x800)");
    const WindowGeometry g = size ? *size : WindowGeometry{};
    req_.headless.script.width = g.width;
    req_.headless.script.height = g.height;
  }
  return Status::ok();
}

// The target: a card's (or --settings Scene's) camera and size for one headless view, then choose_target.
Status ViewCommand::choose() {
  if (pose_) {
    // As vxr render draws it (a headset or window keeps its own eye size).
    req_.headless.stereo = false;
    if (!o_.width && pose_->viewport[0] > 0) req_.headless.script.width = pose_->viewport[0];
    if (!o_.height && pose_->viewport[1] > 0) req_.headless.script.height = pose_->viewport[1];
    req_.headless.camera = scene_camera(*pose_, placement_, placement_.dims[2] == 1);
  }
  auto choice = choose_target(req_);
  if (!choice) return work(choice.status());
  choice_ = std::move(choice).value();
  report_.info(choice_->reason);
  return Status::ok();
}

// The hands' tools and the store they edit. The desktop viewer holds the store
// itself (its tools edit it) and draws its markers over the volume; otherwise
// the session holds it (the one opened for a window not chosen: one LevelDB
// lock), the hands' tools edit it and it is drawn from there.
Status ViewCommand::hand_tools(ViewOptions& vo) {
  const bool viewer_has_store = choice_->kind == TargetKind::kDesktop && req_.viewer && req_.viewer->store;
  if (viewer_has_store && o_.tool_given)
    report_.note("note: --tool/--class set the controllers' tools; the window's tools panel picks its own");
  // The hands' report lines (the cut plane's too, which needs no store).
  const ViewReport& report = report_;
  vo.on_tool_report = [&report](const std::string& line) { report.info(line); };
  if (session_->annotation_store.empty() || viewer_has_store) return Status::ok();
  vo.tool_store = req_.viewer ? req_.viewer->store : nullptr;
  if (!vo.tool_store) {
    auto store = annotate::AnnotationStore::open(session_->annotation_store, false);
    if (!store) return work(store.status());
    vo.tool_store = std::move(store).value();
  }
  vo.hand_tools.tool = *annotate::tool_from_name(o_.tool);  // checked by the flag
  vo.hand_tools.count_class = o_.tool_class;
  return Status::ok();
}

// --movie from the frames, --json figures, then the summary lines.
Status ViewCommand::write_outputs(const ViewStats& stats, const ViewOptions& vo) {
  if (!o_.movie.empty()) {
    if (Status st = encode_movie(movie_frames_, o_.fps, o_.movie); !st) return work(st);
    std::error_code ec;
    std::filesystem::remove_all(movie_frames_, ec);
    char line[512];
    std::snprintf(line, sizeof line, "movie %s: %llu frames at %.6g fps", o_.movie.c_str(),
                  static_cast<unsigned long long>(stats.frames_rendered), o_.fps);
    report_.info(line);
  }
  if (!o_.json.empty()) {
    nlohmann::json j = view_stats_json(stats, vo);
    j["input"] = session_->description;
    if (Status st = write_file_atomically(o_.json, j.dump(2) + "\n"); !st) return work(st);
  }
  char line[512];
  std::snprintf(line, sizeof line, "%llu frames rendered on %s, %.2f ms mean, %.2f ms max per frame, %d restart(s)",
                static_cast<unsigned long long>(stats.frames_rendered), stats.target.c_str(), stats.mean_frame_ms,
                stats.max_frame_ms, stats.restarts);
  report_.info(line);
  const auto& t = stats.transform;
  std::snprintf(line, sizeof line, "volume at (%.6f, %.6f, %.6f), scale %.9g m/unit", t.position.x, t.position.y,
                t.position.z, t.scale);
  report_.info(line);
  return Status::ok();
}

Status ViewCommand::run() {
  VXR_RETURN_IF_ERROR(start_from_card());
  VXR_RETURN_IF_ERROR(start_from_settings());
  VXR_RETURN_IF_ERROR(check_outputs());
  VXR_RETURN_IF_ERROR(open_session());
  VXR_RETURN_IF_ERROR(build_request());
  VXR_RETURN_IF_ERROR(build_viewer_setup());
  VXR_RETURN_IF_ERROR(choose());
  ViewOptions vo;
  vo.frames = o_.frames;
  vo.settings = session_->settings;
  vo.channels = session_->channels;
  vo.warp.enabled = o_.lens_warp;
  vo.frame.lod.lod_bias = o_.lod_bias;
  vo.frame.lod.skip_empty = !o_.no_skip;
  vo.frame.lod.timepoint = session_->timepoint;
  vo.frame_budget_ms = o_.frame_budget_ms;
  // A headset keeps its own head pose and fov: the volume is placed so the head
  // sees what the card's (or a --settings Scene's) camera saw; headless draws the camera itself.
  if (pose_ && choice_->kind == TargetKind::kOpenXr) vo.place_for_camera = req_.headless.camera;
  VXR_RETURN_IF_ERROR(hand_tools(vo));
  auto stats = run_view(choice_->factory, session_->source, vo, start_);
  if (!stats) return work(stats.status());
  return write_outputs(*stats, vo);
}

}  // namespace

Status run_view_command(const ViewCommandOptions& options, const ViewReport& report, ViewFailure* failure) {
  ViewCommandOptions o = options;
  for (;;) {
    auto open_request = std::make_shared<std::string>();
    ViewCommand command(o, report, open_request);
    Status st = command.run();
    if (!st && failure) *failure = command.failed();
    if (!st || open_request->empty()) return st;
    // The window's Open: the next input with the window's own choices (target,
    // size, frames, screenshot) and the new input's defaults (its remembered view).
    report.info("opening " + *open_request);
    o.input = *open_request;
    o.sample = false;
    o.card.clear();
    o.ui_script.clear();
    o.flags = SessionFlags{};
  }
}

}  // namespace vxr::xr
