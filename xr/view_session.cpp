#include "xr/view_session.h"

#include <chrono>

#include "core/log.h"
#include "core/trace.h"
#include "xr/eye_renderer.h"

namespace vxr::xr {
namespace {

enum class Outcome { kDone, kRestart };

// One run of a target: returns kRestart when the target lost its session.
Result<Outcome> run_once(FrameTarget& target, const DenseVolume& volume, const ViewOptions& options,
                         GrabInteraction& grab, ViewStats& stats) {
  gpu::ContextOptions copts = gpu::ContextOptions::from_env();
  VXR_RETURN_IF_ERROR(target.prepare_context(copts));
  VXR_ASSIGN_OR_RETURN(std::unique_ptr<gpu::Context> ctx, gpu::Context::create(copts));
  stats.device_fingerprint = ctx->info().fingerprint();
  // Everything tied to the device goes before it: renderer, then the target's objects.
  struct Detach {
    FrameTarget& t;
    ~Detach() { t.detach(); }
  };
  std::unique_ptr<EyeRenderer> eyes;
  Detach detach{target};
  VXR_RETURN_IF_ERROR(target.attach(*ctx));
  VXR_ASSIGN_OR_RETURN(eyes, EyeRenderer::create(*ctx, volume));
  stats.target = target.describe();

  bool exit_requested = false;
  int64_t last_display_ns = 0;
  double total_ms = 0.0;
  uint64_t timed = 0;
  for (;;) {
    VXR_TRACE_SCOPE("xr.frame");
    auto frame = target.wait_frame();
    if (!frame) return target.wants_restart() ? Result<Outcome>(Outcome::kRestart) : frame.status();
    if (frame->exit) {
      stats.target = target.describe();
      return Outcome::kDone;
    }
    const auto t0 = std::chrono::steady_clock::now();

    // Seconds since the last frame's display time, for thumbstick flight (capped: a stall is not a jump).
    const double dt = last_display_ns > 0 && frame->display_time_ns > last_display_ns
                          ? std::min(0.1, double(frame->display_time_ns - last_display_ns) * 1e-9)
                          : 0.0;
    last_display_ns = frame->display_time_ns;
    const auto started = grab.update(frame->input, stats.transform, dt);
    for (int h = 0; h < 2; ++h)
      if (started[h]) target.haptic_pulse(Hand(h), 0.5, 0.02);

    std::vector<ImageRgba8> images;
    if (frame->should_render) {
      for (size_t v = 0; v < frame->views.size(); ++v) {
        uint64_t rays = 0;
        VXR_ASSIGN_OR_RETURN(ImageRgba8 img,
                             eyes->render(frame->views[v], stats.transform, options.settings, options.warp, &rays));
        stats.rays += rays;
        auto image = target.acquire(v);
        if (!image) return target.wants_restart() ? Result<Outcome>(Outcome::kRestart) : image.status();
        VXR_RETURN_IF_ERROR(eyes->upload(*image, img));
        images.push_back(std::move(img));
      }
    }
    FrameContent content;
    content.focus_point = stats.transform.position;
    if (Status s = target.end_frame(*frame, content); !s)
      return target.wants_restart() ? Result<Outcome>(Outcome::kRestart) : Result<Outcome>(s);
    ++stats.frames_submitted;
    if (frame->should_render) {
      const double ms = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
      total_ms += ms;
      ++timed;
      stats.max_frame_ms = std::max(stats.max_frame_ms, ms);
      stats.mean_frame_ms = total_ms / double(timed);
      if (options.on_frame) options.on_frame(stats.frames_rendered, images);
      ++stats.frames_rendered;
    }
    if (options.frames > 0 && stats.frames_rendered >= options.frames && !exit_requested) {
      target.request_exit();
      exit_requested = true;
    }
  }
}

}  // namespace

RenderSettings default_view_settings() {
  RenderSettings s;
  s.channels[0].colormap = "hot";
  s.channels[0].window_lo = 20;
  s.channels[0].window_hi = 220;
  s.step_voxels = 0.5;
  s.density = 0.08;
  return s;
}

Result<ViewStats> run_view(const TargetFactory& make_target, const DenseVolume& volume, const ViewOptions& options,
                           const VolumeTransform& initial) {
  ViewStats stats;
  stats.transform = initial;
  GrabInteraction grab;
  for (;;) {
    std::unique_ptr<FrameTarget> target;
    VXR_ASSIGN_OR_RETURN(target, make_target());
    auto outcome = run_once(*target, volume, options, grab, stats);
    if (!outcome) {
      if (!target->wants_restart()) return outcome.status();
      log_warn("XR: " + outcome.status().message());
    } else if (*outcome == Outcome::kDone) {
      return stats;
    }
    if (stats.restarts >= options.max_restarts)
      return Status(ErrorCode::kGpu, "the XR session was lost " + std::to_string(stats.restarts + 1) +
                                         " times; giving up (check the headset and its runtime)");
    ++stats.restarts;
    log_info("XR: session lost; restarting (" + std::to_string(stats.restarts) + "/" +
             std::to_string(options.max_restarts) + ")");
    if (options.frames > 0 && stats.frames_rendered >= options.frames) return stats;
  }
}

}  // namespace vxr::xr
