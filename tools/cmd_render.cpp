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
#include <fstream>
#include <sstream>

#include "command.h"
#include "core/trace.h"
#include "render/camera.h"
#include "render/raycaster.h"
#include "render/reference_renderer.h"
#include "render/transfer_function.h"
#include "scene/render_settings.h"
#include "volume/load_dense.h"

namespace vxr::cli {
namespace {

struct Options {
  std::string input, output, settings_path, camera, size = "512x512", model, colormap, window, path = "compute";
  double fov = 0.0, step = 0.0, reference_step = 1.0 / 16.0;
  bool reference = false;
};

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

int run(const Options& o) {
  VXR_TRACE_SCOPE("render");
  // Settings first: a bad setting is a usage error even before any file is read.
  Scene scene;
  bool window_given = false;
  if (!o.settings_path.empty()) {
    auto text = read_text(o.settings_path);
    if (!text) return fail(text.status(), kExitUsage);
    const bool is_scene = text->find("\"render\"") != std::string::npos;
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

  std::unique_ptr<gpu::Context> gpu;
  uint32_t max_dim = 2048;
  if (!o.reference) {
    auto g = open_gpu();
    if (!g) return fail(g.status());
    gpu = std::move(g).value();
    max_dim = std::min(max_dim, gpu->limits().maxImageDimension3D);
  }
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
  Camera camera = channels[0].dims[2] == 1 ? orbit_camera(placement, 0.0, 90.0 - 1e-3, 1.1)
                                           : orbit_camera(placement, 30.0, 25.0, 1.25);
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
  return kExitOk;
}

}  // namespace

void add_render_command(CLI::App& app, Invocation& inv) {
  auto o = std::make_shared<Options>();
  auto* cmd = app.add_subcommand("render", "render one picture of a volume (TIFF, OME-TIFF, slices, .ims, raw+JSON) to PNG");
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
  cmd->add_flag("--reference", o->reference, "render with the CPU reference renderer (double precision, slow)");
  cmd->add_option("--reference-step", o->reference_step, "the reference's step in voxels (default 1/16)");
  cmd->callback([&inv, o] { inv.run = [o] { return run(*o); }; });
}

}  // namespace vxr::cli
