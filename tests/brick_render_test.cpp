// The out-of-core path end to end on the GPU: procedural source -> LOD ->
// brick pool -> brick ray caster. Why the pictures are right: the skipped,
// paged and throttled images are compared with images made without skipping,
// without paging and without throttling; the goldens pin cut plane, ROI and a
// multi-level view of the procedural vessels.
#include <doctest/doctest.h>

#include <algorithm>
#include <set>

#include "golden.h"
#include "gpu_fixture.h"
#include "render/lod/brick_renderer.h"
#include "volume/procedural_source.h"

using namespace vxr;

namespace {

std::unique_ptr<ProceduralSource> make(uint64_t side, uint32_t noise = 6) {
  ProceduralOptions o;
  o.dims = {side, side, side};
  o.noise_max = noise;
  auto r = ProceduralSource::create(o);
  REQUIRE(r.is_ok());
  return std::move(r).value();
}

// A renderer with an 8^3-slot pool; `o`: whatever else a test changes.
std::unique_ptr<BrickRenderer> renderer(const ChunkSource& src, BrickRendererOptions o = {}) {
  o.pool.slots = {8, 8, 8};
  auto r = BrickRenderer::create(test::gpu_context(), src, o);
  REQUIRE(r.is_ok());
  return std::move(r).value();
}

RenderSettings vessels() {
  RenderSettings s;
  s.channels[0].colormap = "hot";
  s.channels[0].window_lo = 8;  // above the background noise (0..6): empty bricks are transparent
  s.channels[0].window_hi = 200;
  s.step_voxels = 0.5;
  s.density = 0.3;
  return s;
}

// Renders until nothing is missing; returns the last frame.
ImageRgba8 converge(BrickRenderer& r, const Camera& cam, const RenderSettings& s, const BrickFrameSettings& f,
                    uint32_t w, uint32_t h, BrickFrameStats* st = nullptr) {
  BrickFrameStats local;
  for (int i = 0; i < 64; ++i) {
    auto img = r.render(cam, s, f, w, h, &local);
    REQUIRE(img.is_ok());
    if (local.lod.missing == 0) {
      if (st) *st = local;
      return *img;
    }
  }
  FAIL("did not converge in 64 frames");
  return {};
}

void check(const std::string& name, const ImageRgba8& img, const std::string& why) {
  CHECK(test::looks_non_blank(img));
  auto r = test::check_golden(name, img, test::gpu_context().info().fingerprint(), 3, why);
  INFO(r.message);
  CHECK(r.passed);
}

// A clipped frame (cut plane or ROI) of the 128^3 vessels at level 0: the
// bricks outside are culled, and the picture is the monolithic path's, which
// clips each sample instead; then the golden.
void check_clipped(const std::string& name, LodSettings clip, const std::string& why) {
  auto src = make(128);
  auto r = renderer(*src);
  const Camera cam = orbit_camera(r->placement(), 30, 25, 1.25);
  BrickFrameSettings f;
  f.lod = clip;
  f.lod.force_level = 0;
  BrickFrameStats st;
  const ImageRgba8 img = converge(*r, cam, vessels(), f, 128, 128, &st);
  CHECK(st.lod.culled > 0);
  REQUIRE(r->set_monolithic(0).is_ok());
  auto mono = r->render_monolithic(cam, vessels(), f.lod, 128, 128);
  REQUIRE(mono.is_ok());
  CHECK(test::diff_images(img, *mono).max_abs <= 1);
  check(name, img, why);
}

}  // namespace

TEST_CASE("brick render: empty-space skipping takes far fewer samples and gives the identical image") {
  test::GpuTestScope scope;
  auto src = make(128);
  auto r = renderer(*src);
  const Camera cam = orbit_camera(r->placement(), 30, 25, 1.25);
  BrickFrameSettings f;
  f.lod.force_level = 0;
  BrickFrameStats on, off;
  const ImageRgba8 a = converge(*r, cam, vessels(), f, 96, 96, &on);
  f.lod.skip_empty = false;
  const ImageRgba8 b = converge(*r, cam, vessels(), f, 96, 96, &off);
  CHECK(test::looks_non_blank(a));
  CHECK(a.pixels == b.pixels);
  CHECK(on.lod.skipped_empty > 0);
  CHECK(off.lod.skipped_empty == 0);
  MESSAGE("samples on " << on.samples << " off " << off.samples);
  CHECK(off.samples >= 3 * on.samples);
}

TEST_CASE("brick render: single pass and multipass waves give the same image") {
  test::GpuTestScope scope;
  auto src = make(128);
  auto r = renderer(*src);
  const Camera cam = orbit_camera(r->placement(), 200, -20, 0.9, 50);
  BrickFrameSettings f;
  f.lod.lod_bias = -0.5;
  f.mode = BrickPassMode::kMultipass;
  BrickFrameStats ms, ss;
  const ImageRgba8 multi = converge(*r, cam, vessels(), f, 96, 96, &ms);
  f.mode = BrickPassMode::kSinglePass;
  const ImageRgba8 single = converge(*r, cam, vessels(), f, 96, 96, &ss);
  CHECK(test::looks_non_blank(multi));
  CHECK(multi.pixels == single.pixels);
  CHECK(ms.samples == ss.samples);
  CHECK(ss.dispatches == 1);  // one march: the cells were classified by an earlier frame with the same inputs
  CHECK(ms.dispatches > 3);
}

TEST_CASE("brick render: tiled frames clear the tiles no brick touches, or draw them with the brickless variant: same image") {
  test::GpuTestScope scope;
  auto src = make(128);
  // Far away: the volume covers the middle of the image, most tiles touch no brick.
  const Camera cam = orbit_camera(renderer(*src)->placement(), 30, 25, 3.0);
  BrickFrameSettings f;
  f.lod.force_level = 0;
  f.mode = BrickPassMode::kSinglePass;
  auto reference = renderer(*src);
  BrickFrameStats ss;
  const ImageRgba8 single = converge(*reference, cam, vessels(), f, 96, 96, &ss);
  f.mode = BrickPassMode::kTiled;
  std::vector<std::vector<float>> floats;
  for (bool clear : {true, false}) {
    INFO("clear_empty_tiles " << clear);
    BrickRendererOptions o;
    o.clear_empty_tiles = clear;
    auto r = renderer(*src, o);
    BrickFrameStats ts;
    // A close view first fills the whole target: the far view's empty tiles must be written again.
    const ImageRgba8 close = converge(*r, orbit_camera(r->placement(), 30, 25, 0.5), vessels(), f, 96, 96);
    const ImageRgba8 tiled = converge(*r, cam, vessels(), f, 96, 96, &ts);
    CHECK(close.pixels != single.pixels);
    CHECK(test::looks_non_blank(tiled));
    CHECK(tiled.pixels == single.pixels);
    CHECK(ts.samples == ss.samples);
    // After the cells were classified: the tiles whose rays walk cells, then
    // those whose bricks all march without a walk (a variant without the
    // cell code, where there are any), each a dispatch; the empty ones a
    // clear, or a dispatch of their own.
    CHECK(ts.classify_passes == 0);
    CHECK(ts.tiles_empty > 0);
    CHECK(ts.dispatches == 1 + (ts.tiles_plain > 0 ? 1 : 0) + (clear ? 0 : 1));
    // Float pixels go through the accumulation image (cleared the same way) and a blit.
    REQUIRE(r->render_float(orbit_camera(r->placement(), 30, 25, 0.5), vessels(), f, 96, 96).is_ok());
    auto as_float = r->render_float(cam, vessels(), f, 96, 96);
    REQUIRE(as_float.is_ok());
    floats.push_back(std::move(as_float->rgba));
  }
  REQUIRE(floats.size() == 2);
  CHECK(floats[0] == floats[1]);
  CHECK(std::count(floats[0].begin(), floats[0].end(), 0.0f) > 0);  // the empty tiles
  CHECK(std::count(floats[0].begin(), floats[0].end(), 0.0f) < long(floats[0].size()));
}

TEST_CASE("brick render: paged through the pool equals the single-texture path within 1/255") {
  test::GpuTestScope scope;
  auto src = make(128);
  auto r = renderer(*src);
  REQUIRE(r->set_monolithic(0).is_ok());
  const Camera cam = orbit_camera(r->placement(), 30, 25, 1.25);
  BrickFrameSettings f;
  f.lod.force_level = 0;
  f.lod.skip_empty = false;
  BrickFrameStats ps, ms;
  const ImageRgba8 paged = converge(*r, cam, vessels(), f, 96, 96, &ps);
  auto mono = r->render_monolithic(cam, vessels(), f.lod, 96, 96, &ms);
  REQUIRE(mono.is_ok());
  CHECK(ps.lod.drawn > 30);
  const auto d = test::diff_images(paged, *mono);
  MESSAGE("max_abs " << d.max_abs << " differing " << d.differing << " samples " << ps.samples << " vs "
                     << ms.samples);
  CHECK(d.max_abs <= 1);
  // Same sample grid: the paged path takes the same samples, up to rays grazing brick faces.
  CHECK(double(ps.samples) == doctest::Approx(double(ms.samples)).epsilon(0.01));
}

TEST_CASE("brick render: the rays' own filter over texel views matches the sampler's") {
  // On a CPU device the rays filter the atlases' texel views by hand (float
  // weights); elsewhere, and with texel views off, they call the sampler
  // (lavapipe: 8-bit weights). Same samples for E-A; pictures within 1/255,
  // MIP within 4/255 (a maximum follows the one largest sample, which the
  // sampler's coarse weights move most) and both with an RMSE under 0.2/255.
  test::GpuTestScope scope;
  auto src = make(128);
  auto hand = renderer(*src);
  BrickRendererOptions o;
  o.pool.texel_views = false;
  auto sampled = renderer(*src, o);
  if (test::gpu_context().info().type == VK_PHYSICAL_DEVICE_TYPE_CPU) {
    CHECK(hand->pool().atlas_texels_view() != nullptr);
    CHECK(hand->pool().texel_words());  // u8: texel quads, 2 loads a sample
  }
  CHECK(sampled->pool().atlas_texels_view() == nullptr);
  const Camera cam = orbit_camera(hand->placement(), 30, 25, 1.25);
  BrickFrameSettings f;
  f.lod.force_level = 0;
  RenderSettings mip = vessels();
  mip.model = OpticalModel::kMip;
  for (const RenderSettings& s : {vessels(), mip}) {
    CAPTURE(int(s.model));
    BrickFrameStats hs, ss;
    const ImageRgba8 a = converge(*hand, cam, s, f, 96, 96, &hs);
    const ImageRgba8 b = converge(*sampled, cam, s, f, 96, 96, &ss);
    const auto d = test::diff_images(a, b);
    MESSAGE("max_abs " << d.max_abs << " rmse " << d.rmse << " differing " << d.differing);
    CHECK(test::looks_non_blank(a));
    CHECK(d.max_abs <= (s.model == OpticalModel::kMip ? 4 : 1));
    CHECK(d.rmse < 0.2);
    // E-A skips by the transfer function alone: the same samples. MIP skips
    // a cell by the running maximum, which the two filters move apart a little.
    if (s.model == OpticalModel::kMip)
      CHECK(double(hs.samples) == doctest::Approx(double(ss.samples)).epsilon(0.001));
    else
      CHECK(hs.samples == ss.samples);
  }
}

TEST_CASE("brick render: with uploads throttled every frame is complete and converges to the full-resolution image") {
  test::GpuTestScope scope;
  auto src = make(128);
  RenderSettings s = vessels();
  s.channels[0].window_lo = -50;  // every voxel, even a zero, has some opacity: every ray through the volume gets alpha
  s.density = 0.05;
  const Camera cam = orbit_camera({{128, 128, 128}, {1, 1, 1}}, 30, 25, 1.25);
  BrickFrameSettings f;
  f.lod.force_level = 0;
  auto full_r = renderer(*src);
  const ImageRgba8 full = converge(*full_r, cam, s, f, 64, 64);

  auto r = renderer(*src);
  f.upload_budget_bytes = 4 * r->pool().brick_bytes();
  int frames = 0;
  ImageRgba8 last;
  for (; frames < 64; ++frames) {
    BrickFrameStats st;
    auto img = r->render(cam, s, f, 64, 64, &st);
    REQUIRE(img.is_ok());
    CHECK(st.bricks_uploaded <= 4);
    // Covered: full-resolution alpha of at least 8/255. A ray that only grazes
    // the volume's silhouette for less than one coarse step (alpha 1..3 here)
    // may take no sample at a coarser level: that is sampling, not a missing
    // brick (the CPU test proves the drawn bricks tile the volume each frame).
    uint64_t holes = 0;
    for (size_t i = 3; i < full.pixels.size(); i += 4)
      if (full.pixels[i] >= 8 && img->pixels[i] == 0) ++holes;
    CHECK(holes == 0);
    last = *img;
    if (st.lod.missing == 0) break;
  }
  CHECK(frames > 4);
  CHECK(last.pixels == full.pixels);
}

TEST_CASE("brick render: a cut plane clips the vessels (golden)") {
  test::GpuTestScope scope;
  LodSettings clip;
  const glm::dvec3 n = glm::normalize(glm::dvec3(1, 1, 0.5));
  clip.cut = {true, n, -glm::dot(n, glm::dvec3(64))};
  check_clipped("lod_cut_plane", clip,
                "vessels of the 128^3 procedural volume cut by the oblique plane (1,1,0.5) through the centre; the "
                "half toward +x+y remains");
}

TEST_CASE("brick render: an ROI keeps only its box (golden)") {
  test::GpuTestScope scope;
  LodSettings clip;
  clip.roi = {true, {20, 30, 10}, {100, 90, 80}};
  check_clipped("lod_roi", clip, "only the vessels inside the box [20,100]x[30,90]x[10,80] of the 128^3 volume");
}

TEST_CASE("brick render: a close view mixes levels by distance (golden)") {
  test::GpuTestScope scope;
  auto src = make(2048);
  auto r = renderer(*src);
  const Camera cam = orbit_camera(r->placement(), 40, 30, 0.45, 60);
  BrickFrameSettings f;
  f.lod.lod_bias = 1.0;
  BrickFrameStats st;
  const ImageRgba8 img = converge(*r, cam, vessels(), f, 128, 128, &st);
  MESSAGE(format_stats(st));
  CHECK(st.lod.drawn > 8);
  CHECK(st.lod.fallback == 0);
  check("lod_multilevel", img,
        "2048^3 procedural vessels seen from inside the bounding sphere at 60 degrees: near bricks fine, far ones "
        "coarse (bias 1), converged");
}

TEST_CASE("brick render: render_into reuses its image and the staging buffer across sizes and gives render()'s pixels") {
  test::GpuTestScope scope;
  auto src = make(64);
  auto r = renderer(*src);
  const Camera cam = orbit_camera(r->placement(), 30, 25, 1.25);
  BrickFrameSettings f;
  f.lod.force_level = 0;
  const ImageRgba8 warm = converge(*r, cam, vessels(), f, 80, 60);  // every brick resident
  REQUIRE(test::looks_non_blank(warm));
  ImageRgba8 into;
  // Down then up: the staging buffer shrinks in use, then grows.
  for (const auto& [w, h] : {std::pair{80u, 60u}, std::pair{40u, 30u}, std::pair{120u, 90u}, std::pair{120u, 90u}}) {
    CAPTURE(w);
    REQUIRE(r->render_into(into, cam, vessels(), f, w, h).is_ok());
    auto fresh = r->render(cam, vessels(), f, w, h);
    REQUIRE(fresh.is_ok());
    CHECK(into.width == w);
    CHECK(into.height == h);
    CHECK(into.pixels == fresh->pixels);
    CHECK(test::looks_non_blank(into));
  }
}
