#include "xr/lens_warp.h"

#include <algorithm>
#include <cmath>

#include "core/trace.h"

namespace vxr::xr {

WarpAxis warp_axis(uint32_t full, const LensWarp& warp) {
  WarpAxis a;
  a.full = full;
  a.step = std::max<uint32_t>(1, warp.periphery_step);
  if (!warp.enabled || a.step == 1) {
    a.centre = full;
    return a;
  }
  // Outer bands: a whole number of steps each, the rest is centre.
  const double f = std::clamp(warp.centre_fraction, 0.0, 1.0);
  uint32_t edge = static_cast<uint32_t>(std::lround(full * (1.0 - f) * 0.5));
  edge -= edge % a.step;
  a.edge_full = edge;
  a.edge_warped = edge / a.step;
  a.centre = full - 2 * edge;
  return a;
}

std::vector<WarpBand> warp_bands(const WarpAxis& ax, const WarpAxis& ay) {
  const uint32_t xs_full[4] = {0, ax.edge_full, ax.edge_full + ax.centre, ax.full};
  const uint32_t ys_full[4] = {0, ay.edge_full, ay.edge_full + ay.centre, ay.full};
  const uint32_t xs_warp[4] = {0, ax.edge_warped, ax.edge_warped + ax.centre, ax.warped()};
  const uint32_t ys_warp[4] = {0, ay.edge_warped, ay.edge_warped + ay.centre, ay.warped()};
  std::vector<WarpBand> bands;
  for (int by = 0; by < 3; ++by)
    for (int bx = 0; bx < 3; ++bx) {
      if (xs_warp[bx + 1] == xs_warp[bx] || ys_warp[by + 1] == ys_warp[by]) continue;
      bands.push_back({{xs_warp[bx], ys_warp[by], xs_warp[bx + 1], ys_warp[by + 1]},
                       {xs_full[bx], ys_full[by], xs_full[bx + 1], ys_full[by + 1]}});
    }
  return bands;
}

}  // namespace vxr::xr
