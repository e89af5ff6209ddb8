#include "bench/brick_timing.h"

#include <algorithm>
#include <chrono>

#include "bench.h"

namespace vxr::bench {

RenderSettings vtk_ramp(OpticalModel model, double lo, double hi) {
  RenderSettings s;
  s.model = model;
  s.channels[0].window_lo = lo;
  s.channels[0].window_hi = hi;
  s.channels[0].colormap = "gray";
  s.channels[0].opacity_points = {{0.0, 0.0}, {1.0, 1.0}};
  return s;
}

Result<std::vector<TimedFrames>> time_in_turn(BrickRenderer& r, const Camera& cam, const RenderSettings& s,
                                              const std::vector<BrickFrameSettings>& frames, uint32_t size,
                                              int repeats, const std::function<Status()>& after_round) {
  std::vector<TimedFrames> t(frames.size());
  // Frames per round: a short frame is drawn back to back until the round
  // holds about kRoundMs of it, so a pause of the machine's other work
  // falls on a few of its many samples, not on one of five (the sparse
  // vessels' 2.5 ms frame moved by 2x between roofline runs).
  constexpr double kRoundMs = 20.0;
  std::vector<int> per_round(frames.size(), 1);
  for (size_t k = 0; k < frames.size(); ++k) {
    for (int i = 0;; ++i) {
      VXR_ASSIGN_OR_RETURN(t[k].image, r.render(cam, s, frames[k], size, size, &t[k].stats));
      if (t[k].stats.lod.missing == 0) break;
      if (i > 200) return internal_error("bench: the view did not converge in 200 frames");
    }
    // A warm-up with every brick resident: pipelines and classified cells in place.
    const auto t0 = std::chrono::steady_clock::now();
    VXR_RETURN_IF_ERROR(r.render_into(t[k].image, cam, s, frames[k], size, size, &t[k].stats));
    per_round[k] = std::clamp(int(kRoundMs / std::max(ms_since(t0), 1e-3)), 1, 50);
  }
  std::vector<std::vector<double>> wall(frames.size()), gpu(frames.size());
  for (int i = 0; i < repeats; ++i) {
    for (size_t k = 0; k < frames.size(); ++k) {
      for (int f = 0; f < per_round[k]; ++f) {
        const auto t0 = std::chrono::steady_clock::now();
        VXR_RETURN_IF_ERROR(r.render_into(t[k].image, cam, s, frames[k], size, size, &t[k].stats));
        wall[k].push_back(ms_since(t0));
        gpu[k].push_back(t[k].stats.gpu_ms);
      }
    }
    if (after_round) {
      VXR_RETURN_IF_ERROR(after_round());
      // The hook may evict the view's bricks from the caches (the roofline's
      // ceiling kernel streams 16 MB): the next round starts warm, as a
      // viewer's back-to-back frames do, not with the first kind cold alone.
      if (i + 1 < repeats) VXR_RETURN_IF_ERROR(r.render_into(t[0].image, cam, s, frames[0], size, size, &t[0].stats));
    }
  }
  for (size_t k = 0; k < frames.size(); ++k) {
    t[k].wall_ms = median(wall[k]);
    t[k].gpu_ms = median(gpu[k]);
  }
  return t;
}

}  // namespace vxr::bench
