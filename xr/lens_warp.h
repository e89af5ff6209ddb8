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
// xr/eye_renderer stretches the bands onto the eye with linear blits.
#pragma once

#include <cstdint>
#include <vector>

#include "core/image.h"
#include "core/status.h"
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

}  // namespace vxr::xr
