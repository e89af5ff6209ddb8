// The numerical stress suite behind `vxr bench stability` and its ctest
// subset: seeded random ray-casting configurations that go out of their way
// to hit the hard cases (axis-parallel and grazing rays, a camera exactly on
// a face, edge or corner or inside the box, zero-size and one-voxel-thick
// volumes, offsets up to 2^24 voxels, scales 1e-6..1e6, anisotropy to 1:100,
// NaN/Inf voxels, constant data, extreme transfer functions, steps from 1/64
// to 8 voxels).
//
// Each case is rendered by the one renderer (the brick renderer over the
// case's volume in memory, render/lod/memory_volume.h) into RGBA32F and by the
// CPU double-precision reference at the same step on the same eye-anchored
// grid (same sample positions, so the difference is the GPU's float
// arithmetic and texture filtering, not the discretisation); it passes when no output channel is NaN or Inf and the
// max-abs difference is within its class's bound.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include "core/status.h"
#include "render/camera.h"
#include "core/image.h"
#include "gpu/context.h"
#include "render/lod/brick_renderer.h"
#include "scene/render_settings.h"
#include "volume/dense_volume.h"

namespace vxr::bench {

struct StabilityClass {
  const char* name;
  double bound;     // max-abs error (0..1 units) against the same-step reference, before case_bound's gain
  const char* why;  // where the bound comes from
};

// When a case's gain drives its max-abs bound to 1 (a hard opacity or colour
// step, a window 1e-6 of the range, float data holding +-1e30), a sample
// within the filter's value error of a threshold may flip a pixel, and a
// zoomed view of a flat region near the threshold flips many together, so
// max-abs cannot fail. Such a case is held to a coarse guard instead: at most
// this fraction of its pixels may be off by more than case_flip_tolerance. It
// catches errors that move the whole picture (wrong density, overflow, a lost
// segment); worst seen 26.7% over seeds 1-4 x 10,000 cases.
inline constexpr double kCappedOverFraction = 0.5;

// Every class, in the order cases cycle through them.
const std::vector<StabilityClass>& stability_classes();

struct StabilityCase {
  uint32_t index = 0;
  uint32_t class_index = 0;
  DenseVolume volume;  // tiny; voxel_size and origin carry the placement
  Camera camera;       // world space
  RenderSettings settings;
  uint32_t width = 15, height = 15;
  bool expect_rejection = false;  // zero-size volumes: both renderers must refuse with kInvalidArgument
  std::string note;               // what is special about it, for failure reports
};

// Case `index` of the suite with `seed`: deterministic, independent of the
// other cases (so any failure can be re-run alone with the same seed/index).
StabilityCase make_stability_case(uint64_t seed, uint32_t index);

struct CaseOutcome {
  bool passed = false;
  bool non_finite = false;   // NaN or Inf in some output channel (GPU or reference)
  double max_abs = 0.0;      // GPU vs reference, 0..1 units
  double bound = 0.0;        // what max_abs had to stay within (case_bound)
  bool capped = false;       // case_bound reached 1: max-abs cannot fail, over_fraction is checked instead
  double over_fraction = 0;  // fraction of pixels with some channel off by more than case_flip_tolerance
  std::string failure;       // empty when passed
};

// The case's error bound: its class's bound times how much the case's
// settings amplify a small error in a sampled value (window slope relative to
// the texel range, the steepest transfer-function segment or colormap step, gamma, extinction
// per step above 1), capped at 1. For ordinary settings it is the class bound.
double case_bound(const StabilityCase& c);
// What a pixel away from any threshold flip must stay within in a capped
// case: the class bound times the colormap's steepest slope.
double case_flip_tolerance(const StabilityCase& c);

// Renders one case on `ctx` (a renderer over the case's volume, with
// `pipelines` shared across cases) and with the reference, and judges it.
CaseOutcome run_stability_case(gpu::Context& ctx, const StabilityCase& c,
                               const std::shared_ptr<BrickPipelines>& pipelines = nullptr);

// Largest |a - b| over all channels; +inf if sizes differ or either is NaN.
double max_abs_difference(const ImageRgbaF& a, const ImageRgbaF& b);
// Fraction of pixels with some channel differing by more than `tolerance` (1 if sizes differ).
double fraction_over(const ImageRgbaF& a, const ImageRgbaF& b, double tolerance);
bool all_finite(const ImageRgbaF& image);

}  // namespace vxr::bench
