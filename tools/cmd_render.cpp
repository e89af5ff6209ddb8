// `vxr render INPUT -o out.png`: one picture of a volume through the one
// renderer vxr view uses, for every input. Only flags live here: the session
// (source, settings, channels, timepoint; the same as vxr view's) is
// render/volume_session.h, the frames render/still_render.h. For comparison:
// --reference draws the CPU reference (double precision) with the same
// resolved settings instead; with --json it measures each frame against it.
//
// Settings come from --settings (a RenderSettings JSON, or a Scene JSON with
// "render" and "camera"), then the flags override them. Bad settings exit 2
// with one line naming the setting.
//
// Cards: --save-card STORE stores the picture as a card whose Scene holds every
// resolved choice (input, timepoint, channels, windows, camera, size,
// LOD bias); --card STORE:ID starts from that Scene, so the same build draws
// the same pixels again.
//
// Timing (out-of-core renderer): --frames N --json prints each frame's GPU ms
// (timestamp queries), wall ms and samples, with --reference also the RMSE
// against the CPU reference of the finest level; --no-skip marches empty
// space too (the same image; for A/B timing).
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <sstream>

#include <nlohmann/json.hpp>

#include "annotate/annotation_store.h"
#include "annotate/file_io.h"
#include "command.h"
#include "core/output_file.h"
#include "core/trace.h"
#include "render/camera.h"
#include "render/transfer_function.h"
#include "render/still_render.h"
#include "render/volume_session.h"
#include "scene/render_settings.h"
#include "volume_flags.h"

namespace vxr::cli {
namespace {

struct Options {
  std::string input, output, camera, size = "512x512";
  double fov = 0.0, reference_step = 1.0 / 16.0;
  double lod_bias = 0.0, frame_budget_ms = 0.0;
  bool lod_bias_given = false;
  int frames = 0;  // 0: until converged
  bool reference = false, stats = false;
  bool no_skip = false;  // lod: no empty-space skipping (bricks or cells), for A/B timing
  bool json = false;     // lod: per-frame figures as JSON on stdout
  bool size_given = false;
  std::string card;       // STORE:ID to restore
  std::string save_card;  // STORE to add a card to
  std::string card_title, card_note;
  SessionFlags flags;  // the session's flags, shared with vxr view (--settings, --channel, --annotations, ...)
};

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
int run_lod(const Options& o, gpu::Context& gpu, uint32_t width, uint32_t height, const CameraChooser& camera_for,
            Resolved* resolved) {
  SessionStep failed_at = SessionStep::kSettings;
  auto session = open_volume_session(o.input, o.flags, &failed_at);
  if (!session) {
    // The flags, channels and timepoint are usage errors; so is a bad procedural spec. A file that fails to read is not.
    const bool usage = failed_at == SessionStep::kSource ? starts_with(o.input, "procedural:")
                                                         : session.status().code() == ErrorCode::kInvalidArgument;
    return fail(session.status(), usage ? kExitUsage : kExitFailure);
  }
  for (const std::string& n : session->notes) std::fprintf(stderr, "vxr: note: %s: %s\n", o.input.c_str(), n.c_str());
  const RenderSettings& s = session->settings;
  const VolumeInfo& info = session->source->info();
  const VolumePlacement placement{{uint32_t(info.dims[0]), uint32_t(info.dims[1]), uint32_t(info.dims[2])},
                                  info.voxel_size};
  auto chosen = camera_for(placement, info.dims[2] == 1);
  if (!chosen) return fail(chosen.status(), kExitUsage);
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
    so.on_frame = [](const StillFrame& f) {
      std::printf("frame %d: bias %.2f, %.1f ms, drawn %llu, missing %llu\n", f.frame, f.lod_bias, f.wall_ms,
                  (unsigned long long)f.bricks_drawn, (unsigned long long)f.bricks_missing);
    };
  auto still = render_still(gpu, *session, camera, so);
  if (!still) {
    const Status& st = still.status();
    if (st.code() == ErrorCode::kInternal) return fail(Status(st.code(), o.input + ": " + st.message()));
    return fail(st, st.code() == ErrorCode::kInvalidArgument ? kExitUsage : kExitFailure);
  }
  if (Status e = write_png(o.output, over_black(still->image)); !e) return fail(e);
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
    std::printf("%s\n", j.dump(2).c_str());
    return kExitOk;
  }
  const int frames = int(still->frames.size());
  std::printf("%s: %ux%u, %s, out-of-core (lod), %d frames%s, %.1f ms\n", o.output.c_str(), width, height,
              optical_model_name(s.model), frames, still->converged ? " to converge" : "", still->total_ms);
  if (budget) {
    // Median of the last few frames: what the controller settled on.
    std::vector<double> tail;
    for (size_t i = still->frames.size() - std::min<size_t>(still->frames.size(), 5); i < still->frames.size(); ++i)
      tail.push_back(still->frames[i].wall_ms);
    std::sort(tail.begin(), tail.end());
    std::printf("frame budget: target %.1f ms, bias %.2f -> %.2f, last frames %.1f ms (median of %zu)\n",
                o.frame_budget_ms, o.lod_bias, still->frames.back().lod_bias, tail[tail.size() / 2], tail.size());
  }
  if (o.stats) {
    std::printf("stats: %s\n", format_stats(still->last).c_str());
    std::printf("stats: %d frames, %llu bricks %.2f MiB uploaded in all, pool %u of %u bricks\n", frames,
                (unsigned long long)still->bricks_uploaded, double(still->bytes_uploaded) / (1 << 20), still->pool_used,
                still->pool_capacity);
  }
  return kExitOk;
}

// Adds the picture just written as a card whose Scene is what this run
// resolved, so `--card` draws it again without guessing anything.
int save_card(const Options& o, Scene sc, const Resolved& r, uint32_t width, uint32_t height) {
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
  if (!png) return fail(png.status());
  annotate::Card card;
  card.title = o.card_title;
  card.note = o.card_note;
  card.scene_json = scene_to_json(sc);
  card.snapshot_png.assign(png->begin(), png->end());
  auto store = annotate::AnnotationStore::open(o.save_card, /*create=*/false);
  if (!store) return fail(store.status());
  auto id = (*store)->add_card(std::move(card));
  if (!id) return fail(id.status());
  std::printf("card %llu in %s\n", (unsigned long long)*id, o.save_card.c_str());
  return kExitOk;
}

int run(const Options& given) {
  VXR_TRACE_SCOPE("render");
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
    if (!o.flags.settings.empty()) return fail(invalid_argument("give --card or --settings, not both"), kExitUsage);
    auto sc = load_card_scene(o.card, o.flags.annotations, o.input);
    if (!sc) {
      const ErrorCode c = sc.status().code();
      return fail(sc.status(), c == ErrorCode::kInvalidArgument || c == ErrorCode::kNotFound ? kExitUsage : kExitFailure);
    }
    if (o.input.empty()) o.input = sc->volume;
    if (sc->renderer == "dense")
      std::fprintf(stderr, "vxr: note: card %s was drawn by the dense renderer (since removed); drawing it out of core\n",
                   o.card.c_str());
    o.flags.start = SettingsStart{*sc, /*is_scene=*/true, /*has_window=*/true};  // a card holds resolved windows
  }
  if (o.input.empty())
    return fail(invalid_argument("give the volume to render (vxr render INPUT -o out.png), or --card STORE:ID"), kExitUsage);
  if (!o.save_card.empty() && (o.reference || o.frame_budget_ms != 0.0))
    return fail(invalid_argument(std::string("--save-card: a card restores through the GPU renderer to the same pixels; ") +
                                 (o.reference ? "drop --reference" : "drop --frame-budget-ms (its picture depends on timing)")),
                kExitUsage);
  if (!starts_with(o.input, "procedural:")) {
    if (Status st = check_input(o.input, /*allow_dir=*/true); !st) return fail(st);
  }
  if (Status st = check_output(o.output, {{o.input, o.flags.settings}}, "-o"); !st) return fail(st, kExitUsage);
  if (!o.flags.settings.empty()) {
    if (Status st = check_input(o.flags.settings); !st) return fail(st, kExitUsage);
  }
  // Settings first: a bad setting is a usage error even before any file is read.
  auto completed = complete_session_flags(o.flags);
  if (!completed) return fail(completed.status(), kExitUsage);
  o.flags = std::move(completed).value();
  if (o.flags.start) {
    scene = o.flags.start->scene;
    if (o.flags.start->is_scene) adopt_scene_choices(scene);
  }
  if (auto choice = choose_settings(o.flags); !choice) return fail(choice.status(), kExitUsage);
  uint32_t width = 0, height = 0;
  if (std::sscanf(o.size.c_str(), "%ux%u", &width, &height) != 2 || width == 0 || height == 0 || width > 16384 ||
      height > 16384)
    return fail(invalid_argument("--size: expected WxH like 512x512, got '" + o.size + "'"), kExitUsage);
  if (o.reference && !o.json && (o.lod_bias_given || o.frame_budget_ms != 0.0 || o.no_skip || o.frames != 0))
    return fail(invalid_argument(std::string(o.lod_bias_given          ? "--lod-bias"
                                             : o.frame_budget_ms != 0.0 ? "--frame-budget-ms"
                                             : o.no_skip                ? "--no-skip"
                                                                        : "--frames") +
                                 ": the CPU reference (--reference) draws the whole volume once; drop it, or add "
                                 "--json to measure the GPU frames against the reference"),
                kExitUsage);
  if (o.reference && !o.json && starts_with(o.input, "procedural:"))
    return fail(invalid_argument("--reference: a procedural source is drawn by the GPU only (add --json to measure "
                                 "its frames against the reference of its finest level)"),
                kExitUsage);
  if (o.reference && !o.json && !o.flags.annotations.empty())
    return fail(invalid_argument("--annotations: drawn by the GPU renderer; drop --reference"), kExitUsage);
  if (o.json && (o.frame_budget_ms != 0.0 || !o.save_card.empty()))
    return fail(invalid_argument("--json: measures fixed frames; drop --frame-budget-ms and --save-card"), kExitUsage);
  if (o.frame_budget_ms < 0.0 || !std::isfinite(o.frame_budget_ms))
    return fail(invalid_argument("--frame-budget-ms: must be > 0 milliseconds"), kExitUsage);
  if (o.frames < 0 || o.frames > 100000) return fail(invalid_argument("--frames: must be 1..100000"), kExitUsage);
  // The reference marches every sample in double on the CPU: below 1/256 voxel it would run for days.
  if (o.reference && !(o.reference_step >= 1.0 / 256 && o.reference_step <= 64.0))
    return fail(invalid_argument("--reference-step: must be within 1/256..64 voxels (default 1/16)"), kExitUsage);
  if (o.reference && !o.json && o.flags.timepoint != 0)
    return fail(invalid_argument("--timepoint: the CPU reference (--reference) reads timepoint 0 only; add --json to "
                                 "measure the GPU frames of other timepoints against it"),
                kExitUsage);
  if (!std::isfinite(o.lod_bias) || std::abs(o.lod_bias) > 16.0)
    return fail(invalid_argument("--lod-bias: must be within -16..16 (log2 of voxels per pixel)"), kExitUsage);

  std::unique_ptr<gpu::Context> gpu;
  uint32_t max_dim = 2048;
  const bool reference_only = o.reference && !o.json;
  if (!reference_only) {
    auto g = open_gpu();
    if (!g) return fail(g.status());
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
  auto finish = [&](int rc) {
    if (rc != kExitOk || o.save_card.empty()) return rc;
    resolved.camera = world_camera;
    return save_card(o, scene, resolved, width, height);
  };

  if (!reference_only) return finish(run_lod(o, *gpu, width, height, camera_for, &resolved));

  ReferenceStillOptions ro;
  ro.width = width;
  ro.height = height;
  ro.reference_step = o.reference_step;
  ro.max_dim = max_dim;
  SessionStep failed_at = SessionStep::kSettings;
  auto still = render_still_reference(o.input, o.flags, camera_for, ro, &failed_at);
  if (!still) {
    const bool usage = failed_at != SessionStep::kSource && still.status().code() == ErrorCode::kInvalidArgument;
    return fail(still.status(), usage ? kExitUsage : kExitFailure);
  }
  for (const std::string& n : still->notes) std::fprintf(stderr, "vxr: note: %s: %s\n", o.input.c_str(), n.c_str());
  if (Status st = write_png(o.output, over_black(still->image)); !st) return fail(st);
  std::printf("%s: %ux%u, %s, CPU reference, %.1f ms\n", o.output.c_str(), width, height,
              optical_model_name(still->settings.model), still->ms);
  if (o.stats)
    std::printf("stats: CPU reference, shrink %u, samples <= %llu (before early termination), %.1f ms\n", still->shrink,
                (unsigned long long)still->sample_bound, still->ms);
  return kExitOk;
}

}  // namespace

void add_render_command(CLI::App& app, Invocation& inv) {
  auto o = std::make_shared<Options>();
  auto* cmd = app.add_subcommand("render", "render one picture of a volume (.vxc, OME-Zarr, TIFF, OME-TIFF, slices, .ims, raw+JSON, procedural:vessels:SIDE) to PNG");
  cmd->add_option("input", o->input, "the volume (optional with --card: the card's volume)");
  cmd->add_option("-o,--out", o->output, "output PNG")->required();
  cmd->add_option("--camera", o->camera, "px,py,pz,tx,ty,tz,ux,uy,uz: eye, target, up in world units (volume centred at 0)");
  cmd->add_option("--fov", o->fov, "vertical field of view in degrees");
  cmd->add_option("--size", o->size, "WxH (default 512x512)");
  add_session_flags(cmd, &o->flags);
  cmd->add_option("--lod-bias", o->lod_bias, "log2 of voxels per pixel accepted (+1 coarser, -1 finer; default 0)");
  cmd->add_option("--frame-budget-ms", o->frame_budget_ms,
                  "render --frames frames, adjusting the LOD bias to hold this frame time");
  cmd->add_option("--frames", o->frames, "frames to render (default: until converged; 30 with a frame budget)");
  cmd->add_flag("--stats", o->stats, "print the final frame's statistics (bricks, samples, uploads, cache hits)");
  cmd->add_flag("--reference", o->reference,
                "draw the CPU reference (double precision, whole volume, slow) instead; with --json: measure each GPU "
                "frame against it");
  cmd->add_option("--reference-step", o->reference_step, "the reference's step in voxels (default 1/16)");
  cmd->add_flag("--no-skip", o->no_skip, "march empty space too (no brick or cell skipping; same image, for timing)");
  cmd->add_flag("--json", o->json,
                "print per-frame GPU ms, wall ms and samples as JSON (with --reference: RMSE against the CPU "
                "reference of the finest level, 8-bit units)");
  add_annotations_option(cmd, o->flags.annotations);
  cmd->add_option("--card", o->card,
                  "STORE:ID (or ID of the --annotations store): restore a card's scene (volume, camera, settings, size); "
                  "flags override");
  cmd->add_option("--save-card", o->save_card, "STORE: also store the picture as a card with the full scene to restore it");
  cmd->add_option("--card-title", o->card_title, "with --save-card: the card's title");
  cmd->add_option("--card-note", o->card_note, "with --save-card: the card's note");
  cmd->callback([&inv, o, cmd] {
    o->lod_bias_given = cmd->count("--lod-bias") > 0;
    o->size_given = cmd->count("--size") > 0;
    note_session_flags(cmd, &o->flags);
    inv.run = [o] { return run(*o); };
  });
}

}  // namespace vxr::cli
