// Lens-warped ray casting (the paper's "rendering in the wrapped space").
//
// A headset's lens magnifies the centre of each eye's image and squeezes the
// edges, so the compositor throws away most of the rectangular eye buffer's
// peripheral detail. We cast rays on a separable grid that is denser at the
// centre: along each axis the middle `centre_fraction` of the image keeps full
// density and each outer band gets one ray per `periphery_step` pixels. The
// warp u -> ndc is piecewise linear, so every band pair is an ordinary
// off-axis frustum: the ray caster renders 3x3 tiles with exact rays and
// resample_warped() maps the warped image back onto the full pixel grid
// (bilinear in warped coordinates; centre pixels land exactly on a sample).
#pragma once

#include <cstdint>

#include "core/image.h"
#include "core/status.h"
#include "render/raycaster.h"

namespace vxr::xr {

struct LensWarp {
  bool enabled = false;
  double centre_fraction = 0.5;  // of each axis, cast at full density
  uint32_t periphery_step = 2;   // pixels per ray in the outer bands
};

// One axis of the warped grid, in pixels.
struct WarpAxis {
  uint32_t full = 0;         // output pixels
  uint32_t edge_full = 0;    // output pixels in each outer band
  uint32_t centre = 0;       // output (= warped) pixels in the centre band
  uint32_t edge_warped = 0;  // rays across each outer band
  uint32_t step = 1;
  uint32_t warped() const { return centre + 2 * edge_warped; }
  // Continuous warped coordinate of continuous output coordinate p (both in
  // pixels, 0 at the first pixel's left edge).
  double to_warped(double p) const;
};

WarpAxis warp_axis(uint32_t full, const LensWarp& warp);

// Renders `camera` (its frustum must be set) at width x height output pixels
// through the warped grid and resamples it. `rays` (if given) receives the
// number of rays cast.
Result<ImageRgba8> render_lens_warped(Raycaster& caster, const Camera& camera, const RenderSettings& settings,
                                      uint32_t width, uint32_t height, const LensWarp& warp,
                                      uint64_t* rays = nullptr);

// Maps a warped image (ax.warped() x ay.warped()) onto the full grid.
ImageRgba8 resample_warped(const ImageRgba8& warped, const WarpAxis& ax, const WarpAxis& ay);

}  // namespace vxr::xr
