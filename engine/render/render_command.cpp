#include "render/render_command.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <cstdarg>
#include <sstream>

#include <nlohmann/json.hpp>

#include "annotate/annotation_store.h"
#include "annotate/file_io.h"
#include "core/output_file.h"
#include "core/trace.h"
#include "render/camera.h"
#include "render/card_scene.h"
#include "render/transfer_function.h"
#include "render/still_render.h"
#include "render/volume_session.h"
#include "scene/render_settings.h"

namespace vxr {
namespace {

using Options = RenderCommandOptions;

// How a step failed: a usage error (flags, settings) or the work (the default).
struct Failure {
  RenderFailure kind = RenderFailure::kWork;
  Status usage(Status s) {
    kind = RenderFailure::kUsage;
    return s;
  }
};

// printf into a string.
std::string strf(const char* fmt, ...) {
  va_list a, b;
  va_start(a, fmt);
  va_copy(b, a);
  const int n = std::vsnprintf(nullptr, 0, fmt, a);
  va_end(a);
  std::string s(n > 0 ? size_t(n) : 0, '\0');
  if (n > 0) std::vsnprintf(s.data(), s.size() + 1, fmt, b);
  va_end(b);
  return s;
}


// What the render resolved, for --save-card.
struct Resolved {
  std::vector<uint32_t> channels;
  RenderSettings settings;
  Camera camera;
};

bool starts_with(const std::string& s, const char* prefix) { return s.rfind(prefix, 0) == 0; }

bool parse_doubles(const std::string& text, size_t n, std::vector<double>& out) {
  out.clear();
  std::stringstream ss(text);
  std::string item;
  while (std::getline(ss, item, ',')) {
    char* end = nullptr;
    const double v = std::strtod(item.c_str(), &end);
    if (item.empty() || *end != '\0' || !std::isfinite(v)) return false;
    out.push_back(v);
  }
  return out.size() == n;
}

// The one renderer, for every input: open_volume_session's session through
// render_still (engine/render/still_render.h). Without --frame-budget-ms it
// renders until nothing is missing and writes that frame; with it, --frames
// frames (default 30) with the LOD bias following the frame time, and writes
// the last.
Status run_lod(const Options& o, gpu::Context& gpu, uint32_t width, uint32_t height, const CameraChooser& camera_for,
               Resolved* resolved, const RenderReport& report, Failure& failure) {
  SessionStep failed_at = SessionStep::kSettings;
  auto session = open_volume_session(o.input, o.flags, &failed_at);
  if (!session) {
    // The flags, channels and timepoint are usage errors; so is a bad procedural spec. A file that fails to read is not.
    const bool usage = failed_at == SessionStep::kSource ? starts_with(o.input, "procedural:")
                                                         : session.status().code() == ErrorCode::kInvalidArgument;
    return (usage) ? failure.usage(session.status()) : Status(session.status());
  }
  for (const std::string& n : session->notes) report.note(strf("note: %s: %s", o.input.c_str(), n.c_str()));
  const RenderSettings& s = session->settings;
  const VolumeInfo& info = session->source->info();
  const VolumePlacement placement{{uint32_t(info.dims[0]), uint32_t(info.dims[1]), uint32_t(info.dims[2])},
                                  info.voxel_size};
  auto chosen = camera_for(placement, info.dims[2] == 1);
  if (!chosen) return failure.usage(chosen.status());
  const Camera& camera = *chosen;
  *resolved = {session->channels, s, camera};

  StillOptions so;
  so.width = width;
  so.height = height;
  so.lod_bias = o.lod_bias;
  so.frame_budget_ms = o.frame_budget_ms;
  so.frames = o.frames;
  so.skip_empty = !o.no_skip;
  so.compare_to_reference = o.json && o.reference;
  so.reference_step = o.reference_step;
  const bool budget = o.frame_budget_ms > 0.0;
  if (budget && o.stats)
    so.on_frame = [&report](const StillFrame& f) {
      report.out(strf("frame %d: bias %.2f, %.1f ms, drawn %llu, missing %llu", f.frame, f.lod_bias, f.wall_ms,
                  (unsigned long long)f.bricks_drawn, (unsigned long long)f.bricks_missing));
    };
  auto still = render_still(gpu, *session, camera, so);
  if (!still) {
    const Status& st = still.status();
    if (st.code() == ErrorCode::kInternal) return Status(st.code(), o.input + ": " + st.message());
    return (st.code() == ErrorCode::kInvalidArgument) ? failure.usage(st) : Status(st);
  }
  if (Status e = write_png(o.output, over_black(still->image)); !e) return e;
  if (o.json) {
    nlohmann::json frames_json = nlohmann::json::array();
    for (const StillFrame& f : still->frames) {
      nlohmann::json fj = {{"frame", f.frame},
                           {"wall_ms", f.wall_ms},
                           {"gpu_ms", f.gpu_ms},
                           {"samples", f.samples},
                           {"bricks_drawn", f.bricks_drawn},
                           {"bricks_missing", f.bricks_missing},
                           {"bricks_uploaded", f.bricks_uploaded}};
      if (f.rmse_vs_reference >= 0.0) fj["rmse_vs_reference"] = f.rmse_vs_reference;
      frames_json.push_back(fj);
    }
    nlohmann::json j = {{"output", o.output},
                        {"width", width},
                        {"height", height},
                        {"model", optical_model_name(s.model)},
                        {"step_voxels", s.step_voxels},
                        {"empty_space_skipping", !o.no_skip},
                        {"device", gpu.info().name},
                        {"frames", frames_json}};
    if (o.reference) j["reference"] = {{"step_voxels", o.reference_step}, {"cpu_ms", still->reference_cpu_ms}};
    report.out(strf("%s", j.dump(2).c_str()));
    return Status::ok();
  }
  const int frames = int(still->frames.size());
  report.out(strf("%s: %ux%u, %s, out-of-core (lod), %d frames%s, %.1f ms", o.output.c_str(), width, height,
              optical_model_name(s.model), frames, still->converged ? " to converge" : "", still->total_ms));
  if (budget) {
    // Median of the last few frames: what the controller settled on.
    std::vector<double> tail;
    for (size_t i = still->frames.size() - std::min<size_t>(still->frames.size(), 5); i < still->frames.size(); ++i)
      tail.push_back(still->frames[i].wall_ms);
    std::sort(tail.begin(), tail.end());
    report.out(strf("frame budget: target %.1f ms, bias %.2f -> %.2f, last frames %.1f ms (median of %zu)",
                o.frame_budget_ms, o.lod_bias, still->frames.back().lod_bias, tail[tail.size() / 2], tail.size()));
  }
  if (o.stats) {
    report.out(strf("stats: %s", format_stats(still->last).c_str()));
    report.out(strf("stats: %d frames, %llu bricks %.2f MiB uploaded in all, pool %u of %u bricks", frames,
                (unsigned long long)still->bricks_uploaded, double(still->bytes_uploaded) / (1 << 20), still->pool_used,
                still->pool_capacity));
  }
  return Status::ok();
}

// Adds the picture just written as a card whose Scene is what this run
// resolved, so `--card` draws it again without guessing anything.
Status save_card(const Options& o, Scene sc, const Resolved& r, uint32_t width, uint32_t height,
                 const RenderReport& report) {
  std::error_code ec;
  sc.volume = starts_with(o.input, "procedural:") ? o.input : std::filesystem::absolute(o.input, ec).lexically_normal().string();
  sc.timepoint = o.flags.timepoint;
  sc.channels = r.channels;
  sc.has_camera = true;
  sc.camera = {{r.camera.eye.x, r.camera.eye.y, r.camera.eye.z},
               {r.camera.target.x, r.camera.target.y, r.camera.target.z},
               {r.camera.up.x, r.camera.up.y, r.camera.up.z},
               r.camera.fov_y_deg};
  sc.viewport = {width, height};
  sc.renderer = "lod";
  sc.path.clear();
  sc.lod_bias = o.lod_bias;
  if (auto vs = parse_voxel_size_flag(o.flags.voxel_size); vs.is_ok() && vs->has_value()) sc.voxel_size = **vs;
  sc.render = r.settings;
  sc.annotations = o.flags.annotations.empty() ? "" : std::filesystem::absolute(o.flags.annotations, ec).lexically_normal().string();
  auto png = annotate::read_whole_file(o.output);
  if (!png) return png.status();
  annotate::Card card;
  card.title = o.card_title;
  card.note = o.card_note;
  card.scene_json = scene_to_json(sc);
  card.snapshot_png.assign(png->begin(), png->end());
  auto store = annotate::AnnotationStore::open(o.save_card, /*create=*/false);
  if (!store) return store.status();
  auto id = (*store)->add_card(std::move(card));
  if (!id) return id.status();
  report.out(strf("card %llu in %s", (unsigned long long)*id, o.save_card.c_str()));
  return Status::ok();
}

Status run_command(const Options& given, const std::function<GpuOpener>& open_gpu, const RenderReport& report,
                   Failure& failure) {
  Options o = given;
  // A card (or a Scene given with --settings) supplies the choices the flags
  // did not make; a flag given on the command line wins. The session's own
  // (channels, timepoint, voxel size, annotations) are complete_session_flags'.
  Scene scene;
  auto adopt_scene_choices = [&](const Scene& sc) {
    if (!o.size_given && sc.viewport[0] > 0)
      o.size = std::to_string(sc.viewport[0]) + "x" + std::to_string(sc.viewport[1]);
    if (!o.lod_bias_given && sc.lod_bias != 0.0) o.lod_bias = sc.lod_bias, o.lod_bias_given = true;
  };
  if (!o.card.empty()) {
    if (!o.flags.settings.empty()) return failure.usage(invalid_argument("give --card or --settings, not both"));
    auto sc = load_card_scene(o.card, o.flags.annotations, o.input);
    if (!sc) {
      const ErrorCode c = sc.status().code();
      return (c == ErrorCode::kInvalidArgument || c == ErrorCode::kNotFound) ? failure.usage(sc.status()) : Status(sc.status());
    }
    if (o.input.empty()) o.input = sc->volume;
    if (sc->renderer == "dense")
      report.note(strf("note: card %s was drawn by the dense renderer (since removed); drawing it out of core",
                   o.card.c_str()));
    o.flags.start = SettingsStart{*sc, /*is_scene=*/true, /*has_window=*/true};  // a card holds resolved windows
  }
  if (o.input.empty())
    return failure.usage(invalid_argument("give the volume to render (vxr render INPUT -o out.png), or --card STORE:ID"));
  if (!o.save_card.empty() && (o.reference || o.frame_budget_ms != 0.0))
    return failure.usage(invalid_argument(std::string("--save-card: a card restores through the GPU renderer to the same pixels; ") +
                                 (o.reference ? "drop --reference" : "drop --frame-budget-ms (its picture depends on timing)")));
  if (!starts_with(o.input, "procedural:")) {
    if (Status st = check_input(o.input, /*allow_dir=*/true); !st) return st;
  }
  if (Status st = check_output(o.output, {{o.input, o.flags.settings}}, "-o"); !st) return failure.usage(st);
  if (!o.flags.settings.empty()) {
    if (Status st = check_input(o.flags.settings); !st) return failure.usage(st);
  }
  // Settings first: a bad setting is a usage error even before any file is read.
  auto completed = complete_session_flags(o.flags);
  if (!completed) return failure.usage(completed.status());
  o.flags = std::move(completed).value();
  if (o.flags.start) {
    scene = o.flags.start->scene;
    if (o.flags.start->is_scene) adopt_scene_choices(scene);
  }
  if (auto choice = choose_settings(o.flags); !choice) return failure.usage(choice.status());
  uint32_t width = 0, height = 0;
  if (std::sscanf(o.size.c_str(), "%ux%u", &width, &height) != 2 || width == 0 || height == 0 || width > 16384 ||
      height > 16384)
    return failure.usage(invalid_argument("--size: expected WxH like 512x512, got '" + o.size + "'"));
  if (o.reference && !o.json && (o.lod_bias_given || o.frame_budget_ms != 0.0 || o.no_skip || o.frames != 0))
    return failure.usage(invalid_argument(std::string(o.lod_bias_given          ? "--lod-bias"
                                             : o.frame_budget_ms != 0.0 ? "--frame-budget-ms"
                                             : o.no_skip                ? "--no-skip"
                                                                        : "--frames") +
                                 ": the CPU reference (--reference) draws the whole volume once; drop it, or add "
                                 "--json to measure the GPU frames against the reference"));
  if (o.reference && !o.json && starts_with(o.input, "procedural:"))
    return failure.usage(invalid_argument("--reference: a procedural source is drawn by the GPU only (add --json to measure "
                                 "its frames against the reference of its finest level)"));
  if (o.reference && !o.json && !o.flags.annotations.empty())
    return failure.usage(invalid_argument("--annotations: drawn by the GPU renderer; drop --reference"));
  if (o.json && (o.frame_budget_ms != 0.0 || !o.save_card.empty()))
    return failure.usage(invalid_argument("--json: measures fixed frames; drop --frame-budget-ms and --save-card"));
  if (o.frame_budget_ms < 0.0 || !std::isfinite(o.frame_budget_ms))
    return failure.usage(invalid_argument("--frame-budget-ms: must be > 0 milliseconds"));
  if (o.frames < 0 || o.frames > 100000) return failure.usage(invalid_argument("--frames: must be 1..100000"));
  // The reference marches every sample in double on the CPU: below 1/256 voxel it would run for days.
  if (o.reference && !(o.reference_step >= 1.0 / 256 && o.reference_step <= 64.0))
    return failure.usage(invalid_argument("--reference-step: must be within 1/256..64 voxels (default 1/16)"));
  if (o.reference && !o.json && o.flags.timepoint != 0)
    return failure.usage(invalid_argument("--timepoint: the CPU reference (--reference) reads timepoint 0 only; add --json to "
                                 "measure the GPU frames of other timepoints against it"));
  if (!std::isfinite(o.lod_bias) || std::abs(o.lod_bias) > 16.0)
    return failure.usage(invalid_argument("--lod-bias: must be within -16..16 (log2 of voxels per pixel)"));

  std::unique_ptr<gpu::Context> gpu;
  uint32_t max_dim = 2048;
  const bool reference_only = o.reference && !o.json;
  if (!reference_only) {
    auto g = open_gpu();
    if (!g) return g.status();
    gpu = std::move(g).value();
    max_dim = std::min(max_dim, gpu->limits().maxImageDimension3D);
  }

  Camera world_camera;  // before the volume transform: what a card stores
  Resolved resolved;
  // The camera: the default orbit view, then the scene's, then the flags.
  const CameraChooser camera_for = [&](const VolumePlacement& placement, bool flat) -> Result<Camera> {
    Camera camera = scene_world_camera(scene, placement, flat);
    if (!o.camera.empty()) {
      std::vector<double> c;
      if (!parse_doubles(o.camera, 9, c))
        return invalid_argument("--camera: expected 9 numbers px,py,pz,tx,ty,tz,ux,uy,uz (world units, volume "
                                "centred at 0), got '" + o.camera + "'");
      camera.eye = {c[0], c[1], c[2]};
      camera.target = {c[3], c[4], c[5]};
      camera.up = {c[6], c[7], c[8]};
    }
    if (o.fov != 0.0) {
      if (!(o.fov > 0.0 && o.fov < 179.0)) return invalid_argument("--fov: must be in (0, 179) degrees");
      camera.fov_y_deg = o.fov;
    }
    if (glm::length(camera.target - camera.eye) == 0.0)
      return invalid_argument("--camera: the eye and the target are the same point");
    world_camera = camera;
    return camera_in_volume_frame(camera, scene.transform);
  };
  auto finish = [&](Status st) {
    if (!st || o.save_card.empty()) return st;
    resolved.camera = world_camera;
    return save_card(o, scene, resolved, width, height, report);
  };

  if (!reference_only) return finish(run_lod(o, *gpu, width, height, camera_for, &resolved, report, failure));

  ReferenceStillOptions ro;
  ro.width = width;
  ro.height = height;
  ro.reference_step = o.reference_step;
  ro.max_dim = max_dim;
  SessionStep failed_at = SessionStep::kSettings;
  auto still = render_still_reference(o.input, o.flags, camera_for, ro, &failed_at);
  if (!still) {
    const bool usage = failed_at != SessionStep::kSource && still.status().code() == ErrorCode::kInvalidArgument;
    return (usage) ? failure.usage(still.status()) : Status(still.status());
  }
  for (const std::string& n : still->notes) report.note(strf("note: %s: %s", o.input.c_str(), n.c_str()));
  if (Status st = write_png(o.output, over_black(still->image)); !st) return st;
  report.out(strf("%s: %ux%u, %s, CPU reference, %.1f ms", o.output.c_str(), width, height,
              optical_model_name(still->settings.model), still->ms));
  if (o.stats)
    report.out(strf("stats: CPU reference, shrink %u, samples <= %llu (before early termination), %.1f ms", still->shrink,
                (unsigned long long)still->sample_bound, still->ms));
  return Status::ok();
}

}  // namespace

Status run_render_command(const RenderCommandOptions& given, const std::function<GpuOpener>& open_gpu,
                          const RenderReport& report, RenderFailure* failure_out) {
  VXR_TRACE_SCOPE("render");
  Failure failure;
  const Status st = run_command(given, open_gpu, report, failure);
  if (failure_out) *failure_out = failure.kind;
  return st;
}

}  // namespace vxr
