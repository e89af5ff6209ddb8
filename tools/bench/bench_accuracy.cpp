// `vxr bench accuracy`: run time against error for the renderer's speed
// settings, on real datasets from several views, against the CPU
// double-precision reference (step 1/16 voxel, no early termination). Every
// variant is drawn by the one renderer: the volume in memory at full
// resolution (render/lod/memory_volume.h), or a .vxc of it at a LOD bias.
// (Lens-warp error: `vxr bench xr`.)
//
// Every point is one setting; its time is the sum over all scenes (dataset x
// view) of the median wall time of a render, repeats interleaved across
// points so load on the machine spreads evenly; its error is pooled over the
// same scenes (RMSE and max-abs in 8-bit units, PSNR in dB). The Pareto front
// of (time, RMSE) is marked in the plot and listed in the JSON, with the
// default settings' distance from it. Writes out/bench/accuracy.{json,png}.
#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <map>
#include <optional>

#include "assets/assets.h"
#include "bench.h"
#include "bench/pareto.h"
#include "bench/plot.h"
#include "bench/roofline.h"
#include "core/image.h"
#include "render/lod/brick_renderer.h"
#include "render/lod/memory_volume.h"
#include "render/reference_renderer.h"
#include "volume/container_reader.h"
#include "volume/load_dense.h"
#include "volume/memory_slab_source.h"
#include "volume/pyramid_builder.h"

namespace vxr::bench {
namespace {

struct Dataset {
  std::string name;
  DenseVolume volume;
  RenderSettings base;  // window for this dataset
  // The same voxels as a .vxc pyramid, drawn by the out-of-core renderer.
  std::unique_ptr<ContainerReader> container;
  std::unique_ptr<BrickRenderer> bricks;
  std::unique_ptr<MemoryVolumeRenderer> full;  // the same voxels in memory, always level 0
};

struct View {
  std::string name;
  double azimuth, elevation, distance;
};

struct Variant {
  std::string name;
  std::string family;  // "step x termination", "naive opacity", "LOD bias", ...
  RenderSettings settings;
  std::optional<double> lod_bias;  // set: the out-of-core brick renderer at this LOD bias
  bool is_default = false;
};

struct SceneResult {
  std::vector<double> ms;
  double sq_sum = 0.0;  // squared error sum, 8-bit units
  size_t values = 0;
  double max_abs = 0.0;
  uint64_t samples = 0;  // without early termination, from the slab test (for the roofline ratio)
};

// Converts `v` into a .vxc (32^3 chunks, mean pyramid) at `path` and opens a
// brick renderer on it: the out-of-core path over the same voxels.
Status attach_container(gpu::Context& ctx, Dataset& ds, const std::string& path) {
  MemorySlabSource slabs(ds.volume);
  ImportOptions io;
  io.chunk_size = 32;
  VXR_RETURN_IF_ERROR(build_container(slabs, path, io).status());
  VXR_ASSIGN_OR_RETURN(ds.container, ContainerReader::open(path));
  VXR_ASSIGN_OR_RETURN(ds.bricks, BrickRenderer::create(ctx, *ds.container));
  return Status::ok();
}

Camera view_camera(const DenseVolume& v, const View& view) {
  const VolumePlacement p{v.dims, v.voxel_size};
  return orbit_camera(p, view.azimuth, view.elevation, view.distance, 40.0);
}

uint64_t count_samples(const Camera& cam, const DenseVolume& v, uint32_t w, uint32_t h, double step) {
  return dense_sample_count(cam, VolumePlacement{v.dims, v.voxel_size}, step, w, h);
}

void accumulate_error(SceneResult& r, const ImageRgbaF& got, const ImageRgbaF& ref) {
  for (size_t i = 0; i < got.rgba.size(); ++i) {
    const double d = 255.0 * std::abs(double(got.rgba[i]) - double(ref.rgba[i]));
    r.sq_sum += d * d;
    r.max_abs = std::max(r.max_abs, std::isfinite(d) ? d : 1e9);
  }
  r.values += got.rgba.size();
}

ImageRgbaF from_rgba8(const ImageRgba8& img) {
  ImageRgbaF f{img.width, img.height, std::vector<float>(img.pixels.size())};
  for (size_t i = 0; i < img.pixels.size(); ++i) f.rgba[i] = img.pixels[i] / 255.0f;
  return f;
}

std::vector<Variant> make_variants(bool quick) {
  std::vector<Variant> out;
  const RenderSettings defaults;
  auto label = [](double v) {
    char b[32];
    if (v >= 1.0 || v <= 0.0) std::snprintf(b, sizeof b, "%g", v);
    else std::snprintf(b, sizeof b, "1/%g", 1.0 / v);
    return std::string(b);
  };
  const std::vector<double> steps = quick ? std::vector<double>{1.0, 0.5, 0.25}
                                          : std::vector<double>{2.0, 1.0, 0.75, 0.5, 0.35, 0.25, 0.125};
  const std::vector<double> terms = quick ? std::vector<double>{1.0 / 512.0} : std::vector<double>{0.1, 1.0 / 32.0, 1.0 / 512.0, 0.0};
  for (double st : steps)
    for (double et : terms) {
      Variant v;
      v.settings = defaults;
      v.settings.step_voxels = st;
      v.settings.early_termination = et;
      v.family = "step x termination";
      v.name = "step " + label(st) + ", term " + label(et);
      v.is_default = st == defaults.step_voxels && et == defaults.early_termination;
      out.push_back(v);
    }
  for (double st : quick ? std::vector<double>{0.5} : std::vector<double>{1.0, 0.5, 0.25}) {
    Variant v;
    v.settings = defaults;
    v.settings.step_voxels = st;
    v.settings.opacity_correction = false;
    v.family = "naive opacity (a = tau, linear in step)";
    v.name = "naive, step " + label(st);
    out.push_back(v);
  }
  for (double bias : quick ? std::vector<double>{0.0} : std::vector<double>{-1.0, 0.0, 1.0, 2.0}) {
    Variant v;
    v.settings = defaults;
    v.lod_bias = bias;
    v.family = "out-of-core LOD bias (brick renderer)";
    v.name = "lod bias " + label(bias);
    out.push_back(v);
  }
  return out;
}

struct Options {
  BenchOptions common;
  uint32_t size = 128;
  bool quick = false;
  bool roofline = true;
  std::string testdata = VXR_DEFAULT_TESTDATA_DIR;
};

int run(const Options& o) {
  auto gpu = cli::open_gpu();
  if (!gpu) return cli::fail(gpu.status());
  gpu::Context& ctx = **gpu;

  std::vector<Dataset> datasets;
  {
    auto mri = assets::sample_volume();
    if (!mri) return cli::fail(mri.status());
    datasets.push_back({"mri (assets, 186x226x27 u8)", std::move(mri).value(), RenderSettings{}});
    const std::string mask = o.testdata + "/tiff/mri-stack-calibrated.tif";
    auto m = load_for_render(mask, ctx.limits().maxImageDimension3D, uint64_t(1) << 30);
    if (m) {
      RenderSettings s;
      s.density = 0.05;  // a binary mask is all-or-nothing: thinner so the inside shows
      datasets.push_back({"mri mask (testdata tiff, 186x226x27 u8)", std::move(m->channels[0]), s});
    } else {
      std::fprintf(stderr, "accuracy: skipping %s: %s\n", mask.c_str(), m.status().to_string().c_str());
    }
  }
  {
    std::error_code ec;
    std::filesystem::create_directories(o.common.out_dir, ec);
    for (size_t di = 0; di < datasets.size(); ++di) {
      const std::string path =
          (std::filesystem::path(o.common.out_dir) / ("accuracy-dataset-" + std::to_string(di) + ".vxc")).string();
      if (Status s = attach_container(ctx, datasets[di], path); !s) return cli::fail(s);
    }
  }
  const std::vector<View> views = {{"front-left", 30.0, 20.0, 1.3}, {"back-low", 160.0, -35.0, 1.5},
                                   {"top", 250.0, 70.0, 1.4}};
  std::vector<Variant> variants = make_variants(o.quick);
  const uint32_t w = o.size, h = o.size;

  // results[variant][scene]
  const size_t scenes = datasets.size() * views.size();
  std::vector<std::vector<SceneResult>> results(variants.size(), std::vector<SceneResult>(scenes));
  nlohmann::json scene_info = nlohmann::json::array();
  double reference_ms = 0.0;
  for (size_t di = 0; di < datasets.size(); ++di) {
    Dataset& ds = datasets[di];
    auto full = MemoryVolumeRenderer::create(ctx, {ds.volume});
    if (!full) return cli::fail(full.status());
    ds.full = std::move(full).value();
    for (size_t vi = 0; vi < views.size(); ++vi) {
      const size_t si = di * views.size() + vi;
      const Camera cam = view_camera(ds.volume, views[vi]);
      // The reference: exact exponentials, step 1/16, no early termination.
      RenderSettings ref_settings = ds.base;
      ref_settings.early_termination = 0.0;
      ReferenceOptions ro;
      ro.step_voxels = 1.0 / 16.0;
      const auto r0 = std::chrono::steady_clock::now();
      auto ref = render_reference(std::span(&ds.volume, 1), cam, ref_settings, w, h, ro);
      if (!ref) return cli::fail(ref.status());
      reference_ms += ms_since(r0);
      scene_info.push_back({{"dataset", ds.name}, {"view", views[vi].name}, {"azimuth", views[vi].azimuth},
                            {"elevation", views[vi].elevation}, {"distance", views[vi].distance}});
      std::fprintf(stderr, "accuracy: %s, %s: reference done\n", ds.name.c_str(), views[vi].name.c_str());

      auto render_once = [&](const Variant& v, ImageRgbaF* out) -> Status {
        RenderSettings s = v.settings;
        s.channels = ds.base.channels;
        s.density = ds.base.density;
        if (v.lod_bias) {
          // Converged frames only: the first render of a view uploads its bricks.
          BrickFrameSettings f;
          f.lod.lod_bias = *v.lod_bias;
          BrickFrameStats st;
          for (int i = 0;; ++i) {
            VXR_ASSIGN_OR_RETURN(ImageRgba8 img, ds.bricks->render(cam, s, f, w, h, &st));
            if (st.lod.missing == 0) {
              if (out) *out = from_rgba8(img);
              return Status::ok();
            }
            if (i > 100) return internal_error("bench accuracy: the LOD view did not converge in 100 frames");
          }
        }
        VXR_ASSIGN_OR_RETURN(ImageRgbaF img, ds.full->render_float(cam, s, w, h));
        if (out) *out = std::move(img);
        return Status::ok();
      };
      // Error (and warm-up) first, then the timed repeats interleaved over variants.
      for (size_t k = 0; k < variants.size(); ++k) {
        ImageRgbaF img;
        if (Status s = render_once(variants[k], &img); !s) return cli::fail(s);
        accumulate_error(results[k][si], img, *ref);
        results[k][si].samples = count_samples(cam, ds.volume, w, h, variants[k].settings.step_voxels);
      }
      for (int rep = 0; rep < o.common.repeats; ++rep)
        for (size_t k = 0; k < variants.size(); ++k) {
          const auto t0 = std::chrono::steady_clock::now();
          if (Status s = render_once(variants[k], nullptr); !s) return cli::fail(s);
          results[k][si].ms.push_back(ms_since(t0));
        }
    }
  }

  // Aggregate per variant.
  std::vector<TradeoffPoint> pts(variants.size());
  nlohmann::json points = nlohmann::json::array();
  size_t default_index = 0;
  for (size_t k = 0; k < variants.size(); ++k) {
    double ms = 0.0, sq = 0.0, mx = 0.0;
    size_t n = 0;
    uint64_t samples = 0;
    nlohmann::json per_scene = nlohmann::json::array();
    for (size_t si = 0; si < scenes; ++si) {
      const SceneResult& r = results[k][si];
      const double m = median(r.ms);
      ms += m;
      sq += r.sq_sum;
      n += r.values;
      mx = std::max(mx, r.max_abs);
      samples += r.samples;
      per_scene.push_back({{"ms", m}, {"rmse", std::sqrt(r.sq_sum / r.values)}, {"max_abs", r.max_abs}});
    }
    const double rmse = std::sqrt(sq / n);
    pts[k] = {ms, rmse};
    if (variants[k].is_default) default_index = k;
    const RenderSettings& s = variants[k].settings;
    points.push_back({{"name", variants[k].name},
                      {"family", variants[k].family},
                      {"step_voxels", s.step_voxels},
                      {"early_termination", s.early_termination},
                      {"opacity_correction", s.opacity_correction},
                      {"lod_bias", variants[k].lod_bias ? nlohmann::json(*variants[k].lod_bias) : nlohmann::json()},
                      {"default", variants[k].is_default},
                      {"ms", ms},
                      {"ms_per_frame", ms / scenes},
                      {"rmse", rmse},
                      {"max_abs", mx},
                      {"psnr", rmse > 0 ? 20.0 * std::log10(255.0 / rmse) : 999.0},
                      {"samples_without_termination", samples},
                      {"scenes", per_scene}});
  }
  const std::vector<size_t> front = pareto_front(pts);
  for (size_t i : front) points[i]["on_front"] = true;
  for (auto& p : points)
    if (!p.contains("on_front")) p["on_front"] = false;
  const TradeoffPoint d = pts[default_index];
  const double t_front = front_time_at_error(pts, front, d.error);
  const double distance = d.time / t_front - 1.0;
  const bool on_front = std::find(front.begin(), front.end(), default_index) != front.end();

  nlohmann::json doc = {
      {"image", std::to_string(w) + "x" + std::to_string(h)},
      {"repeats", o.common.repeats},
      {"reference", {{"step_voxels", 1.0 / 16.0}, {"early_termination", 0.0}, {"ms_total", reference_ms}}},
      {"time", "sum over scenes of the median wall time of one render (ms), incl. submit and readback"},
      {"error", "pooled over scenes and RGBA channels, 8-bit units (0..255); psnr = 20 log10(255 / rmse)"},
      {"scenes", scene_info},
      {"points", points},
      {"front", nlohmann::json::array()},
      {"default",
       {{"name", variants[default_index].name},
        {"ms", d.time},
        {"rmse", d.error},
        {"on_front", on_front},
        {"front_ms_at_equal_error", t_front},
        {"time_over_front", distance},
        {"within_10_percent", distance <= 0.10}}},
  };
  for (size_t i : front) doc["front"].push_back(variants[i].name);

  // Roofline ratio of the default step (no early termination, so the sample
  // count is exact): samples/s against the trilinear sampling ceiling.
  if (o.roofline) {
    // The frames below and the ceiling kernel are timed in turn, so drift falls on both alike.
    auto ceiling = SamplingCeiling::create(ctx);
    if (!ceiling) return cli::fail(ceiling.status());
    auto roof = measure_roofline(ctx, **ceiling, o.common.repeats);
    if (!roof) return cli::fail(roof.status());
    Variant v = variants[default_index];
    v.settings.early_termination = 0.0;
    const Dataset& ds = datasets[0];
    const Camera cam = view_camera(ds.volume, views[0]);
    BrickFrameStats st;
    std::vector<double> wall_ms, gpu_ms, ceiling_ms;
    for (int i = -1; i < o.common.repeats; ++i) {  // i = -1: warm-up
      const auto t0 = std::chrono::steady_clock::now();
      if (Status s = ds.full->render_float(cam, v.settings, 256, 256, {}, &st).status(); !s.is_ok())
        return cli::fail(s);
      const double wall = ms_since(t0);
      auto c = (*ceiling)->time_ms();
      if (!c) return cli::fail(c.status());
      if (i < 0) continue;
      wall_ms.push_back(wall);
      gpu_ms.push_back(st.gpu_ms);
      ceiling_ms.push_back(*c);
    }
    const double ms = median(wall_ms), ceiling_rate = SamplingCeiling::samples() / (median(ceiling_ms) * 1e-3);
    const uint64_t samples = st.samples;  // the shader's count (no early termination; empty space skipped)
    const double rate = samples / (ms * 1e-3), gpu = median(gpu_ms);
    doc["roofline"] = {{"scene", ds.name + ", " + views[0].name + ", 256x256, default step, no early termination"},
                       {"ms", ms},
                       {"gpu_ms", gpu},
                       {"samples", samples},
                       {"samples_per_s", rate},
                       // Timed in turn with the frames; the calibration's figure is the device's.
                       {"trilinear_ceiling_samples_per_s", ceiling_rate},
                       {"calibrated_trilinear_samples_per_s", roof->trilinear_samples_per_s},
                       {"copy_gb_per_s", roof->copy_gb_per_s},
                       {"roofline_ratio", rate / ceiling_rate},
                       // The same on GPU time alone (no submit/readback): what the shader
                       // achieves once a frame is big enough to hide the fixed costs.
                       {"roofline_ratio_gpu_time", gpu > 0 ? samples / (gpu * 1e-3) / ceiling_rate : 0.0}};
    std::fprintf(stderr, "accuracy: default step %.0f M samples/s = %.2f of the %.0f M/s trilinear ceiling\n",
                 rate / 1e6, rate / ceiling_rate, ceiling_rate / 1e6);
  }

  // The plot: each family its own colour, the front as a line, the default ringed.
  PlotSpec plot;
  plot.title = "renderer: time vs error against the CPU double reference";
  plot.x_label = "time, ms (sum over " + std::to_string(scenes) + " scenes)";
  plot.y_label = "RMSE (8-bit units)";
  plot.log_x = true;
  plot.log_y = true;
  std::map<std::string, size_t> family_series;
  for (size_t k = 0; k < variants.size(); ++k) {
    auto it = family_series.find(variants[k].family);
    if (it == family_series.end()) {
      PlotSeries s;
      s.label = variants[k].family;
      s.color = series_colour(family_series.size());
      plot.series.push_back(s);
      it = family_series.emplace(variants[k].family, plot.series.size() - 1).first;
    }
    plot.series[it->second].x.push_back(pts[k].time);
    plot.series[it->second].y.push_back(pts[k].error);
  }
  PlotSeries fr;
  fr.label = "Pareto front";
  fr.color = {0, 0, 0};
  fr.line = true;
  fr.marker_radius = 2;
  for (size_t i : front) fr.x.push_back(pts[i].time), fr.y.push_back(pts[i].error);
  plot.series.push_back(fr);
  PlotSeries def;
  def.label = "default (" + variants[default_index].name + ")";
  def.color = {227, 119, 194};
  def.marker_radius = 7;
  def.x = {d.time};
  def.y = {d.error};
  plot.series.push_back(def);
  auto png = write_plot(o.common, "accuracy", plot);
  if (!png) return cli::fail(png.status());
  const std::string& png_path = *png;
  doc["plot"] = png_path;

  std::fprintf(stderr, "accuracy: %zu points, %zu on the front; default %s: %.1f ms, RMSE %.3f, %s (%.1f%% over the front's time at equal error)\n",
               variants.size(), front.size(), variants[default_index].name.c_str(), d.time, d.error,
               on_front ? "on the front" : "off the front", 100.0 * distance);
  auto path = write_report(o.common, "accuracy", doc, &ctx);
  if (!path) return cli::fail(path.status());
  std::printf("%s\n", png_path.c_str());
  return cli::kExitOk;
}

}  // namespace

void add_accuracy_bench(CLI::App& bench, cli::Invocation& inv) {
  auto* cmd = bench.add_subcommand("accuracy", "time vs error of the ray caster's settings against the CPU reference");
  auto o = std::make_shared<Options>();
  add_common_options(cmd, o->common);
  cmd->add_option("--size", o->size, "image side in pixels (default 128)")->check(CLI::Range(8u, 1024u));
  cmd->add_flag("--quick", o->quick, "a handful of points (smoke test)");
  cmd->add_option("--testdata", o->testdata, "the shared testdata folder (for tiff/mri-stack-calibrated.tif)");
  cmd->add_flag("!--no-roofline", o->roofline, "skip the roofline calibration");
  cmd->callback([&inv, o] { inv.run = [o] { return run(*o); }; });
}

}  // namespace vxr::bench
