// Roofline calibration: the device's memory-bound and sampling-bound
// ceilings, measured with two tiny kernels, so a ray caster's samples/s can
// be reported as a fraction of what the machine can do and compared across
// machines.
#pragma once

#include <memory>

#include "core/status.h"
#include "gpu/context.h"

namespace vxr::bench {

struct Roofline {
  double copy_gb_per_s = 0.0;          // bytes read + written per second, buffer stream
  double trilinear_samples_per_s = 0.0;  // 3D-texture trilinear fetches per second, ray-like access
  double transfer_gb_per_s = 0.0;     // vkCmdCopyBuffer bytes read + written per second
  double copy_ms = 0.0;
  double transfer_ms = 0.0;
  double sample_ms = 0.0;
};

// The trilinear-sampling kernel, set up once and timed on demand, so a
// benchmark can time it in turn with its own frames: on a shared machine a
// ratio of two measurements taken in turn drifts far less than one of
// measurements taken a minute apart.
class SamplingCeiling {
 public:
  static Result<std::unique_ptr<SamplingCeiling>> create(gpu::Context& ctx);
  ~SamplingCeiling();
  // Wall ms of one dispatch of samples() trilinear fetches (submitted and waited for).
  Result<double> time_ms();
  static double samples();

 private:
  struct Resources;
  explicit SamplingCeiling(gpu::Context& ctx);
  gpu::Context& ctx_;
  std::unique_ptr<Resources> res_;
};

// Takes about a second on lavapipe; `repeats` timed runs each, median kept.
// The trilinear figure is `ceiling`'s (which a caller may time again later).
Result<Roofline> measure_roofline(gpu::Context& ctx, SamplingCeiling& ceiling, int repeats);

}  // namespace vxr::bench
