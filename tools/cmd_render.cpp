// `vxr render INPUT -o out.png`: one picture of a volume, on the GPU (compute
// or fragment path) or with the CPU reference renderer (--reference).
//
// Settings come from --settings (a RenderSettings JSON, or a Scene JSON with
// "render" and "camera"), then the flags override them. Without a window the
// 0.5..99.5 percentiles of each channel are used. Bad settings exit 2 with one
// line naming the setting.
#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <functional>
#include <sstream>

#include "command.h"
#include "core/output_file.h"
#include "core/trace.h"
#include "render/camera.h"
#include "render/lod/brick_renderer.h"
#include "render/raycaster.h"
#include "render/reference_renderer.h"
#include "render/transfer_function.h"
#include "render/volume_session.h"
#include "scene/render_settings.h"
#include "volume/container_reader.h"
#include "volume/load_dense.h"
#include "volume/open_chunk_source.h"
#include "volume/procedural_source.h"

namespace vxr::cli {
namespace {

struct Options {
  std::string input, output, settings_path, camera, size = "512x512", model, colormap, window, path = "compute";
  std::string renderer;  // "" = lod for chunk sources (.vxc, OME-Zarr) and procedural: inputs, dense otherwise
  double fov = 0.0, step = 0.0, reference_step = 1.0 / 16.0;
  double lod_bias = 0.0, frame_budget_ms = 0.0;
  bool lod_bias_given = false;
  int frames = 0;  // 0: until converged (lod) / one frame (dense)
  bool reference = false, stats = false;
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

// Values at the 0.5 and 99.5 percentiles of the channel (sampled), in data units.
std::pair<double, double> auto_window(const DenseVolume& v) {
  std::vector<double> s;
  const uint64_t n = v.voxel_count();
  const uint64_t stride = std::max<uint64_t>(1, n / 200000);
  for (uint64_t i = 0; i < n; i += stride) {
    const uint64_t x = i % v.dims[0], y = (i / v.dims[0]) % v.dims[1], z = i / (uint64_t(v.dims[0]) * v.dims[1]);
    s.push_back(v.value_at(static_cast<uint32_t>(x), static_cast<uint32_t>(y), static_cast<uint32_t>(z)));
  }
  std::sort(s.begin(), s.end());
  double lo = s[static_cast<size_t>(0.005 * (s.size() - 1))], hi = s[static_cast<size_t>(0.995 * (s.size() - 1))];
  if (!(hi > lo)) lo = s.front(), hi = s.back();
  if (!(hi > lo)) hi = lo + 1.0;
  return {lo, hi};
}

Result<std::string> read_text(const std::string& path) {
  std::ifstream f(path, std::ios::binary);
  if (!f) return not_found(path + ": cannot open the settings file");
  std::stringstream ss;
  ss << f.rdbuf();
  return ss.str();
}

using CameraMaker = std::function<int(const VolumePlacement&, bool, Camera*)>;

// The out-of-core path: a .vxc container, an OME-Zarr folder or a procedural source through the
// brick renderer. Without --frame-budget-ms it renders until nothing is
// missing (every wanted brick resident) and writes that frame; with it, it
// renders --frames frames (default 30) letting the frame-budget controller set
// the LOD bias, and writes the last.
int run_lod(const Options& o, RenderSettings s, bool window_given, gpu::Context& gpu, bool procedural, uint32_t width,
            uint32_t height, const CameraMaker& make_camera) {
  std::unique_ptr<ChunkSource> src;
  if (procedural) {
    auto p = open_procedural(o.input);
    if (!p) return fail(p.status(), kExitUsage);
    src = std::move(p).value();
    if (!window_given) {  // `vxr bench lod`'s: above the background noise (0..6)
      s.channels[0].window_lo = 8;
      s.channels[0].window_hi = 200;
      window_given = true;
    }
  } else {
    auto r = open_chunk_source(o.input);
    if (!r) return fail(r.status());
    for (const std::string& w : r->warnings) std::fprintf(stderr, "vxr: note: %s: %s\n", o.input.c_str(), w.c_str());
    src = std::move(r->source);
  }
  const VolumeInfo& info = src->info();
  if (info.dtype != DType::kU8 && info.dtype != DType::kU16)
    return fail(invalid_argument(o.input + ": the out-of-core renderer draws u8 or u16 data, this is " +
                                 dtype_name(info.dtype) + "; use --renderer dense"),
                kExitUsage);
  if (info.channels > 1 || info.timepoints > 1)
    std::fprintf(stderr, "vxr: note: %s: the out-of-core renderer draws channel 0 of timepoint 0 (of %u channels, %u "
                         "timepoints); --renderer dense draws all channels\n",
                 o.input.c_str(), info.channels, info.timepoints);
  if (!window_given) {
    // Percentiles of a level small enough to read whole (~2 M voxels).
    const uint32_t level = finest_level_that_fits(*src, 4096, uint64_t(2) << 20);
    auto dense = read_level_dense(*src, level, 0, 0, uint64_t(64) << 20);
    if (!dense) return fail(dense.status());
    auto [lo, hi] = auto_window(*dense);
    s.channels[0].window_lo = lo;
    s.channels[0].window_hi = hi;
  }
  if (Status st = validate_render_settings(s, 1); !st) return fail(st, kExitUsage);
  if (Status st = check_brick_settings(s); !st) return fail(st, kExitUsage);

  auto renderer = BrickRenderer::create(gpu, *src);
  if (!renderer) return fail(renderer.status());
  BrickRenderer& r = **renderer;
  const VolumePlacement placement = r.placement();
  Camera camera;
  if (int rc = make_camera(placement, info.dims[2] == 1, &camera); rc != kExitOk) return rc;

  BrickFrameSettings frame;
  frame.lod.lod_bias = o.lod_bias;
  const bool budget = o.frame_budget_ms > 0.0;
  FrameBudget controller;
  controller.target_ms = o.frame_budget_ms;
  controller.bias = o.lod_bias;
  const int max_frames = o.frames > 0 ? o.frames : budget ? 30 : 1000;
  BrickFrameStats st;
  uint64_t total_bytes = 0, total_bricks = 0;
  std::vector<double> frame_ms;
  Result<ImageRgba8> image = invalid_argument("unset");
  int frames = 0;
  bool converged = false;
  const auto t0 = std::chrono::steady_clock::now();
  while (frames < max_frames) {
    if (budget) frame.lod.lod_bias = controller.bias;
    const auto f0 = std::chrono::steady_clock::now();
    image = r.render(camera, s, frame, width, height, &st);
    if (!image) return fail(image.status(), image.status().code() == ErrorCode::kInvalidArgument ? kExitUsage : kExitFailure);
    const double ms = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - f0).count();
    frame_ms.push_back(ms);
    ++frames;
    total_bytes += st.bytes_uploaded;
    total_bricks += st.bricks_uploaded;
    if (budget) {
      if (o.stats)
        std::printf("frame %d: bias %.2f, %.1f ms, drawn %llu, missing %llu\n", frames, frame.lod.lod_bias, ms,
                    (unsigned long long)st.lod.drawn, (unsigned long long)st.lod.missing);
      controller.update(ms);
      continue;
    }
    converged = st.lod.missing == 0;
    if (converged && o.frames == 0) break;
  }
  const double total_ms = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
  if (!budget && o.frames == 0 && !converged)
    return fail(internal_error(o.input + ": the view still missed bricks after " + std::to_string(frames) +
                               " frames; raise --lod-bias or render fewer pixels"));
  if (Status e = write_png(o.output, over_black(*image)); !e) return fail(e);
  std::printf("%s: %ux%u, %s, out-of-core (lod), %d frames%s, %.1f ms\n", o.output.c_str(), width, height,
              optical_model_name(s.model), frames, converged ? " to converge" : "", total_ms);
  if (budget) {
    // Median of the last few frames: what the controller settled on.
    std::vector<double> tail(frame_ms.end() - std::min<size_t>(frame_ms.size(), 5), frame_ms.end());
    std::sort(tail.begin(), tail.end());
    std::printf("frame budget: target %.1f ms, bias %.2f -> %.2f, last frames %.1f ms (median of %zu)\n",
                o.frame_budget_ms, o.lod_bias, frame.lod.lod_bias, tail[tail.size() / 2], tail.size());
  }
  if (o.stats) {
    std::printf("stats: %s\n", format_stats(st).c_str());
    std::printf("stats: %d frames, %llu bricks %.2f MiB uploaded in all, pool %u of %u bricks\n", frames,
                (unsigned long long)total_bricks, double(total_bytes) / (1 << 20), r.pool().used(), r.pool().capacity());
  }
  return kExitOk;
}

int run(const Options& o) {
  VXR_TRACE_SCOPE("render");
  if (!starts_with(o.input, "procedural:")) {
    if (Status st = check_input(o.input, /*allow_dir=*/true); !st) return fail(st);
  }
  if (Status st = check_output(o.output, {{o.input, o.settings_path}}, "-o"); !st) return fail(st, kExitUsage);
  if (!o.settings_path.empty()) {
    if (Status st = check_input(o.settings_path); !st) return fail(st, kExitUsage);
  }
  // Settings first: a bad setting is a usage error even before any file is read.
  Scene scene;
  bool window_given = false;
  if (!o.settings_path.empty()) {
    auto text = read_text(o.settings_path);
    if (!text) return fail(text.status(), kExitUsage);
    // A Scene has a render, camera or volume section; plain RenderSettings have none.
    const bool is_scene = text->find("\"render\"") != std::string::npos || text->find("\"camera\"") != std::string::npos ||
                          text->find("\"volume\"") != std::string::npos;
    if (is_scene) {
      auto sc = scene_from_json(*text);
      if (!sc) return fail(invalid_argument(o.settings_path + ": " + sc.status().message()), kExitUsage);
      scene = *sc;
    } else {
      auto rs = render_settings_from_json(*text);
      if (!rs) return fail(invalid_argument(o.settings_path + ": " + rs.status().message()), kExitUsage);
      scene.render = *rs;
    }
    window_given = text->find("\"window\"") != std::string::npos;
  }
  RenderSettings& s = scene.render;
  if (!o.model.empty() && !optical_model_from_name(o.model, &s.model))
    return fail(invalid_argument("--model: unknown optical model '" + o.model +
                                 "' (use ea, emission, mip, minip, average or iso)"),
                kExitUsage);
  if (!o.colormap.empty()) s.channels[0].colormap = o.colormap;
  if (!o.window.empty()) {
    std::vector<double> w;
    if (!parse_doubles(o.window, 2, w)) return fail(invalid_argument("--window: expected lo,hi, got '" + o.window + "'"), kExitUsage);
    if (!(w[1] > w[0]))
      return fail(invalid_argument("--window: lo " + o.window.substr(0, o.window.find(',')) + " must be below hi"), kExitUsage);
    s.channels[0].window_lo = w[0];
    s.channels[0].window_hi = w[1];
    window_given = true;
  }
  if (o.step != 0.0) s.step_voxels = o.step;
  if (!(s.step_voxels > 0.0)) return fail(invalid_argument("--step: must be > 0 voxels"), kExitUsage);
  uint32_t width = 0, height = 0;
  if (std::sscanf(o.size.c_str(), "%ux%u", &width, &height) != 2 || width == 0 || height == 0 || width > 16384 ||
      height > 16384)
    return fail(invalid_argument("--size: expected WxH like 512x512, got '" + o.size + "'"), kExitUsage);
  if (o.path != "compute" && o.path != "fragment")
    return fail(invalid_argument("--path: use compute or fragment, not '" + o.path + "'"), kExitUsage);
  // Settings that do not depend on the data (colormap names, windows, steps).
  if (Status st = validate_render_settings(s, static_cast<uint32_t>(std::max<size_t>(1, s.channels.size()))); !st)
    return fail(st, kExitUsage);

  // Which renderer: the out-of-core brick renderer for containers and
  // procedural sources (the product's path for them), the dense one otherwise.
  const bool procedural = starts_with(o.input, "procedural:");
  const bool container = is_chunk_source_input(o.input);  // .vxc or OME-Zarr, read in place
  if (!o.renderer.empty() && o.renderer != "lod" && o.renderer != "dense")
    return fail(invalid_argument("--renderer: use lod or dense, not '" + o.renderer + "'"), kExitUsage);
  std::string renderer = o.renderer;
  if (renderer.empty()) renderer = (procedural || container) && !o.reference ? "lod" : "dense";
  if (renderer == "lod" && !procedural && !container)
    return fail(invalid_argument("--renderer lod: '" + o.input + "' is not a .vxc container or OME-Zarr folder; "
                                 "convert it with `vxr import` first, or use --renderer dense"),
                kExitUsage);
  if (renderer == "dense" && procedural)
    return fail(invalid_argument("--renderer dense: a procedural source is drawn only by --renderer lod"), kExitUsage);
  if (renderer == "lod" && o.reference)
    return fail(invalid_argument("--reference: the CPU reference draws a whole volume; use --renderer dense"), kExitUsage);
  if (renderer == "dense" && (o.lod_bias_given || o.frame_budget_ms != 0.0))
    return fail(invalid_argument(std::string(o.lod_bias_given ? "--lod-bias" : "--frame-budget-ms") +
                                 ": only the out-of-core renderer has levels of detail; use --renderer lod with a .vxc"),
                kExitUsage);
  if (o.frame_budget_ms < 0.0 || !std::isfinite(o.frame_budget_ms))
    return fail(invalid_argument("--frame-budget-ms: must be > 0 milliseconds"), kExitUsage);
  if (o.frames < 0 || o.frames > 100000) return fail(invalid_argument("--frames: must be 1..100000"), kExitUsage);
  // The reference marches every sample in double on the CPU: below 1/256 voxel it would run for days.
  if (o.reference && !(o.reference_step >= 1.0 / 256 && o.reference_step <= 64.0))
    return fail(invalid_argument("--reference-step: must be within 1/256..64 voxels (default 1/16)"), kExitUsage);
  if (!std::isfinite(o.lod_bias) || std::abs(o.lod_bias) > 16.0)
    return fail(invalid_argument("--lod-bias: must be within -16..16 (log2 of voxels per pixel)"), kExitUsage);

  std::unique_ptr<gpu::Context> gpu;
  uint32_t max_dim = 2048;
  if (!o.reference) {
    auto g = open_gpu();
    if (!g) return fail(g.status());
    gpu = std::move(g).value();
    max_dim = std::min(max_dim, gpu->limits().maxImageDimension3D);
  }

  // The camera: the default orbit view, then the scene's, then the flags.
  auto make_camera = [&](const VolumePlacement& placement, bool flat, Camera* out) -> int {
    Camera camera = flat ? orbit_camera(placement, 0.0, 90.0 - 1e-3, 1.1) : orbit_camera(placement, 30.0, 25.0, 1.25);
    if (scene.has_camera) {
      camera.eye = {scene.camera.eye[0], scene.camera.eye[1], scene.camera.eye[2]};
      camera.target = {scene.camera.target[0], scene.camera.target[1], scene.camera.target[2]};
      camera.up = {scene.camera.up[0], scene.camera.up[1], scene.camera.up[2]};
      camera.fov_y_deg = scene.camera.fov_y_deg;
    }
    if (!o.camera.empty()) {
      std::vector<double> c;
      if (!parse_doubles(o.camera, 9, c))
        return fail(invalid_argument("--camera: expected 9 numbers px,py,pz,tx,ty,tz,ux,uy,uz (world units, volume "
                                     "centred at 0), got '" + o.camera + "'"),
                    kExitUsage);
      camera.eye = {c[0], c[1], c[2]};
      camera.target = {c[3], c[4], c[5]};
      camera.up = {c[6], c[7], c[8]};
    }
    if (o.fov != 0.0) {
      if (!(o.fov > 0.0 && o.fov < 179.0)) return fail(invalid_argument("--fov: must be in (0, 179) degrees"), kExitUsage);
      camera.fov_y_deg = o.fov;
    }
    if (glm::length(camera.target - camera.eye) == 0.0)
      return fail(invalid_argument("--camera: the eye and the target are the same point"), kExitUsage);
    *out = camera;
    return kExitOk;
  };

  if (renderer == "lod") return run_lod(o, s, window_given, *gpu, procedural, width, height, make_camera);

  auto loaded = load_for_render(o.input, max_dim, uint64_t(1) << 30);
  if (!loaded) return fail(loaded.status());
  for (const auto& note : loaded->notes) std::fprintf(stderr, "vxr: note: %s\n", note.c_str());
  std::vector<DenseVolume>& channels = loaded->channels;

  // Channels without settings get their own: single-hue colours, auto windows.
  const char* hues[4] = {"green", "magenta", "cyan", "yellow"};
  for (size_t c = s.channels.size(); c < channels.size(); ++c) {
    ChannelSettings ch = s.channels[0];
    ch.colormap = channels.size() > 1 ? hues[c] : ch.colormap;
    ch.color_points.clear();
    s.channels.push_back(ch);
  }
  if (channels.size() > 1 && o.colormap.empty() && s.channels[0].colormap == "gray") s.channels[0].colormap = hues[0];
  for (size_t c = 0; c < channels.size(); ++c)
    if (!window_given || c > 0) {
      auto [lo, hi] = auto_window(channels[c]);
      if (c > 0 && window_given) continue;
      s.channels[c].window_lo = lo;
      s.channels[c].window_hi = hi;
    }
  if (s.iso_value == RenderSettings{}.iso_value && !window_given)
    s.iso_value = 0.5 * (s.channels[0].window_lo + s.channels[0].window_hi);
  if (Status st = validate_render_settings(s, static_cast<uint32_t>(channels.size())); !st) return fail(st, kExitUsage);

  const VolumePlacement placement{channels[0].dims, channels[0].voxel_size};
  Camera camera;
  if (int rc = make_camera(placement, channels[0].dims[2] == 1, &camera); rc != kExitOk) return rc;

  const auto t0 = std::chrono::steady_clock::now();
  Result<ImageRgbaF> image = invalid_argument("unset");
  if (o.reference) {
    image = render_reference(channels, camera, s, width, height, {o.reference_step, 0});
  } else {
    auto caster = Raycaster::create(*gpu);
    if (!caster) return fail(caster.status());
    if (Status st = (*caster)->set_channels(channels); !st) return fail(st);
    image = (*caster)->render_float(camera, s, width, height,
                                    o.path == "fragment" ? RenderPath::kFragment : RenderPath::kCompute);
  }
  if (!image) return fail(image.status(), image.status().code() == ErrorCode::kInvalidArgument ? kExitUsage : kExitFailure);
  const double ms = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
  if (Status st = write_png(o.output, over_black(to_rgba8(*image))); !st) return fail(st);
  std::printf("%s: %ux%u, %s, %s, %.1f ms\n", o.output.c_str(), width, height, optical_model_name(s.model),
              o.reference ? "CPU reference" : (o.path + " path").c_str(), ms);
  if (o.stats) {
    // The dense renderer keeps no counters: the samples are counted here from
    // the rays (slab test per pixel), before early termination.
    const uint64_t n = dense_sample_count(camera, placement, s.step_voxels, width, height);
    std::printf("stats: renderer dense, shrink %u, samples <= %llu (before early termination), %.1f ms\n",
                loaded->shrink, (unsigned long long)n, ms);
  }
  return kExitOk;
}

}  // namespace

void add_render_command(CLI::App& app, Invocation& inv) {
  auto o = std::make_shared<Options>();
  auto* cmd = app.add_subcommand("render", "render one picture of a volume (.vxc, OME-Zarr, TIFF, OME-TIFF, slices, .ims, raw+JSON, procedural:vessels:SIDE) to PNG");
  cmd->add_option("input", o->input, "the volume")->required();
  cmd->add_option("-o,--out", o->output, "output PNG")->required();
  cmd->add_option("--settings", o->settings_path, "render settings JSON (RenderSettings, or a Scene with render+camera)");
  cmd->add_option("--camera", o->camera, "px,py,pz,tx,ty,tz,ux,uy,uz: eye, target, up in world units (volume centred at 0)");
  cmd->add_option("--fov", o->fov, "vertical field of view in degrees");
  cmd->add_option("--size", o->size, "WxH (default 512x512)");
  cmd->add_option("--model", o->model, "ea | emission | mip | minip | average | iso");
  cmd->add_option("--colormap", o->colormap, "gray, viridis, magma, inferno, plasma, turbo, hot, red, green, blue, cyan, magenta, yellow");
  cmd->add_option("--window", o->window, "lo,hi in data units (default: 0.5..99.5 percentiles)");
  cmd->add_option("--step", o->step, "sample step in voxels");
  cmd->add_option("--path", o->path, "compute (default) or fragment");
  cmd->add_option("--renderer", o->renderer,
                  "lod (out-of-core bricks; default for .vxc, OME-Zarr and procedural:vessels:SIDE) or dense (whole volume)");
  cmd->add_option("--lod-bias", o->lod_bias, "lod: log2 of voxels per pixel accepted (+1 coarser, -1 finer; default 0)");
  cmd->add_option("--frame-budget-ms", o->frame_budget_ms,
                  "lod: render --frames frames, adjusting the LOD bias to hold this frame time");
  cmd->add_option("--frames", o->frames, "lod: frames to render (default: until converged; 30 with a frame budget)");
  cmd->add_flag("--stats", o->stats, "print the final frame's statistics (bricks, samples, uploads, cache hits)");
  cmd->add_flag("--reference", o->reference, "render with the CPU reference renderer (double precision, slow)");
  cmd->add_option("--reference-step", o->reference_step, "the reference's step in voxels (default 1/16)");
  cmd->callback([&inv, o, cmd] {
    o->lod_bias_given = cmd->count("--lod-bias") > 0;
    inv.run = [o] { return run(*o); };
  });
}

}  // namespace vxr::cli
