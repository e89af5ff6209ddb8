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

Result<ImageRgba8> render_lens_warped(Raycaster& caster, const Camera& camera, const RenderSettings& settings,
                                      uint32_t width, uint32_t height, const LensWarp& warp, uint64_t* rays) {
  VXR_TRACE_SCOPE("xr.render_lens_warped");
  if (!camera.frustum) return invalid_argument("render_lens_warped: the camera needs an off-axis frustum");
  const WarpAxis ax = warp_axis(width, warp), ay = warp_axis(height, warp);
  const FrustumTangents& t = *camera.frustum;
  // Output pixel edge -> tangent (x left to right, y top to bottom).
  auto tan_x = [&](double p) { return t.left + p / width * (t.right - t.left); };
  auto tan_y = [&](double p) { return t.up - p / height * (t.up - t.down); };
  ImageRgba8 warped(ax.warped(), ay.warped());
  uint64_t cast = 0;
  for (const WarpBand& b : warp_bands(ax, ay)) {
    const uint32_t w = b.warped[2] - b.warped[0], h = b.warped[3] - b.warped[1];
    Camera tile = camera;
    tile.frustum = FrustumTangents{tan_x(b.full[0]), tan_x(b.full[2]), tan_y(b.full[3]), tan_y(b.full[1])};
    VXR_ASSIGN_OR_RETURN(ImageRgba8 part, caster.render(tile, settings, w, h));
    cast += uint64_t(w) * h;
    for (uint32_t y = 0; y < h; ++y)
      std::copy_n(part.at(0, y), size_t(w) * 4, warped.at(b.warped[0], b.warped[1] + y));
  }
  if (rays) *rays = cast;
  if (ax.warped() == width && ay.warped() == height) return warped;
  return resample_warped(warped, ax, ay);
}

ImageRgba8 resample_warped(const ImageRgba8& warped, const WarpAxis& ax, const WarpAxis& ay) {
  VXR_TRACE_SCOPE("xr.resample_warped");
  ImageRgba8 out(ax.full, ay.full);
  // Per axis: the two warped texels and the weight of the second.
  struct Tap {
    uint32_t i0, i1;
    float w;
  };
  auto taps = [](const WarpAxis& a, uint32_t n_warped) {
    std::vector<Tap> v(a.full);
    for (uint32_t i = 0; i < a.full; ++i) {
      const double q = std::clamp(a.to_warped(i + 0.5) - 0.5, 0.0, double(n_warped - 1));
      const uint32_t i0 = static_cast<uint32_t>(std::floor(q));
      const uint32_t i1 = std::min(i0 + 1, n_warped - 1);
      v[i] = {i0, i1, static_cast<float>(q - i0)};
    }
    return v;
  };
  const std::vector<Tap> tx = taps(ax, warped.width), ty = taps(ay, warped.height);
  for (uint32_t y = 0; y < ay.full; ++y) {
    for (uint32_t x = 0; x < ax.full; ++x) {
      const Tap& a = tx[x];
      const Tap& b = ty[y];
      uint8_t* o = out.at(x, y);
      for (int c = 0; c < 4; ++c) {
        const float top = warped.at(a.i0, b.i0)[c] * (1 - a.w) + warped.at(a.i1, b.i0)[c] * a.w;
        const float bot = warped.at(a.i0, b.i1)[c] * (1 - a.w) + warped.at(a.i1, b.i1)[c] * a.w;
        o[c] = static_cast<uint8_t>(std::lround(top * (1 - b.w) + bot * b.w));
      }
    }
  }
  return out;
}

}  // namespace vxr::xr
