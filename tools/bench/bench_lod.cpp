// `vxr bench lod`: the out-of-core renderer's scale, skip and paging figures.
//
// scale: the procedural vessels at 256^3, 4096^3 and 65536^3 from the same
//   relative viewpoint (same screen coverage), converged, LOD by angular
//   resolution: frame time and samples should stay about constant.
// skip: a ~10% occupied 256^3 volume at full resolution, empty-space skipping
//   on vs off: speedup, sample ratio, identical images; skip_models: the same
//   for each optical model (skip_models_identical: every image the same).
// paged_vs_monolithic: the same 256^3 at full resolution through the brick
//   pool vs one 3D texture, same shader: time ratio and max abs difference.
// passes: single pass over the brick table vs the paper's multipass (one
//   dispatch per brick over its screen rectangle) on the same frames.
// throttled: frames to converge with 4 bricks uploaded per frame.
// Times are whole frames (traversal, brick table, ray cast, readback), median
// of --repeats after convergence.
#include <chrono>
#include <cmath>
#include <cstdio>
#include <nlohmann/json.hpp>

#include "bench.h"
#include "render/lod/brick_renderer.h"
#include "volume/procedural_source.h"

namespace vxr::bench {
using cli::fail;
using cli::kExitOk;
using cli::open_gpu;
namespace {

struct Options {
  BenchOptions common;
  uint32_t size = 256;
  uint64_t largest = 65536;
  uint32_t paged_chunk = 128;
};

struct Case {
  double ms = 0;
  BrickFrameStats stats;
  ImageRgba8 image;
};

RenderSettings vessel_settings() {
  RenderSettings s;
  s.channels[0].colormap = "hot";
  s.channels[0].window_lo = 8;  // above the background noise (0..6)
  s.channels[0].window_hi = 200;
  s.step_voxels = 0.5;
  s.density = 0.3;
  return s;
}

Result<std::unique_ptr<ProceduralSource>> source(uint64_t side, uint32_t chunk = 32) {
  ProceduralOptions o;
  o.dims = {side, side, side};
  o.chunk_size = chunk;
  o.noise_max = 6;
  o.occupancy = 0.10;
  return ProceduralSource::create(o);
}

// Converges (uploads until nothing is missing), then times `repeats` frames.
Result<Case> measure(BrickRenderer& r, const Camera& cam, const BrickFrameSettings& f, uint32_t size, int repeats,
                     const RenderSettings& s = vessel_settings()) {
  Case c;
  for (int i = 0;; ++i) {
    auto img = r.render(cam, s, f, size, size, &c.stats);
    if (!img) return img.status();
    if (c.stats.lod.missing == 0) break;
    if (i > 200) return internal_error("bench lod: the view did not converge in 200 frames");
  }
  Status err;
  c.ms = median_ms(
      repeats,
      [&] {
        auto img = r.render(cam, s, f, size, size, &c.stats);
        if (!img) return img.status();
        c.image = std::move(*img);
        return Status::ok();
      },
      &err);
  if (!err.is_ok()) return err;
  return c;
}

nlohmann::json stats_json(const BrickFrameStats& s) {
  return {{"visited", s.lod.visited},   {"drawn", s.lod.drawn},     {"fallback", s.lod.fallback},
          {"skipped_empty", s.lod.skipped_empty}, {"culled", s.lod.culled}, {"missing", s.lod.missing},
          {"samples", s.samples},       {"bytes_uploaded", s.bytes_uploaded}, {"hit_rate", s.hit_rate},
          {"traverse_ms", s.traverse_ms}, {"render_ms", s.render_ms}, {"dispatches", s.dispatches}};
}

int max_abs_diff(const ImageRgba8& a, const ImageRgba8& b) {
  int m = 0;
  for (size_t i = 0; i < a.pixels.size(); ++i) m = std::max(m, std::abs(int(a.pixels[i]) - int(b.pixels[i])));
  return m;
}

int run(const Options& o) {
  auto gpu = open_gpu();
  if (!gpu) return fail(gpu.status());
  BrickRendererOptions ro;
  ro.pool.slots = {16, 16, 8};
  nlohmann::json doc;
  doc["image_size"] = {o.size, o.size};
  doc["repeats"] = o.common.repeats;

  // --- scale
  {
    nlohmann::json sizes = nlohmann::json::array(), ms = nlohmann::json::array(), samples = nlohmann::json::array(),
                   frames = nlohmann::json::array();
    for (uint64_t side : {uint64_t(256), uint64_t(4096), o.largest}) {
      auto src = source(side);
      if (!src) return fail(src.status());
      auto r = BrickRenderer::create(**gpu, **src, ro);
      if (!r) return fail(r.status());
      const Camera cam = orbit_camera((*r)->placement(), 30, 25, 1.6);
      auto c = measure(**r, cam, {}, o.size, o.common.repeats);
      if (!c) return fail(c.status());
      sizes.push_back(side);
      ms.push_back(c->ms);
      samples.push_back(c->stats.samples);
      frames.push_back(stats_json(c->stats));
      std::printf("scale %llu^3: %.2f ms  %s\n", (unsigned long long)side, c->ms, format_stats(c->stats).c_str());
    }
    doc["scale"] = {{"sizes", sizes},
                    {"ms", ms},
                    {"samples", samples},
                    {"frames", frames},
                    {"ratio_largest_to_smallest",
                     {{"ms", ms.back().get<double>() / ms.front().get<double>()},
                      {"samples", samples.back().get<double>() / samples.front().get<double>()}}}};
  }

  auto src = source(256);
  if (!src) return fail(src.status());
  auto r = BrickRenderer::create(**gpu, **src, ro);
  if (!r) return fail(r.status());
  const Camera cam = orbit_camera((*r)->placement(), 30, 25, 1.25);
  BrickFrameSettings full;
  full.lod.force_level = 0;

  // --- skip
  {
    BrickFrameSettings off = full;
    off.lod.skip_empty = false;
    auto on_c = measure(**r, cam, full, o.size, o.common.repeats);
    auto off_c = measure(**r, cam, off, o.size, o.common.repeats);
    if (!on_c) return fail(on_c.status());
    if (!off_c) return fail(off_c.status());
    doc["skip"] = {{"speedup", off_c->ms / on_c->ms},
                   {"sample_ratio", double(off_c->stats.samples) / double(on_c->stats.samples)},
                   {"identical", on_c->image.pixels == off_c->image.pixels},
                   {"occupancy", (*src)->measured_occupancy()},
                   {"on", stats_json(on_c->stats)},
                   {"off", stats_json(off_c->stats)},
                   {"ms_on", on_c->ms},
                   {"ms_off", off_c->ms}};
    std::printf("skip on : %.2f ms  %s\nskip off: %.2f ms  %s\n", on_c->ms, format_stats(on_c->stats).c_str(),
                off_c->ms, format_stats(off_c->stats).c_str());

    // --- skip per model: what skipping buys each optical model, with the
    // same image.
    nlohmann::json models = nlohmann::json::object();
    bool all_identical = true;
    for (OpticalModel m : {OpticalModel::kEmissionAbsorption, OpticalModel::kEmission, OpticalModel::kMip,
                           OpticalModel::kMinIp, OpticalModel::kAverage, OpticalModel::kIsosurface}) {
      RenderSettings s = vessel_settings();
      s.model = m;
      if (m == OpticalModel::kMinIp) s.channels[0].window_lo = 0;  // the minimum is not the background's
      s.iso_value = 100;                                             // inside the vessels' walls
      auto m_on = measure(**r, cam, full, o.size, o.common.repeats, s);
      if (!m_on) return fail(m_on.status());
      auto m_off = measure(**r, cam, off, o.size, o.common.repeats, s);
      if (!m_off) return fail(m_off.status());
      const bool identical = m_on->image.pixels == m_off->image.pixels;
      all_identical = all_identical && identical;
      const double speedup = m_off->ms / m_on->ms;
      const double sample_ratio = double(m_off->stats.samples) / double(std::max<uint64_t>(m_on->stats.samples, 1));
      models[optical_model_name(m)] = {{"speedup", speedup}, {"sample_ratio", sample_ratio}, {"identical", identical},
                                       {"ms_on", m_on->ms},  {"ms_off", m_off->ms}};
      std::printf("skip %-9s on %8.2f ms, off %8.2f ms: %6.1fx, %7.1fx fewer samples, %s\n", optical_model_name(m),
                  m_on->ms, m_off->ms, speedup, sample_ratio, identical ? "same image" : "IMAGES DIFFER");
    }
    doc["skip_models"] = models;
    doc["skip_models_identical"] = all_identical;

    // --- paged vs monolithic (skipping off on both: the same work). Frames
    // alternate so that both see the same machine load; medians of each.
    // Bricks of --paged-chunk (128) voxels: each brick costs a restart, an
    // accumulation load/store and a work item per tile (measured on lavapipe:
    // 64^3 bricks ~1.35x the monolithic time, 128^3 ~1.1x).
    auto src64 = source(256, o.paged_chunk);
    if (!src64) return fail(src64.status());
    BrickRendererOptions ro64 = ro;
    const uint32_t edge = o.paged_chunk + 2;
    const uint64_t fit = (512ull << 20) / (uint64_t(edge) * edge * edge);  // a 512 MiB atlas
    const uint32_t n = std::max(2u, std::min(16u, uint32_t(std::cbrt(double(fit)))));
    ro64.pool.slots = {n, n, n};
    auto r64 = BrickRenderer::create(**gpu, **src64, ro64);
    if (!r64) return fail(r64.status());
    if (Status s = (*r64)->set_monolithic(0); !s) return fail(s);
    auto warm = measure(**r64, cam, off, o.size, 1);
    if (!warm) return fail(warm.status());
    ImageRgba8 mono, paged;
    BrickFrameStats ms, ps;
    std::vector<double> mono_t, paged_t;
    for (int i = 0; i <= o.common.repeats; ++i) {
      auto t0 = std::chrono::steady_clock::now();
      auto a = (*r64)->render(cam, vessel_settings(), off, o.size, o.size, &ps);
      auto t1 = std::chrono::steady_clock::now();
      auto b = (*r64)->render_monolithic(cam, vessel_settings(), off.lod, o.size, o.size, &ms);
      auto t2 = std::chrono::steady_clock::now();
      if (!a) return fail(a.status());
      if (!b) return fail(b.status());
      paged = std::move(*a);
      mono = std::move(*b);
      if (i == 0) continue;  // warm-up
      paged_t.push_back(std::chrono::duration<double, std::milli>(t1 - t0).count());
      mono_t.push_back(std::chrono::duration<double, std::milli>(t2 - t1).count());
    }
    const double paged_ms = median(paged_t), mono_ms = median(mono_t);
    doc["paged_vs_monolithic"] = {{"time_ratio", paged_ms / mono_ms},
                                  {"max_abs", max_abs_diff(paged, mono)},
                                  {"paged_ms", paged_ms},
                                  {"monolithic_ms", mono_ms},
                                  {"paged_samples", ps.samples},
                                  {"monolithic_samples", ms.samples},
                                  {"paged_dispatches", ps.dispatches},
                                  {"bricks", ps.lod.drawn},
                                  {"chunk_size", o.paged_chunk}};
    std::printf("paged %.2f ms vs monolithic %.2f ms (ratio %.3f), samples %llu vs %llu, max_abs %d\n", paged_ms,
                mono_ms, paged_ms / mono_ms, (unsigned long long)ps.samples, (unsigned long long)ms.samples,
                max_abs_diff(paged, mono));

    // --- the pass modes on the same frames: the paper's multipass (waves), a
    // single pass over the brick table, per-tile brick lists (kAuto: tiled).
    BrickFrameSettings multi = full, multi_off = off;
    multi.mode = multi_off.mode = BrickPassMode::kMultipass;
    auto multi_c = measure(**r, cam, multi, o.size, o.common.repeats);
    if (!multi_c) return fail(multi_c.status());
    auto multi_off_c = measure(**r, cam, multi_off, o.size, o.common.repeats);
    if (!multi_off_c) return fail(multi_off_c.status());
    BrickFrameSettings single = full;
    single.mode = BrickPassMode::kSinglePass;
    auto single_c = measure(**r, cam, single, o.size, o.common.repeats);
    if (!single_c) return fail(single_c.status());
    BrickFrameSettings tiled = full;
    tiled.mode = BrickPassMode::kTiled;
    auto tiled_c = measure(**r, cam, tiled, o.size, o.common.repeats);
    if (!tiled_c) return fail(tiled_c.status());
    BrickFrameSettings tiled_off = off;
    tiled_off.mode = BrickPassMode::kTiled;
    auto tiled_off_c = measure(**r, cam, tiled_off, o.size, o.common.repeats);
    if (!tiled_off_c) return fail(tiled_off_c.status());
    std::printf("tiled: skip on %.2f ms, skip off %.2f ms\n", tiled_c->ms, tiled_off_c->ms);
    doc["passes"] = {{"single_ms", single_c->ms},
                     {"tiled_ms", tiled_c->ms},
                     {"tiled_skip_off_ms", tiled_off_c->ms},
                     {"multi_skip_off_ms", multi_off_c->ms},
                     {"multi_skip_off_dispatches", multi_off_c->stats.dispatches},
                     {"tiled_max_abs", max_abs_diff(multi_c->image, tiled_c->image)},
                     {"multi_ms", multi_c->ms},
                     {"bricks", multi_c->stats.lod.drawn},
                     {"multi_dispatches", multi_c->stats.dispatches},
                     {"max_abs", max_abs_diff(multi_c->image, single_c->image)},
                     {"auto", "tiled"}};
    std::printf("single pass: %.2f ms vs multipass %.2f ms (%u dispatches); default (auto): tiled\n", single_c->ms,
                multi_c->ms, multi_c->stats.dispatches);
  }

  // --- throttled uploads: frames to converge, 4 bricks per frame
  {
    auto rt = BrickRenderer::create(**gpu, **src, ro);
    if (!rt) return fail(rt.status());
    BrickFrameSettings f;
    f.upload_budget_bytes = 4 * (*rt)->pool().brick_bytes();
    int frames = 0;
    BrickFrameStats st;
    for (; frames < 1000; ++frames) {
      auto img = (*rt)->render(cam, vessel_settings(), f, o.size, o.size, &st);
      if (!img) return fail(img.status());
      if (st.lod.missing == 0) break;
    }
    doc["throttled"] = {{"bricks_per_frame", 4}, {"frames_to_converge", frames + 1}};
  }

  auto path = write_report(o.common, "lod", doc, gpu->get());
  if (!path) return fail(path.status());
  return kExitOk;
}

}  // namespace

void add_lod_bench(CLI::App& bench, cli::Invocation& inv) {
  auto* cmd = bench.add_subcommand(
      "lod", "out-of-core rendering: constant cost across 256^3..65536^3, empty-space skipping, paged vs monolithic");
  auto o = std::make_shared<Options>();
  o->common.repeats = 3;
  cmd->add_option("--size", o->size, "image width and height in pixels (default 256)")->check(CLI::Range(16, 2048));
  cmd->add_option("--largest", o->largest, "side of the largest procedural volume (default 65536, max 131072)")
      ->check(CLI::Range(4096, 131072));
  cmd->add_option("--paged-chunk", o->paged_chunk, "chunk size for paged vs monolithic (default 128)")
      ->check(CLI::Range(16, 128));
  add_common_options(cmd, o->common);
  cmd->callback([&inv, o] { inv.run = [o] { return run(*o); }; });
}

}  // namespace vxr::bench
