// Lens-warped ray casting (the paper's "rendering in the wrapped space").
//
// A headset's lens magnifies the centre of each eye's image and squeezes the
// edges, so the compositor throws away most of the rectangular eye buffer's
// peripheral detail. We cast rays on a separable grid that is denser at the
// centre: along each axis the middle `centre_fraction` of the image keeps full
// density and each outer band gets one ray per `periphery_step` pixels. The
// warp u -> ndc is piecewise linear, so every band pair is an ordinary
// off-axis frustum. The out-of-core renderer casts the whole warped grid as
// one view (RenderTarget::warp_x/warp_y: each ray follows the warp) and
// xr/eye_renderer stretches the bands onto the eye with linear blits; the
// dense ray caster renders the 3x3 tiles with exact rays, and
// resample_warped() maps its warped image back onto the full pixel grid
// (bilinear in warped coordinates; centre pixels land exactly on a sample).
#pragma once

#include <cstdint>
#include <vector>

#include "core/image.h"
#include "core/status.h"
#include "render/raycaster.h"
#include "render/volume_renderer.h"

namespace vxr::xr {

struct LensWarp {
  bool enabled = false;
  double centre_fraction = 0.5;  // of each axis, cast at full density
  uint32_t periphery_step = 2;   // pixels per ray in the outer bands
};

// One axis of the warped grid: the renderer's (render/volume_renderer.h).
using vxr::WarpAxis;
WarpAxis warp_axis(uint32_t full, const LensWarp& warp);

// The up to 3x3 band pairs of the warped grid (empty ones left out): a
// rectangle of the warped image and the output rectangle it stretches onto,
// corners [x0, x1) x [y0, y1) in pixels.
struct WarpBand {
  uint32_t warped[4];  // x0, y0, x1, y1
  uint32_t full[4];
};
std::vector<WarpBand> warp_bands(const WarpAxis& ax, const WarpAxis& ay);

// Dense ray caster (the CPU-side comparison in bench accuracy): renders `camera` (its frustum must be set) at width x height output pixels
// through the warped grid and resamples it. `rays` (if given) receives the
// number of rays cast.
Result<ImageRgba8> render_lens_warped(Raycaster& caster, const Camera& camera, const RenderSettings& settings,
                                      uint32_t width, uint32_t height, const LensWarp& warp,
                                      uint64_t* rays = nullptr);

// Maps a warped image (ax.warped() x ay.warped()) onto the full grid.
ImageRgba8 resample_warped(const ImageRgba8& warped, const WarpAxis& ax, const WarpAxis& ay);

}  // namespace vxr::xr
