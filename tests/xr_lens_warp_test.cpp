// Lens-warped ray casting: fewer rays at equal centre density, the centre
// band reproduced exactly, small error after resampling.
#include <doctest/doctest.h>

#include "assets/assets.h"
#include "gpu_fixture.h"
#include "volume/dense_chunk_source.h"
#include "xr/eye_renderer.h"
#include "xr/view_session.h"

using namespace vxr;
using namespace vxr::xr;

TEST_CASE("lens warp: the warped grid keeps full density in the centre band and halves it outside") {
  const WarpAxis a = warp_axis(128, {true, 0.5, 2});
  CHECK(a.edge_full == 32);
  CHECK(a.centre == 64);
  CHECK(a.edge_warped == 16);
  CHECK(a.warped() == 96);
  CHECK(a.to_warped(32.5) == 16.5);   // first centre pixel lands on a sample centre
  CHECK(a.to_warped(0.0) == 0.0);
  CHECK(a.to_warped(128.0) == 96.0);
  const WarpAxis off = warp_axis(128, {false, 0.5, 2});
  CHECK(off.warped() == 128);
}

TEST_CASE("lens warp: 0.5625x the rays and under 2/255 mean error on the sample head") {
  test::GpuTestScope scope;
  auto volume = assets::sample_volume();
  REQUIRE(volume.is_ok());
  std::vector<DenseVolume> channels{*volume};
  auto source = DenseChunkSource::create(std::move(channels));
  REQUIRE(source.is_ok());
  auto eyes = EyeRenderer::create(test::gpu_context(), *source);
  REQUIRE(eyes.is_ok());
  const xr::VolumeTransform t = default_volume_transform((*eyes)->placement());
  ViewSpec view;
  view.pose.position = {0.03, 1.62, -0.30};  // close: the head reaches into the outer bands
  view.fov = {-0.785398, 0.698132, 0.785398, -0.785398};
  view.width = view.height = 128;
  uint64_t rays_full = 0, rays_warped = 0;
  auto full = (*eyes)->render(view, t, default_view_settings(), {}, &rays_full);
  auto warped = (*eyes)->render(view, t, default_view_settings(), {true, 0.5, 2}, &rays_warped);
  REQUIRE(full.is_ok());
  REQUIRE(warped.is_ok());
  CHECK(rays_full == 128u * 128u);
  CHECK(rays_warped == 96u * 96u);
  double sum = 0.0;
  uint64_t n = 0, lit = 0, outer_lit = 0;
  int centre_max = 0;
  for (uint32_t y = 0; y < 128; ++y)
    for (uint32_t x = 0; x < 128; ++x)
      for (int c = 0; c < 3; ++c) {
        const int d = std::abs(int(full->at(x, y)[c]) - int(warped->at(x, y)[c]));
        sum += d;
        ++n;
        if (c == 0 && full->at(x, y)[0] > 0) {
          ++lit;
          if (x < 32 || x >= 96) ++outer_lit;
        }
        if (x >= 33 && x < 95 && y >= 33 && y < 95) centre_max = std::max(centre_max, d);
      }
  MESSAGE("mean abs error " << sum / n << " /255, centre max " << centre_max);
  CHECK(lit > 128 * 128 / 4);     // the head is really in view
  CHECK(outer_lit > 500);         // ... and in the half-density bands
  CHECK(sum / n <= 2.0);          // <= 2/255
  CHECK(centre_max <= 2);         // centre rays are the same rays (float rounding only)
}

TEST_CASE("lens warp: the one-view warped grid casts the full image's rays where they coincide (step 3)") {
  // With 3 pixels per ray, warped ray k of an outer band lies on the centre of
  // output pixel 3k + 1, and the linear blit samples it exactly there: those
  // pixels (and the centre band) must equal the full render's. Rays that did
  // not follow the warp (a uniform grid, or tiles misplaced) fail this.
  test::GpuTestScope scope;
  auto volume = assets::sample_volume();
  REQUIRE(volume.is_ok());
  std::vector<DenseVolume> channels{*volume};
  auto source = DenseChunkSource::create(std::move(channels));
  REQUIRE(source.is_ok());
  auto eyes = EyeRenderer::create(test::gpu_context(), *source);
  REQUIRE(eyes.is_ok());
  const xr::VolumeTransform t = default_volume_transform((*eyes)->placement());
  ViewSpec view;
  view.pose.position = {-0.15, 1.7, -0.28};
  view.fov = {-0.785398, 0.698132, 0.785398, -0.785398};
  view.width = view.height = 129;
  const LensWarp warp{true, 0.5, 3};
  const WarpAxis a = warp_axis(129, warp);
  REQUIRE(a.edge_full == 30);
  REQUIRE(a.warped() == 89);
  uint64_t rays = 0;
  auto full = (*eyes)->render(view, t, default_view_settings(), {});
  auto warped = (*eyes)->render(view, t, default_view_settings(), warp, &rays);
  REQUIRE(full.is_ok());
  REQUIRE(warped.is_ok());
  CHECK(rays == 89u * 89u);
  auto on_ray = [&](uint32_t p) {
    return (p >= a.edge_full && p < a.edge_full + a.centre) || (p < a.edge_full ? p : p - a.edge_full - a.centre) % 3 == 1;
  };
  int max_diff = 0;
  uint64_t compared = 0, lit_outer = 0;
  for (uint32_t y = 0; y < 129; ++y)
    for (uint32_t x = 0; x < 129; ++x) {
      if (!on_ray(x) || !on_ray(y)) continue;
      ++compared;
      const bool outer = x < a.edge_full || y < a.edge_full || x >= a.edge_full + a.centre || y >= a.edge_full + a.centre;
      if (outer && full->at(x, y)[0] > 8) ++lit_outer;
      for (int c = 0; c < 3; ++c)
        max_diff = std::max(max_diff, std::abs(int(full->at(x, y)[c]) - int(warped->at(x, y)[c])));
    }
  MESSAGE("compared " << compared << " pixels, " << lit_outer << " lit in the outer bands, max diff " << max_diff);
  CHECK(lit_outer > 200);  // the head really reaches the outer bands
  CHECK(max_diff <= 1);
}
