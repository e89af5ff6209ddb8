// `vxr bench peer`: the scenes a VTK-style setup renders (ramp transfer
// function, step in voxels, 512x512), so vxr's speed-vs-error front can be
// set beside other tools' figures, and what empty-space skipping buys.
//
// Scenes: the MRI sample (186x226x27 u8, through DenseChunkSource; ramp from
// 75, the tissue threshold, to the 99.5th percentile) with emission-absorption and MIP, and a 256^3 sparse procedural volume (vessels,
// 10% occupied) with emission-absorption; every one drawn at full resolution
// (LOD level 0) by the brick renderer. Per step: the median frame wall time
// and GPU time (timestamps) with skipping on (bricks and cells) and off,
// drawn in turn frame by frame (a busy machine slows both alike); whether
// the two images are byte-identical; RMSE (8-bit units, RGBA over black)
// against the CPU reference of the same scene. Per scene the
// report names the coarsest step whose RMSE <= 1.5 and the on/off speedup there.
// Opacity is per world unit (unit distance 1, VTK's default scalar opacity
// unit distance), so the MRI's 5x thicker z voxels absorb 5x along z as in
// VTK; --opacity-unit-distance 0 gives vxr's per-voxel opacity instead.
//
// The report names each scene's camera and transfer function; with
// --export-scenes the level-0 voxels and the reference image go beside it,
// so another tool can draw the same scenes and be scored against the same
// reference (tools/peer/vtk_peer.py, run by ci/peer-vtk.sh).
//
// Beside the report, peer.png plots each scene's time against its error,
// skipping on and off, with the RMSE goal.
#include <algorithm>
#include <cctype>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <nlohmann/json.hpp>

#include "assets/assets.h"
#include "bench.h"
#include "bench/brick_timing.h"
#include "bench/plot.h"
#include "core/output_file.h"
#include "core/progress.h"
#include "render/lod/brick_renderer.h"
#include "render/reference_renderer.h"
#include "render/volume_session.h"
#include "volume/container_reader.h"
#include "volume/dense_chunk_source.h"
#include "volume/procedural_source.h"

namespace vxr::bench {
using cli::fail;
using cli::kExitOk;
using cli::open_gpu;
namespace {

struct Options {
  BenchOptions common;
  uint32_t size = 512;
  std::vector<double> steps{2.0, 1.0, 0.5, 0.25};
  double reference_step = 0.125;
  double rmse_goal = 1.5;  // 8-bit units
  double opacity_unit_distance = 1.0;  // world units; 0: per voxel
  bool export_scenes = false;          // write each scene's voxels and reference image beside the report
};

struct Scene {
  std::string name;
  std::shared_ptr<ChunkSource> source;
  DenseVolume level0;  // what the reference draws
  RenderSettings settings;
};

// The VTK-style transfer function with opacity per `unit_distance` world units.
RenderSettings ramp(OpticalModel model, double lo, double hi, double unit_distance) {
  RenderSettings s = vtk_ramp(model, lo, hi);
  s.opacity_unit_distance = unit_distance;
  return s;
}

Result<std::vector<Scene>> scenes(double unit_distance) {
  std::vector<Scene> out;
  VXR_ASSIGN_OR_RETURN(DenseVolume mri, assets::sample_volume());
  // The ramp starts where tissue starts: 75 is the threshold of the testdata's
  // calibrated mask of this stack (mri-stack-calibrated.tif: value > 74);
  // below it is background noise, transparent as in a VTK ramp.
  const double lo = 75.0, hi = std::max(percentile_window(mri).second, lo + 1.0);
  VXR_ASSIGN_OR_RETURN(auto mri_src, DenseChunkSource::create({mri}));
  out.push_back({"mri ea", mri_src, mri, ramp(OpticalModel::kEmissionAbsorption, lo, hi, unit_distance)});
  out.push_back({"mri mip", mri_src, mri, ramp(OpticalModel::kMip, lo, hi, unit_distance)});
  ProceduralOptions po;
  po.dims = {256, 256, 256};
  po.noise_max = 6;
  po.occupancy = 0.10;
  VXR_ASSIGN_OR_RETURN(auto vessels, ProceduralSource::create(po));
  std::shared_ptr<ChunkSource> vsrc = std::move(vessels);
  VXR_ASSIGN_OR_RETURN(DenseVolume v0, read_level_dense(*vsrc, 0, 0, 0, uint64_t(1) << 30));
  RenderSettings vs = ramp(OpticalModel::kEmissionAbsorption, 8, 200, unit_distance);  // above the noise (0..6)
  vs.density = 0.3;
  out.push_back({"vessels 256^3 ea", vsrc, std::move(v0), vs});
  return out;
}

// File names for a scene's exported data: "mri ea" -> "peer-mri-ea".
std::string scene_slug(const std::string& name) {
  std::string s = "peer-";
  for (char c : name) s += std::isalnum(static_cast<unsigned char>(c)) ? c : '-';
  return s;
}

// What another tool needs to draw the scene as vxr does: the volume as it
// sits in the world (voxel centres at (i + 0.5) * voxel_size - extent / 2,
// plus the box centre; trilinear, clamped at the box), the camera and the
// transfer function.
nlohmann::json describe_scene(const Scene& sc, const VolumePlacement& placed, const Camera& cam, uint32_t size) {
  const RenderSettings& s = sc.settings;
  const ChannelSettings& ch = s.channels[0];
  nlohmann::json opacity = nlohmann::json::array();
  for (const OpacityPoint& p : ch.opacity_points) opacity.push_back({p.x, p.opacity});
  return {{"volume", {{"dims", sc.level0.dims}, {"dtype", dtype_name(sc.level0.dtype)},
                      {"voxel_size", placed.voxel_size},
                      {"centre", {placed.origin.x, placed.origin.y, placed.origin.z}}}},
          {"camera", {{"eye", {cam.eye.x, cam.eye.y, cam.eye.z}},
                      {"target", {cam.target.x, cam.target.y, cam.target.z}},
                      {"up", {cam.up.x, cam.up.y, cam.up.z}},
                      {"fov_y_deg", cam.fov_y_deg},
                      {"image_size", {size, size}}}},
          {"transfer", {{"model", optical_model_name(s.model)},
                        {"window", {ch.window_lo, ch.window_hi}},
                        {"colormap", ch.colormap},
                        {"opacity_points", opacity},
                        {"density", s.density},
                        {"opacity_unit_distance", s.opacity_unit_distance},
                        {"early_termination", s.early_termination}}}};
}

// Writes the scene's level-0 voxels (x fastest, little-endian) and its
// reference image (8-bit RGBA over black, top row first) into `dir`.
Result<nlohmann::json> export_scene(const std::string& dir, const Scene& sc, const std::vector<uint8_t>& ref_px) {
  const std::string slug = scene_slug(sc.name);
  const std::string volume = slug + ".raw", reference = slug + "-reference.rgba";
  VXR_RETURN_IF_ERROR(write_file_atomically((std::filesystem::path(dir) / volume).string(), sc.level0.data));
  VXR_RETURN_IF_ERROR(write_file_atomically((std::filesystem::path(dir) / reference).string(), ref_px));
  return nlohmann::json{{"volume", volume}, {"reference_rgba", reference}};
}

// Time (wall ms) against error per scene, skipping on as a line and off as
// lighter points, and the RMSE goal across: the speed-vs-error front the
// report lists, and what skipping buys at each error.
PlotSpec peer_plot(const nlohmann::json& scenes, double rmse_goal, uint32_t size) {
  PlotSpec plot;
  plot.title = "vxr bench peer: time vs error, " + std::to_string(size) + "x" + std::to_string(size);
  plot.x_label = "wall ms per frame";
  plot.y_label = "RMSE vs the CPU reference (8-bit units)";
  plot.log_x = plot.log_y = true;
  double lo = 1e300, hi = 0.0;
  for (size_t i = 0; i < scenes.size(); ++i) {
    PlotSeries on, off;
    on.label = scenes[i]["scene"].get<std::string>() + ", skipping on";
    on.color = series_colour(i);
    on.line = true;
    off.label = scenes[i]["scene"].get<std::string>() + ", skipping off";
    off.color = lighter(on.color);
    for (const nlohmann::json& row : scenes[i]["steps"]) {
      const double err = row["rmse_vs_reference"], on_ms = row["on"]["wall_ms"], off_ms = row["off"]["wall_ms"];
      on.x.push_back(on_ms), on.y.push_back(err);
      off.x.push_back(off_ms), off.y.push_back(err);
      lo = std::min({lo, on_ms, off_ms}), hi = std::max({hi, on_ms, off_ms});
    }
    plot.series.push_back(std::move(on));
    plot.series.push_back(std::move(off));
  }
  if (hi > 0.0) {
    PlotSeries goal;
    goal.label = "RMSE goal";
    goal.color = {0, 0, 0};
    goal.line = true;
    goal.markers = false;
    goal.x = {lo, hi};
    goal.y = {rmse_goal, rmse_goal};
    plot.series.push_back(std::move(goal));
  }
  return plot;
}

int run(const Options& o) {
  auto gpu = open_gpu();
  if (!gpu) return fail(gpu.status());
  auto made = scenes(o.opacity_unit_distance);
  if (!made) return fail(made.status());
  nlohmann::json doc, per_scene = nlohmann::json::array();
  doc["image_size"] = {o.size, o.size};
  doc["repeats"] = o.common.repeats;
  doc["reference_step_voxels"] = o.reference_step;
  doc["rmse_goal"] = o.rmse_goal;
  doc["opacity_unit_distance"] = o.opacity_unit_distance;
  Progress progress("bench peer", made->size() * (o.steps.size() * 2 + 1), false);
  std::printf("%-18s %6s %10s %10s %8s %10s %10s %9s %9s %s\n", "scene", "step", "on ms", "off ms", "off/on",
              "on gpu ms", "off gpu ms", "samples x", "rmse", "identical");
  for (const Scene& sc : *made) {
    BrickRendererOptions ro;
    ro.preload_if_fits = true;
    auto r = BrickRenderer::create(**gpu, *sc.source, ro);
    if (!r) return fail(r.status());
    const Camera cam = orbit_camera((*r)->placement(), 30, 25, 1.25);
    auto ref = render_reference(std::span(&sc.level0, 1), cam, sc.settings, o.size, o.size, {o.reference_step, 0});
    if (!ref) return fail(ref.status());
    const std::vector<uint8_t> ref_px = over_black(to_rgba8(*ref)).pixels;
    nlohmann::json scene_doc = describe_scene(sc, (*r)->placement(), cam, o.size);
    if (o.export_scenes) {
      std::error_code ec;
      std::filesystem::create_directories(o.common.out_dir, ec);
      auto files = export_scene(o.common.out_dir, sc, ref_px);
      if (!files) return fail(files.status());
      scene_doc["files"] = *files;
    }
    progress.advance(1);
    nlohmann::json rows = nlohmann::json::array();
    double front_step = 0.0, front_speedup = 0.0, front_on_ms = 0.0;
    for (double step : o.steps) {
      RenderSettings s = sc.settings;
      s.step_voxels = step;
      BrickFrameSettings on;
      on.lod.force_level = 0;
      BrickFrameSettings off = on;
      off.lod.skip_empty = false;
      // On and off in turn, frame by frame: the ratio is what the acceptance reads.
      auto timed = time_in_turn(**r, cam, s, {on, off}, o.size, o.common.repeats);
      if (!timed) return fail(timed.status());
      progress.advance(2);
      const TimedFrames* a = &(*timed)[0];
      const TimedFrames* b = &(*timed)[1];
      const bool identical = a->image.pixels == b->image.pixels;
      const double err = compare_pixels(over_black(a->image).pixels, ref_px).rmse;
      const double speedup = b->wall_ms / a->wall_ms;
      if (err <= o.rmse_goal && (front_step == 0.0 || step > front_step)) {
        front_step = step;
        front_speedup = speedup;
        front_on_ms = a->wall_ms;
      }
      rows.push_back({{"step_voxels", step},
                      {"on", {{"wall_ms", a->wall_ms}, {"gpu_ms", a->gpu_ms}, {"samples", a->stats.samples},
                              {"bricks_drawn", a->stats.lod.drawn}}},
                      {"off", {{"wall_ms", b->wall_ms}, {"gpu_ms", b->gpu_ms}, {"samples", b->stats.samples},
                               {"bricks_drawn", b->stats.lod.drawn}}},
                      {"speedup_wall", speedup},
                      {"speedup_gpu", a->gpu_ms > 0 ? b->gpu_ms / a->gpu_ms : 0.0},
                      // Samples taken off / on: the skip's share of the work, steady under a loaded CPU.
                      {"samples_ratio", a->stats.samples ? double(b->stats.samples) / double(a->stats.samples) : 0.0},
                      {"identical", identical},
                      {"rmse_vs_reference", err}});
      std::printf("%-18s %6.3f %10.2f %10.2f %8.2f %10.2f %10.2f %9.2f %9.3f %s\n", sc.name.c_str(), step, a->wall_ms,
                  b->wall_ms, speedup, a->gpu_ms, b->gpu_ms,
                  a->stats.samples ? double(b->stats.samples) / double(a->stats.samples) : 0.0, err,
                  identical ? "yes" : "NO");
    }
    nlohmann::json at_goal = nullptr;
    if (front_step > 0.0)
      at_goal = {{"step_voxels", front_step}, {"on_wall_ms", front_on_ms}, {"speedup_wall", front_speedup}};
    const auto& vs = sc.level0.voxel_size;
    scene_doc["scene"] = sc.name;
    scene_doc["voxel_size"] = {vs[0], vs[1], vs[2]};
    scene_doc["steps"] = rows;
    scene_doc["coarsest_step_within_goal"] = at_goal;
    per_scene.push_back(std::move(scene_doc));
    if (front_step > 0.0)
      std::printf("%-18s coarsest step with rmse <= %.2f: %.3f voxels, %.2f ms, skipping %.2fx\n", sc.name.c_str(),
                  o.rmse_goal, front_step, front_on_ms, front_speedup);
    else
      std::printf("%-18s no step reached rmse <= %.2f\n", sc.name.c_str(), o.rmse_goal);
  }
  progress.finish();
  auto png = write_plot(o.common, "peer", peer_plot(per_scene, o.rmse_goal, o.size));
  if (!png) return fail(png.status());
  std::printf("%s\n", png->c_str());
  doc["plot"] = *png;
  doc["scenes"] = per_scene;
  doc["units"] = {{"time", "median wall ms of one converged frame (traversal, submit, ray cast, readback); gpu_ms from "
                            "timestamps around the frame's commands"},
                  {"error", "RMSE in 8-bit units over RGBA over black, against the CPU reference at the reference step"}};
  auto path = write_report(o.common, "peer", doc, gpu->get());
  if (!path) return fail(path.status());
  return kExitOk;
}

}  // namespace

void add_peer_bench(CLI::App& bench, cli::Invocation& inv) {
  auto* cmd = bench.add_subcommand(
      "peer", "VTK-style scenes (MRI ea/mip, 256^3 sparse vessels): time and error per step, skipping on vs off");
  auto o = std::make_shared<Options>();
  o->common.repeats = 3;
  cmd->add_option("--size", o->size, "image width and height in pixels (default 512)")->check(CLI::Range(16, 2048));
  cmd->add_option("--steps", o->steps, "sample steps in voxels (default 2 1 0.5 0.25)")
      ->check(CLI::PositiveNumber);
  cmd->add_option("--reference-step", o->reference_step, "the CPU reference's step in voxels (default 1/8)")
      ->check(CLI::Range(1.0 / 64, 1.0));
  cmd->add_option("--rmse-goal", o->rmse_goal, "RMSE (8-bit units) a step must reach (default 1.5)");
  cmd->add_option("--opacity-unit-distance", o->opacity_unit_distance,
                  "opacity per this many world units, as VTK (default 1); 0: per voxel")
      ->check(CLI::NonNegativeNumber);
  cmd->add_flag("--export-scenes", o->export_scenes,
                "write each scene's level-0 voxels (.raw) and reference image (.rgba) beside the report, for "
                "tools/peer/vtk_peer.py");
  add_common_options(cmd, o->common);
  cmd->callback([&inv, o] { inv.run = [o] { return run(*o); }; });
}

}  // namespace vxr::bench
