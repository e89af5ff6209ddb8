// `vxr bench desktop INPUT`: how responsive the desktop viewer window stays
// while a large volume streams in (issue 16). The real viewer (GLFW window,
// ImGui panels, the frame loop of `vxr view`) opens INPUT with a cold chunk
// cache and a still camera; every frame's wall-clock interval (what the user
// feels: events, panels, render, present) and render time are recorded, and
// split at the first frame drawn in full detail (no brick still streaming).
// Needs a display (run under xvfb-run without one).
#include <algorithm>
#include <chrono>
#include <cstdio>
#include <filesystem>

#include "bench.h"
#include "core/progress.h"
#include "render/volume_session.h"
#include "xr/desktop/desktop_target.h"
#include "xr/desktop/viewer_setup.h"
#include "xr/view_session.h"

namespace vxr::bench {
namespace {

struct Options {
  BenchOptions common;
  std::string input;
  uint32_t width = 1280, height = 800;
  uint64_t frames = 300;
  uint64_t cache_mb = 1024;
};

double percentile(std::vector<double> v, double p) {
  if (v.empty()) return 0.0;
  std::sort(v.begin(), v.end());
  return v[std::min(v.size() - 1, size_t(p * double(v.size() - 1) + 0.5))];
}

nlohmann::json phase(const std::vector<double>& interval_ms, const std::vector<double>& render_ms, size_t begin,
                     size_t end) {
  const std::vector<double> iv(interval_ms.begin() + begin, interval_ms.begin() + end);
  const std::vector<double> rv(render_ms.begin() + begin, render_ms.begin() + end);
  double seconds = 0;
  for (double ms : iv) seconds += ms / 1e3;
  return {{"frames", end - begin},
          {"seconds", seconds},
          {"interval_ms", {{"p50", percentile(iv, 0.5)}, {"p95", percentile(iv, 0.95)}, {"max", percentile(iv, 1.0)}}},
          {"render_ms", {{"p50", percentile(rv, 0.5)}, {"p95", percentile(rv, 0.95)}, {"max", percentile(rv, 1.0)}}}};
}

int run(const Options& o) {
  if (Status s = xr::desktop_available(); !s) return cli::fail(s);
  auto session = open_volume_session(o.input, {});
  if (!session) return cli::fail(session.status(), cli::kExitUsage);
  const VolumeInfo& info = session->source->info();
  const VolumePlacement placement{{uint32_t(info.dims[0]), uint32_t(info.dims[1]), uint32_t(info.dims[2])},
                                  info.voxel_size};
  const xr::VolumeTransform start = xr::default_volume_transform(placement);

  // The viewer as `vxr view --desktop` builds it (panels with histograms).
  auto setup = std::make_shared<xr::ViewerSetup>();
  setup->dataset = std::filesystem::path(o.input).filename().string();
  setup->scene.volume = o.input;
  setup->scene.render = session->settings;
  setup->timepoints = info.timepoints;
  setup->data_range = {0.0, 1.0};
  for (const ChannelSettings& c : session->settings.channels) {
    setup->data_range[0] = std::min(setup->data_range[0], c.window_lo);
    setup->data_range[1] = std::max(setup->data_range[1], c.window_hi);
  }
  setup->placement = placement;
  setup->transform = start;
  for (uint32_t c = 0; c < session->settings.channels.size() && c < info.channels; ++c) {
    auto histogram = xr::coarse_histogram(*session->source, c, 0, setup->data_range);
    if (!histogram) return cli::fail(histogram.status());
    setup->histograms.push_back(std::move(histogram).value());
  }
  xr::DesktopOptions d;
  d.width = o.width;
  d.height = o.height;
  d.viewer = setup;
  auto factory = [d]() -> Result<std::unique_ptr<xr::FrameTarget>> {
    VXR_ASSIGN_OR_RETURN(std::unique_ptr<xr::DesktopTarget> t, xr::DesktopTarget::create(d));
    return std::unique_ptr<xr::FrameTarget>(std::move(t));
  };

  xr::ViewOptions vo;
  vo.frames = o.frames;
  vo.settings = session->settings;
  vo.cache_bytes = o.cache_mb << 20;  // cold: a fresh cache each run
  std::vector<double> interval_ms;
  auto last = std::chrono::steady_clock::now();
  Progress progress("desktop: frames", o.frames, false);
  vo.on_frame = [&](uint64_t) {
    progress.advance(1);
    const auto now = std::chrono::steady_clock::now();
    interval_ms.push_back(std::chrono::duration<double, std::milli>(now - last).count());
    last = now;
  };
  const auto t0 = std::chrono::steady_clock::now();
  last = t0;
  auto stats = xr::run_view(factory, session->source, vo, start);
  if (!stats) return cli::fail(stats.status());
  progress.finish();
  const double wall_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  const size_t n = std::min(interval_ms.size(), stats->frame_ms.size());
  // The first frame (pipelines, window mapping) is reported apart; streaming ends at the first full-detail frame.
  size_t full = 1;
  while (full < n && full < stats->frame_missing.size() && stats->frame_missing[full] > 0) ++full;
  nlohmann::json doc = {{"input", session->description},
                        {"dims", {info.dims[0], info.dims[1], info.dims[2]}},
                        {"window", {o.width, o.height}},
                        {"target", stats->target},
                        {"frames", n},
                        {"wall_seconds", wall_s},
                        {"cache_mb", o.cache_mb},
                        {"bricks_uploaded", stats->bricks_uploaded},
                        {"first_frame_ms", n ? interval_ms[0] : 0.0},
                        {"first_frame_missing_bricks", stats->frame_missing.empty() ? 0 : stats->frame_missing[0]},
                        {"full_detail_at_frame", full < n ? nlohmann::json(full) : nlohmann::json(nullptr)}};
  if (n > 1) doc["streaming"] = phase(interval_ms, stats->frame_ms, 1, std::max<size_t>(full, 1));
  if (full < n) doc["settled"] = phase(interval_ms, stats->frame_ms, full, n);
  doc["device_fingerprint"] = stats->device_fingerprint;
  auto report = write_report(o.common, "desktop", doc, nullptr);
  if (!report) return cli::fail(report.status());
  const nlohmann::json& s = doc.contains("streaming") ? doc["streaming"] : nlohmann::json::object();
  std::fprintf(stderr,
               "desktop: %s in a %ux%u window: first frame %.0f ms; %s frames while streaming (%.2f s): interval "
               "p50 %.1f / p95 %.1f / max %.1f ms; full detail at frame %s\n",
               o.input.c_str(), o.width, o.height, n ? interval_ms[0] : 0.0,
               s.contains("frames") ? std::to_string(s["frames"].get<size_t>()).c_str() : "0",
               s.value("seconds", 0.0), s.contains("interval_ms") ? s["interval_ms"]["p50"].get<double>() : 0.0,
               s.contains("interval_ms") ? s["interval_ms"]["p95"].get<double>() : 0.0,
               s.contains("interval_ms") ? s["interval_ms"]["max"].get<double>() : 0.0,
               full < n ? std::to_string(full).c_str() : "never (raise --frames)");
  return cli::kExitOk;
}

}  // namespace

void add_desktop_bench(CLI::App& bench, cli::Invocation& inv) {
  auto* cmd = bench.add_subcommand(
      "desktop", "viewer window frame times while a large volume streams in (cold cache, still camera; needs X)");
  auto o = std::make_shared<Options>();
  add_common_options(cmd, o->common);
  cmd->add_option("input", o->input, "volume: a large .vxc or OME-Zarr, or procedural:vessels:SIDE")->required();
  cmd->add_option("--width", o->width, "window width (default 1280)")->check(CLI::Range(64, 8192));
  cmd->add_option("--height", o->height, "window height (default 800)")->check(CLI::Range(64, 8192));
  cmd->add_option("--frames", o->frames, "frames to run (default 300)")->check(CLI::Range(2, 100000));
  cmd->add_option("--cache-mb", o->cache_mb, "chunk cache budget in MiB (default 1024)")->check(CLI::Range(16, 1 << 20));
  cmd->callback([&inv, o] { inv.run = [o] { return run(*o); }; });
}

}  // namespace vxr::bench
