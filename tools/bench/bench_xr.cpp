// `vxr bench xr`: lens-warped ray casting against the full eye buffer.
//
// For a few head poses around the bundled sample, renders each eye at full
// resolution and through the lens-warped grid (same centre density), and
// reports the ray ratio, the error after resampling (RGB over black, 0..1
// units) and the time per eye, in out/bench/xr.json: per view, the median of
// --repeats timed frames each, after one untimed frame of each (the images
// compared; pipelines and the warped intermediate are made there). Both go
// through the frame path vxr view uses (EyeRenderer over the out-of-core
// renderer); the warped eye is one view whose rays follow the warped grid.
#include <cmath>
#include <cstdio>
#include <nlohmann/json.hpp>

#include "assets/assets.h"
#include "bench.h"
#include "volume/dense_chunk_source.h"
#include "xr/eye_renderer.h"
#include "xr/view_session.h"

namespace vxr::bench {
using cli::fail;
using cli::kExitOk;
using cli::open_gpu;
namespace {

xr::Pose look_at(const glm::dvec3& eye, const glm::dvec3& target) {
  const glm::dvec3 f = glm::normalize(target - eye);
  const glm::dvec3 r = glm::normalize(glm::cross(f, glm::dvec3(0, 1, 0)));
  const glm::dvec3 u = glm::cross(r, f);
  // Columns: x = right, y = up, z = -forward.
  const glm::dmat3 m(r, u, -f);
  return {glm::quat_cast(m), eye};
}

struct Options {
  BenchOptions common;
  uint32_t size = 256;
  xr::LensWarp warp{true, 0.5, 2};
};

int run(const Options& o) {
  auto volume = assets::sample_volume();
  if (!volume) return fail(volume.status());
  auto gpu = open_gpu();
  if (!gpu) return fail(gpu.status());
  std::vector<DenseVolume> volumes;
  volumes.push_back(std::move(volume).value());
  auto source = DenseChunkSource::create(std::move(volumes));
  if (!source) return fail(source.status());
  auto eyes = xr::EyeRenderer::create(**gpu, *source);
  if (!eyes) return fail(eyes.status());
  const xr::VolumeTransform t = xr::default_volume_transform((*eyes)->placement());
  const RenderSettings settings = default_view_settings();
  const xr::Fov fov{-0.785398, 0.698132, 0.785398, -0.785398};  // a typical asymmetric left-eye fov
  const glm::dvec3 c = t.position;
  // Far (the head well inside the centre band), close and close-oblique (it fills the outer bands).
  const xr::Pose heads[] = {look_at({0.0, 1.6, 0.0}, c), look_at({0.03, 1.62, -0.3}, c),
                            look_at({-0.15, 1.7, -0.28}, c)};

  uint64_t rays_full = 0, rays_warp = 0, channels = 0, outer_channels = 0;
  double abs_sum = 0.0, outer_sum = 0.0, full_ms = 0.0, warp_ms = 0.0;
  const xr::WarpAxis axis = xr::warp_axis(o.size, o.warp);
  int max_abs = 0, renders = 0;
  xr::LensWarp none;
  for (const xr::Pose& head : heads) {
    for (const xr::ViewSpec& view : xr::stereo_views(head, 0.064, fov, o.size, o.size)) {
      uint64_t r1 = 0, r2 = 0;
      auto full = (*eyes)->render(view, t, settings, none, &r1);
      auto warped = (*eyes)->render(view, t, settings, o.warp, &r2);
      if (!full) return fail(full.status());
      if (!warped) return fail(warped.status());
      Status error = Status::ok();
      auto frame = [&](const xr::LensWarp& w) {
        return [&, w] { return (*eyes)->render(view, t, settings, w).status(); };
      };
      full_ms += median_ms(o.common.repeats, frame(none), &error);
      if (!error) return fail(error);
      warp_ms += median_ms(o.common.repeats, frame(o.warp), &error);
      if (!error) return fail(error);
      ++renders;
      rays_full += r1;
      rays_warp += r2;
      const ImageRgba8 a = over_black(*full), b = over_black(*warped);
      for (size_t i = 0; i < a.pixels.size(); ++i) {
        if (i % 4 == 3) continue;
        const int d = std::abs(int(a.pixels[i]) - int(b.pixels[i]));
        abs_sum += d;
        max_abs = std::max(max_abs, d);
        ++channels;
        const uint32_t x = uint32_t(i / 4 % o.size), y = uint32_t(i / 4 / o.size);
        const auto outer = [&](uint32_t p) { return p < axis.edge_full || p >= axis.edge_full + axis.centre; };
        if (outer(x) || outer(y)) {
          outer_sum += d;
          ++outer_channels;
        }
      }
    }
  }
  nlohmann::json j;
  j["eye_size"] = {o.size, o.size};
  j["views"] = renders;
  j["centre_fraction"] = o.warp.centre_fraction;
  j["periphery_step"] = o.warp.periphery_step;
  j["rays_full"] = rays_full;
  j["rays_warped"] = rays_warp;
  j["ray_ratio"] = double(rays_warp) / double(rays_full);
  j["mean_abs_error"] = abs_sum / double(channels) / 255.0;
  j["mean_abs_error_8bit"] = abs_sum / double(channels);
  j["max_abs_error_8bit"] = max_abs;
  j["mean_abs_error_outer_bands_8bit"] = outer_channels ? outer_sum / double(outer_channels) : 0.0;
  j["full_ms_per_eye"] = full_ms / renders;
  j["warped_ms_per_eye"] = warp_ms / renders;
  j["warped_faster"] = warp_ms < full_ms;
  j["note"] = "error: RGB over black vs the full-resolution render, all pixels; both times are one frame of one eye "
              "through the out-of-core renderer (record, one submit, wait, one readback), median of repeats per view; "
              "warped: one view whose rays follow the warped grid plus one blit (9 linear regions) onto the eye "
              "image, in the same command buffer";
  auto path = write_report(o.common, "xr", j, gpu->get());
  if (!path) return fail(path.status());
  return kExitOk;
}

}  // namespace

void add_xr_bench(CLI::App& bench, cli::Invocation& inv) {
  auto* cmd = bench.add_subcommand("xr", "lens-warped ray casting vs the full eye buffer: ray ratio, error, time");
  auto o = std::make_shared<Options>();
  cmd->add_option("--size", o->size, "eye image width and height in pixels (default 256)")->check(CLI::Range(16, 2048));
  add_common_options(cmd, o->common);
  cmd->add_option("--centre-fraction", o->warp.centre_fraction, "fraction of each axis cast at full density (0.5)")
      ->check(CLI::Range(0.0, 1.0));
  cmd->add_option("--periphery-step", o->warp.periphery_step, "pixels per ray in the outer bands (2)")
      ->check(CLI::Range(1, 8));
  cmd->callback([&inv, o] { inv.run = [o] { return run(*o); }; });
}

}  // namespace vxr::bench
