#include "bench/brick_timing.h"

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

Result<TimedFrames> time_converged(BrickRenderer& r, const Camera& cam, const RenderSettings& s,
                                   const BrickFrameSettings& f, uint32_t size, int repeats) {
  TimedFrames t;
  for (int i = 0;; ++i) {
    VXR_ASSIGN_OR_RETURN(t.image, r.render(cam, s, f, size, size, &t.stats));
    if (t.stats.lod.missing == 0) break;
    if (i > 200) return internal_error("bench: the view did not converge in 200 frames");
  }
  std::vector<double> gpu;
  Status err;
  t.wall_ms = median_ms(
      repeats,
      [&] {
        VXR_RETURN_IF_ERROR(r.render_into(t.image, cam, s, f, size, size, &t.stats));
        gpu.push_back(t.stats.gpu_ms);
        return Status::ok();
      },
      &err);
  if (!err.is_ok()) return err;
  t.gpu_ms = median(gpu);
  return t;
}

}  // namespace vxr::bench
