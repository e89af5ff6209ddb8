// `vxr bench roofline`: the device's ceilings and the brick renderer's share
// of the trilinear one. Each scene is drawn at full resolution (LOD level 0,
// every brick preloaded, empty-space skipping on), 512x512; its rate is the
// samples the rays took (the shader's counter) per second of GPU time
// (timestamps around the frame), so upload, readback and submission are out.
// Its share is taken against the ceiling kernel timed in turn with its
// frames (the calibration printed first is only the device's figure).
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <optional>

#include "assets/assets.h"
#include "bench.h"
#include "bench/plot.h"
#include "render/camera.h"
#include "render/lod/brick_renderer.h"
#include "render/volume_session.h"
#include "bench/brick_timing.h"
#include "roofline.h"
#include "volume/dense_chunk_source.h"
#include "volume/procedural_source.h"

namespace vxr::bench {
namespace {


struct Scene {
  std::string name;
  std::shared_ptr<ChunkSource> source;
  RenderSettings settings;
};

// `vxr bench peer`'s transfer function at `step`.
RenderSettings ramp(OpticalModel model, double lo, double hi, double step) {
  RenderSettings s = vtk_ramp(model, lo, hi);
  s.step_voxels = step;
  return s;
}

Result<std::vector<Scene>> scenes() {
  std::vector<Scene> out;
  // Dense: every sample classified, nothing to skip; faint, so no ray terminates.
  DenseVolume wave;
  wave.dims = {256, 256, 256};
  wave.data.resize(wave.voxel_count());
  for (uint32_t z = 0, i = 0; z < 256; ++z)
    for (uint32_t y = 0; y < 256; ++y)
      for (uint32_t x = 0; x < 256; ++x, ++i)
        wave.data[i] = static_cast<uint8_t>(127.5 + 127.5 * std::sin(x * 0.11) * std::cos(y * 0.07 + z * 0.05));
  VXR_ASSIGN_OR_RETURN(auto wave_src, DenseChunkSource::create({std::move(wave)}));
  RenderSettings dense_ea = ramp(OpticalModel::kEmissionAbsorption, 0, 255, 1.0);
  dense_ea.density = 0.002;
  out.push_back({"dense 256^3 ea", wave_src, dense_ea});
  out.push_back({"dense 256^3 mip", wave_src, ramp(OpticalModel::kMip, 0, 255, 1.0)});
  // The peer scenes (`vxr bench peer`) at step 0.5, skipping on.
  VXR_ASSIGN_OR_RETURN(DenseVolume mri, assets::sample_volume());
  const double lo = 75.0, hi = std::max(percentile_window(mri).second, lo + 1.0);
  VXR_ASSIGN_OR_RETURN(auto mri_src, DenseChunkSource::create({std::move(mri)}));
  out.push_back({"mri ea", mri_src, ramp(OpticalModel::kEmissionAbsorption, lo, hi, 0.5)});
  out.push_back({"mri mip", mri_src, ramp(OpticalModel::kMip, lo, hi, 0.5)});
  ProceduralOptions po;
  po.noise_max = 6;
  po.occupancy = 0.10;
  VXR_ASSIGN_OR_RETURN(auto vessels, ProceduralSource::create(po));
  RenderSettings vs = ramp(OpticalModel::kEmissionAbsorption, 8, 200, 0.5);
  vs.density = 0.3;
  out.push_back({"vessels 256^3 ea", std::shared_ptr<ChunkSource>(std::move(vessels)), vs});
  return out;
}

// Each scene's share of the trilinear ceiling (the frame, and its fetch-only
// probe where it has one) at x = its number, and the ceiling across.
PlotSpec roofline_plot(const nlohmann::json& rows, uint32_t size) {
  PlotSpec plot;
  plot.title = "vxr bench roofline: share of the ceiling, " + std::to_string(size) + "x" + std::to_string(size);
  plot.x_label = "scene (legend)";
  plot.y_label = "samples/s over the ceiling's, timed in turn";
  plot.y_from_zero = true;  // shares read as heights
  for (size_t i = 0; i < rows.size(); ++i) {
    const double x = double(i + 1), ceiling = rows[i]["ceiling_samples_per_s"];
    PlotSeries frame;
    frame.label = std::to_string(i + 1) + ": " + rows[i]["scene"].get<std::string>();
    frame.color = series_colour(i);
    frame.marker_radius = 5;
    frame.x = {x};
    frame.y = {rows[i]["roofline_ratio"].get<double>()};
    plot.series.push_back(std::move(frame));
    if (rows[i].contains("fetch_only")) {
      PlotSeries fetch;
      fetch.label = std::to_string(i + 1) + ": fetch only";
      fetch.color = lighter(series_colour(i));
      fetch.x = {x};
      fetch.y = {rows[i]["fetch_only"]["samples_per_s"].get<double>() / ceiling};
      plot.series.push_back(std::move(fetch));
    }
  }
  PlotSeries top;
  top.label = "the ceiling";
  top.color = {0, 0, 0};
  top.line = true;
  top.markers = false;
  top.x = {0.5, double(rows.size()) + 0.5};
  top.y = {1.0, 1.0};
  plot.series.push_back(std::move(top));
  return plot;
}

// The frame and, for E-A scenes, its probes (the fetch alone, then neither):
// every brick resident, then `repeats` rounds that draw each in turn with
// one run of the ceiling kernel, so the machine's drift falls on all alike;
// median GPU and wall ms of each, and the ceiling's median rate.
struct SceneTimes {
  TimedFrames frame;
  std::optional<TimedFrames> fetch_only, march_only;
  double ceiling_samples_per_s = 0.0;
};

Result<SceneTimes> measure(gpu::Context& ctx, SamplingCeiling& ceiling, const Scene& sc, uint32_t size, int repeats) {
  BrickRendererOptions ro;
  ro.preload_if_fits = true;
  VXR_ASSIGN_OR_RETURN(auto r, BrickRenderer::create(ctx, *sc.source, ro));
  const Camera cam = orbit_camera(r->placement(), 30.0, 25.0, 1.25);
  std::vector<SampleWork> works = {SampleWork::kShade};
  if (sc.settings.model == OpticalModel::kEmissionAbsorption)
    works.insert(works.end(), {SampleWork::kFetchOnly, SampleWork::kMarchOnly});
  std::vector<BrickFrameSettings> frames(works.size());
  for (size_t w = 0; w < works.size(); ++w) {
    frames[w].lod.force_level = 0;
    frames[w].sample_work = works[w];
  }
  std::vector<double> ceiling_ms;
  VXR_ASSIGN_OR_RETURN(std::vector<TimedFrames> t,
                       time_in_turn(*r, cam, sc.settings, frames, size, repeats, [&]() -> Status {
                         VXR_ASSIGN_OR_RETURN(double ms, ceiling.time_ms());
                         ceiling_ms.push_back(ms);
                         return Status::ok();
                       }));
  for (const TimedFrames& f : t)
    if (f.gpu_ms <= 0.0) return unsupported("bench roofline: the device has no timestamps");
  SceneTimes out{t[0], std::nullopt, std::nullopt, SamplingCeiling::samples() / (median(ceiling_ms) * 1e-3)};
  if (works.size() == 3) out.fetch_only = t[1], out.march_only = t[2];
  return out;
}

}  // namespace

void add_roofline_bench(CLI::App& bench, cli::Invocation& inv) {
  auto* cmd = bench.add_subcommand("roofline",
                                   "measure the device's memory and sampling ceilings and the brick renderer's share");
  auto opt = std::make_shared<BenchOptions>();
  add_common_options(cmd, *opt);
  // A GPU draws 512x512 in about one wave of its cores (launch and tail, not
  // sampling): larger images show its sampling share.
  auto size = std::make_shared<uint32_t>(512);
  cmd->add_option("--size", *size, "image width and height in pixels of the scenes' frames (default 512)")
      ->check(CLI::Range(16u, 4096u));
  cmd->callback([&inv, opt, size] {
    inv.run = [opt, size] {
      auto gpu = cli::open_gpu();
      if (!gpu) return cli::fail(gpu.status());
      gpu::Context& ctx = **gpu;
      std::fprintf(stderr, "roofline: calibrating %s ...\n", ctx.info().name.c_str());
      // Timed again in turn with each scene's frames: its share is taken against that.
      auto ceiling = SamplingCeiling::create(ctx);
      if (!ceiling) return cli::fail(ceiling.status());
      auto roof = measure_roofline(ctx, **ceiling, opt->repeats);
      if (!roof) return cli::fail(roof.status());
      auto made = scenes();
      if (!made) return cli::fail(made.status());
      std::fprintf(stderr, "roofline: shader copy %.1f GB/s, vkCmdCopyBuffer %.1f GB/s, trilinear %.0f M samples/s\n",
                   roof->copy_gb_per_s, roof->transfer_gb_per_s, roof->trilinear_samples_per_s / 1e6);
      nlohmann::json rows = nlohmann::json::array();
      for (const Scene& sc : *made) {
        auto times = measure(ctx, **ceiling, sc, *size, opt->repeats);
        if (!times) return cli::fail(times.status());
        const TimedFrames* m = &times->frame;
        const double rate = m->stats.samples / (m->gpu_ms * 1e-3);
        const double ceiling_rate = times->ceiling_samples_per_s;
        const double ratio = rate / ceiling_rate;
        nlohmann::json row = {{"scene", sc.name},
                              {"step_voxels", sc.settings.step_voxels},
                              {"gpu_ms", m->gpu_ms},
                              {"wall_ms", m->wall_ms},
                              {"samples", m->stats.samples},
                              {"samples_per_s", rate},
                              {"ceiling_samples_per_s", ceiling_rate},
                              {"roofline_ratio", ratio}};
        std::fprintf(stderr,
                     "roofline: %-18s %8.2f gpu ms %8.2f wall ms %6.1f M samples %6.0f M/s  %.2f of ceiling (%.0f M/s "
                     "in turn)\n",
                     sc.name.c_str(), m->gpu_ms, m->wall_ms, m->stats.samples / 1e6, rate / 1e6, ratio,
                     ceiling_rate / 1e6);
        if (times->fetch_only) {
          // Where the frame's time goes: the same rays, bricks and walks with
          // each sample only fetched, then not even that. Probe rays never
          // terminate, so rates (samples per second) are compared, not times.
          const TimedFrames* fetch = &*times->fetch_only;
          const TimedFrames* march = &*times->march_only;
          const double fetch_rate = fetch->stats.samples / (fetch->gpu_ms * 1e-3);
          // Per million samples: the march alone, the fetch on top of it, the shading on top of both.
          const double us_march = march->gpu_ms * 1e3 / (march->stats.samples / 1e6);
          const double us_fetch = fetch->gpu_ms * 1e3 / (fetch->stats.samples / 1e6) - us_march;
          const double us_shade = m->gpu_ms * 1e3 / (m->stats.samples / 1e6) - us_march - us_fetch;
          row["fetch_only"] = {{"gpu_ms", fetch->gpu_ms}, {"samples", fetch->stats.samples},
                               {"samples_per_s", fetch_rate}};
          row["march_only"] = {{"gpu_ms", march->gpu_ms}, {"samples", march->stats.samples}};
          row["ms_per_m_samples"] = {{"march", us_march / 1e3}, {"fetch", us_fetch / 1e3}, {"shade", us_shade / 1e3}};
          row["share_of_fetch_rate"] = rate / fetch_rate;
          std::fprintf(stderr,
                       "roofline: %-18s fetch only %6.0f M/s (%.2f of ceiling), frame %.2f of it; per M samples: "
                       "march %.2f ms, fetch %.2f, shade %.2f\n",
                       "", fetch_rate / 1e6, fetch_rate / ceiling_rate, rate / fetch_rate,
                       us_march / 1e3, us_fetch / 1e3, us_shade / 1e3);
        }
        rows.push_back(std::move(row));
      }
      nlohmann::json doc = {
          {"ceilings",
           {{"copy_gb_per_s", roof->copy_gb_per_s},
            {"trilinear_samples_per_s", roof->trilinear_samples_per_s},
            {"transfer_gb_per_s", roof->transfer_gb_per_s},
            {"copy_ms", roof->copy_ms},
            {"transfer_ms", roof->transfer_ms},
            {"sample_ms", roof->sample_ms}}},
          {"brick_renderer",
           {{"image_size", {*size, *size}},
            {"note", "level 0, preloaded, skipping on; rate = samples taken / GPU time of the frame; roofline_ratio against "
                      "ceiling_samples_per_s, the trilinear kernel timed in turn with the scene's frames"},
            {"scenes", rows}}},
      };
      auto png = write_plot(*opt, "roofline", roofline_plot(rows, *size));
      if (!png) return cli::fail(png.status());
      std::printf("%s\n", png->c_str());
      doc["plot"] = *png;
      auto path = write_report(*opt, "roofline", doc, &ctx);
      return path ? cli::kExitOk : cli::fail(path.status());
    };
  });
}

}  // namespace vxr::bench
