// Empty-space skipping inside bricks (BrickCells): rays jump cells whose
// voxels cannot change a pixel under the frame's transfer function. Why the
// pictures are right: for every optical model that skips, and for both pass
// modes, the image with skipping is compared byte for byte with the image
// without any skipping (bricks or cells) and with brick-level skipping only;
// the cells must also remove samples, or the test fails (a no-op skip passes
// nothing).
#include <doctest/doctest.h>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <random>
#include <set>
#include <tuple>

#include "golden.h"
#include "gpu_fixture.h"
#include "render/camera.h"
#include "render/lod/brick_renderer.h"
#include "shared/brick_params.h"
#include "volume/dense_chunk_source.h"
#include "volume/procedural_source.h"

using namespace vxr;

namespace {

std::unique_ptr<ProceduralSource> sparse_vessels(uint64_t side) {
  ProceduralOptions o;
  o.dims = {side, side, side};
  o.noise_max = 6;
  auto r = ProceduralSource::create(o);
  REQUIRE(r.is_ok());
  return std::move(r).value();
}

// A renderer over `src` (which must outlive it) with a pool of 8x8x8 slots.
std::unique_ptr<BrickRenderer> small_pool_renderer(const ChunkSource& src, BrickRendererOptions ro = {}) {
  ro.pool.slots = {8, 8, 8};
  auto made = BrickRenderer::create(test::gpu_context(), src, ro);
  REQUIRE(made.is_ok());
  return std::move(made).value();
}

// A smooth 64^3 ball: the value falls linearly from 255 at the centre to 0 at radius 30.
DenseVolume linear_ball() {
  DenseVolume ball;
  ball.dims = {64, 64, 64};
  ball.data.resize(ball.voxel_count());
  size_t i = 0;
  for (uint32_t z = 0; z < 64; ++z)
    for (uint32_t y = 0; y < 64; ++y)
      for (uint32_t x = 0; x < 64; ++x, ++i) {
        const double r = std::sqrt((x - 31.5) * (x - 31.5) + (y - 31.5) * (y - 31.5) + (z - 31.5) * (z - 31.5));
        ball.data[i] = static_cast<uint8_t>(std::clamp(255.0 * (1.0 - r / 30.0), 0.0, 255.0));
      }
  return ball;
}

// The vessels' settings for the on/off identity tests: step 0.5, hot, dense enough to terminate rays.
RenderSettings vessel_settings(OpticalModel model) {
  RenderSettings s;
  s.model = model;
  s.channels[0].colormap = "hot";
  // MinIP: a window inside the vessels' values, so the minimum is not the background.
  s.channels[0].window_lo = model == OpticalModel::kMinIp ? 0 : 8;
  s.channels[0].window_hi = 200;
  s.step_voxels = 0.5;
  s.density = 0.3;
  s.iso_value = 100;  // inside the vessels' walls
  if (model == OpticalModel::kAverage) {
    // A ray spends a few percent of its length in the vessels: a window and
    // a table that show such averages.
    s.channels[0].window_hi = 24;
    s.channels[0].opacity_points = {{0.0, 0.0}, {0.05, 1.0}, {1.0, 1.0}};
  }
  return s;
}

ImageRgba8 converge(BrickRenderer& r, const Camera& cam, const RenderSettings& s, const BrickFrameSettings& f,
                    uint32_t w, uint32_t h, BrickFrameStats* st) {
  for (int i = 0; i < 64; ++i) {
    auto img = r.render(cam, s, f, w, h, st);
    REQUIRE(img.is_ok());
    if (st->lod.missing == 0) return *img;
  }
  FAIL("did not converge in 64 frames");
  return {};
}

// Views of sparse_vessels(128) for the tile-list tests: from outside,
// along an axis, from inside (blocks reaching behind the eye), with an ROI
// and with a cut.
struct ClipView {
  const char* what;
  Camera cam;
  RoiBox roi;
  CutPlane cut;
  // A tiled frame at full detail with the view's ROI and cut.
  BrickFrameSettings frame() const {
    BrickFrameSettings f;
    f.lod.force_level = 0;
    f.lod.roi = roi;
    f.lod.cut = cut;
    f.mode = BrickPassMode::kTiled;
    return f;
  }
};
std::vector<ClipView> clip_views(const VolumePlacement& placement) {
  const glm::dvec3 n = glm::normalize(glm::dvec3(1, 1, 0.5));
  return {
      {"orbit", orbit_camera(placement, 30, 25, 1.25), {}, {}},
      {"along x", orbit_camera(placement, 0, 0), {}, {}},
      {"eye inside", orbit_camera(placement, 20, 10, 0.2), {}, {}},
      {"roi", orbit_camera(placement, 30, 25, 1.25), {true, {10, 20, 5}, {100, 90, 120}}, {}},
      {"cut", orbit_camera(placement, -40, 30, 1.25), {}, {true, n, -glm::dot(n, glm::dvec3(64))}},
  };
}

// Renders `s` from `cam` with skipping on and off (converged): the images
// must be byte-identical, not blank, and skipping must take fewer samples.
void check_skipping_keeps_image(BrickRenderer& r, const Camera& cam, const RenderSettings& s, BrickFrameSettings f,
                                uint32_t w, uint32_t h) {
  BrickFrameStats on, off;
  const ImageRgba8 a = converge(r, cam, s, f, w, h, &on);
  f.lod.skip_empty = false;
  const ImageRgba8 b = converge(r, cam, s, f, w, h, &off);
  INFO("samples " << on.samples << " vs " << off.samples);
  CHECK(test::looks_non_blank(a));
  CHECK(a.pixels == b.pixels);
  CHECK(on.samples < off.samples);
}

// check_skipping_keeps_image from each of the clip views, tiled and multipass.
void check_clip_views_keep_image(BrickRenderer& r, const RenderSettings& s) {
  for (const ClipView& v : clip_views(r.placement())) {
    for (BrickPassMode mode : {BrickPassMode::kTiled, BrickPassMode::kMultipass}) {
      BrickFrameSettings f = v.frame();
      f.mode = mode;
      INFO(std::string(v.what) << (mode == BrickPassMode::kTiled ? " tiled" : " multipass"));
      check_skipping_keeps_image(r, v.cam, s, f, 97, 97);
    }
  }
}

// The direct definition: every texel a sample inside the cell filters (its
// core) and one voxel further (its ring), as floats, std::min/max from +-inf;
// the core's ends moved towards the ring's by the band's weight.
std::vector<glm::vec2> direct_cell_ranges(VkFormat format, const uint8_t* texels, uint32_t cs, uint32_t apron,
                                          const BrickCells& cells) {
  const uint32_t edge = cs + 2 * apron, n = cells.cells_per_axis, s = cells.cell_size;
  auto value = [&](size_t i) -> float {
    if (format == VK_FORMAT_R8_UNORM) return float(texels[i]) / 255.0f;
    if (format == VK_FORMAT_R16_UNORM) {
      uint16_t v;
      std::memcpy(&v, texels + 2 * i, 2);
      return float(v) / 65535.0f;
    }
    float v;
    std::memcpy(&v, texels + 4 * i, 4);
    return v;
  };
  auto slot = [&](int64_t v) { return uint32_t(std::clamp<int64_t>(v + apron, 0, edge - 1)); };
  auto range = [&](uint32_t cx, uint32_t cy, uint32_t cz, int64_t wider) {
    const glm::i64vec3 c(cx, cy, cz);
    const glm::uvec3 lo(slot(c.x * s - 1 - wider), slot(c.y * s - 1 - wider), slot(c.z * s - 1 - wider));
    const glm::uvec3 hi(slot(c.x * s + s - 1 + wider), slot(c.y * s + s - 1 + wider), slot(c.z * s + s - 1 + wider));
    float l = INFINITY, h = -INFINITY;
    for (uint32_t z = lo.z; z <= hi.z; ++z)
      for (uint32_t y = lo.y; y <= hi.y; ++y)
        for (uint32_t x = lo.x; x <= hi.x; ++x) {
          const float v = value((size_t(z) * edge + y) * edge + x);
          l = std::min(l, v);
          h = std::max(h, v);
        }
    return glm::vec2(l, h);
  };
  const float w = float(3.0 * VXR_CELL_BAND);
  std::vector<glm::vec2> out(cells.count());
  for (uint32_t cz = 0; cz < n; ++cz)
    for (uint32_t cy = 0; cy < n; ++cy)
      for (uint32_t cx = 0; cx < n; ++cx) {
        const glm::vec2 core = range(cx, cy, cz, 0), ring = range(cx, cy, cz, 1);
        float lo = core.x, hi = core.y;
        if (ring.x < lo) lo = (1.0f - w) * lo + w * ring.x;
        if (ring.y > hi) hi = (1.0f - w) * hi + w * ring.y;
        const float pad_lo = std::abs(lo) * 1e-5f + 1e-7f, pad_hi = std::abs(hi) * 1e-5f + 1e-7f;
        out[(size_t(cz) * n + cy) * n + cx] = glm::vec2(lo - pad_lo, hi + pad_hi);
      }
  return out;
}

// A trilinear sample of one slot at local position p (voxel i's centre at
// i + 0.5), in double, indices clamped to the slot as the atlas's apron does.
double trilinear(const std::vector<uint8_t>& texels, uint32_t edge, uint32_t apron, glm::dvec3 p) {
  const glm::dvec3 a = p + double(apron) - 0.5, f0 = glm::floor(a), f = a - f0;
  double v = 0.0;
  for (int corner = 0; corner < 8; ++corner) {
    const glm::ivec3 d(corner & 1, (corner >> 1) & 1, corner >> 2);
    const glm::ivec3 i = glm::clamp(glm::ivec3(f0) + d, glm::ivec3(0), glm::ivec3(int(edge) - 1));
    const glm::dvec3 wt = glm::mix(1.0 - f, f, glm::dvec3(d));
    v += wt.x * wt.y * wt.z * texels[(size_t(i.z) * edge + i.y) * edge + i.x] / 255.0;
  }
  return v;
}

}  // namespace

TEST_CASE("empty-space cells: the separable min/max equals the direct 3D loop bit for bit (u8, u16, f32 with NaN)") {
  std::mt19937 rng(7);
  for (const VkFormat format : {VK_FORMAT_R8_UNORM, VK_FORMAT_R16_UNORM, VK_FORMAT_R32_SFLOAT})
    for (const auto& [cs, apron] : {std::pair{16u, 1u}, std::pair{30u, 2u}, std::pair{61u, 1u}, std::pair{7u, 0u}}) {
      CAPTURE(format);
      CAPTURE(cs);
      const uint32_t edge = cs + 2 * apron, bytes = format == VK_FORMAT_R8_UNORM ? 1 : format == VK_FORMAT_R16_UNORM ? 2 : 4;
      const size_t n = size_t(edge) * edge * edge;
      std::vector<uint8_t> texels(n * bytes);
      // Sparse bright spots on a dim floor, so cells differ; floats get NaNs, infinities and -0.
      for (size_t i = 0; i < n; ++i) {
        const uint32_t r = rng();
        const bool spot = r % 97 == 0;
        if (bytes == 1) texels[i] = uint8_t(spot ? r >> 8 : r % 5);
        if (bytes == 2) {
          const uint16_t v = uint16_t(spot ? r >> 8 : r % 300);
          std::memcpy(&texels[2 * i], &v, 2);
        }
        if (bytes == 4) {
          float v = spot ? float(int32_t(r >> 4) - (1 << 27)) * 1e-3f : float(r % 1000) * 1e-4f;
          if (r % 389 == 0) v = NAN;
          if (r % 1543 == 0) v = r % 2 ? INFINITY : -0.0f;
          std::memcpy(&texels[4 * i], &v, 4);
        }
      }
      if (bytes == 4)  // one cell (the first) wholly NaN: the direct loop's (inf, -inf) padding
        for (uint32_t z = 0; z < std::min(edge, 10u); ++z)
          for (uint32_t y = 0; y < std::min(edge, 10u); ++y)
            for (uint32_t x = 0; x < std::min(edge, 10u); ++x) {
              const float v = NAN;
              std::memcpy(&texels[4 * ((size_t(z) * edge + y) * edge + x)], &v, 4);
            }
      const BrickCells cells = brick_cells_for(cs);
      std::vector<glm::vec2> got(cells.count());
      compute_cell_ranges(format, texels.data(), cs, apron, cells, got.data());
      const auto want = direct_cell_ranges(format, texels.data(), cs, apron, cells);
      REQUIRE(std::memcmp(got.data(), want.data(), got.size() * sizeof(glm::vec2)) == 0);
    }
}


TEST_CASE("empty-space cells: the grid sits half a voxel off the voxels, and ranges reach the core and the band's share of the ring") {
  // One R8 slot, chunk 16, apron 1: 18^3 texels, 3 cells of 8 voxels per
  // axis. Cell k covers local [8k - 0.5, 8k + 7.5): its samples filter voxels
  // 8k-1 .. 8k+7 (the core); within the band they reach one voxel further.
  const uint32_t cs = 16, apron = 1, edge = cs + 2 * apron;
  const BrickCells cells = brick_cells_for(cs, 8);
  REQUIRE(cells.cells_per_axis == 3);
  REQUIRE(cells.cell_size == 8);
  std::vector<uint8_t> texels(size_t(edge) * edge * edge, 10);
  auto at = [&](int x, int y, int z) -> uint8_t& {  // local voxel (apron at -1)
    return texels[(size_t(z + apron) * edge + (y + apron)) * edge + (x + apron)];
  };
  std::vector<glm::vec2> out(cells.count());
  auto cell = [&](int x, int y, int z) { return out[(size_t(z) * 3 + y) * 3 + x] * 255.0f; };
  const double w = 3.0 * VXR_CELL_BAND;
  at(8, 3, 3) = 200;   // core of cell (1,0,0); ring of cell (0,0,0)
  at(-1, 12, 12) = 0;  // apron voxel: core of cell (0,1,1)
  compute_cell_ranges(VK_FORMAT_R8_UNORM, texels.data(), cs, apron, cells, out.data());
  CHECK(cell(1, 0, 0).y >= 200.0f);
  CHECK(cell(0, 0, 0).y >= 10.0 + w * 190.0);
  CHECK(cell(0, 0, 0).y < 10.0 + w * 190.0 + 0.01);
  CHECK(cell(0, 1, 1).x <= 0.0f);
  CHECK(cell(1, 1, 1).x > 9.99f);
  CHECK(cell(1, 1, 1).y < 10.01f);
  CHECK(cell(1, 1, 1).y >= 10.0f);  // widened, never narrowed
  // Voxel 7 is in both cells' cores (samples on either side of its centre read it); voxel 0 in cell 0's only.
  at(8, 3, 3) = 10;
  at(7, 3, 3) = 250;
  compute_cell_ranges(VK_FORMAT_R8_UNORM, texels.data(), cs, apron, cells, out.data());
  CHECK(cell(0, 0, 0).y >= 250.0f);
  CHECK(cell(1, 0, 0).y >= 250.0f);
  at(7, 3, 3) = 10;
  at(0, 3, 3) = 250;
  compute_cell_ranges(VK_FORMAT_R8_UNORM, texels.data(), cs, apron, cells, out.data());
  CHECK(cell(0, 0, 0).y >= 250.0f);
  CHECK(cell(1, 0, 0).y < 10.01f);
}

TEST_CASE("empty-space cells: every trilinear sample inside a cell or within its band lies in the cell's range") {
  // Random bright spots on a dim floor; samples at random positions in each
  // cell grown by the band, filtered in double: none may leave its range.
  std::mt19937 rng(11);
  for (const auto& [cs, apron, cell_voxels] : {std::tuple{16u, 1u, 2u}, std::tuple{16u, 2u, 8u}, std::tuple{13u, 1u, 4u}}) {
    CAPTURE(cs);
    CAPTURE(cell_voxels);
    const uint32_t edge = cs + 2 * apron;
    std::vector<uint8_t> texels(size_t(edge) * edge * edge);
    for (uint8_t& t : texels) {
      const uint32_t r = rng();
      t = uint8_t(r % 13 == 0 ? r >> 24 : r % 5);
    }
    const BrickCells cells = brick_cells_for(cs, cell_voxels);
    std::vector<glm::vec2> out(cells.count());
    compute_cell_ranges(VK_FORMAT_R8_UNORM, texels.data(), cs, apron, cells, out.data());
    const uint32_t n = cells.cells_per_axis;
    const double s = cells.cell_size, band = VXR_CELL_BAND;
    std::uniform_real_distribution<double> u(-band, s + band);
    size_t outside = 0, tested = 0;
    for (uint32_t c = 0; c < cells.count(); ++c) {
      const glm::dvec3 lo = glm::dvec3(c % n, (c / n) % n, c / (n * n)) * s - 0.5;
      for (int i = 0; i < 64; ++i) {
        // Within the brick's samples: local [0, cs) on every axis.
        const glm::dvec3 p = glm::clamp(lo + glm::dvec3(u(rng), u(rng), u(rng)), 0.0, double(cs) - 1e-9);
        if (glm::any(glm::lessThan(p, lo - band)) || glm::any(glm::greaterThan(p, lo + s + band))) continue;
        const double v = trilinear(texels, edge, apron, p);
        ++tested;
        if (v < out[c].x || v > out[c].y) ++outside;
      }
    }
    CHECK(tested > 1000);
    CHECK(outside == 0);
  }
}

TEST_CASE("empty-space cells: bit-identical with a gamma and with a transfer function that has gaps") {
  // Gamma takes the pow path of the windowing; the opacity points make a
  // transparent band inside the window, so cells inside the vessels can be empty too.
  test::GpuTestScope scope;
  auto src = sparse_vessels(128);
  auto made = small_pool_renderer(*src);
  BrickRenderer& r = *made;
  const Camera cam = orbit_camera(r.placement(), 120, -30, 1.1);
  for (OpticalModel model : {OpticalModel::kEmissionAbsorption, OpticalModel::kMip}) {
    for (int variant = 0; variant < 2; ++variant) {
      RenderSettings s;
      s.model = model;
      s.channels[0].colormap = "viridis";
      s.channels[0].window_lo = 8;
      s.channels[0].window_hi = 200;
      if (variant == 0) s.channels[0].gamma = 0.6;
      if (variant == 1)
        s.channels[0].opacity_points = {{0.0, 0.0}, {0.3, 0.0}, {0.31, 0.8}, {0.6, 0.8}, {0.61, 0.0}, {1.0, 0.0}};
      s.step_voxels = 0.7;
      s.density = 0.5;
      BrickFrameSettings f;
      f.lod.force_level = 0;
      const std::string what = std::string(optical_model_name(model)) + (variant == 0 ? " gamma" : " band");
      INFO(what);
      check_skipping_keeps_image(r, cam, s, f, 80, 64);
    }
  }
}

TEST_CASE("empty-space cells: a cell whose range reaches one table entry into the opaque part is marched") {
  // A smooth ball (value falls linearly with the radius): every cell spans a
  // few table entries, so cells straddle the step of a threshold transfer
  // function at every distance from it. Skipping one that reaches a single
  // opaque entry would drop samples of opacity 1: the images would differ.
  test::GpuTestScope scope;
  auto src = DenseChunkSource::create({linear_ball()}, 32, 2);
  REQUIRE(src.is_ok());
  auto made = BrickRenderer::create(test::gpu_context(), **src, {});
  REQUIRE(made.is_ok());
  BrickRenderer& r = **made;
  const Camera cam = orbit_camera(r.placement(), 30, 25, 1.3);
  for (double threshold : {0.2, 0.5, 0.73}) {
    RenderSettings s;
    s.channels[0].colormap = "magma";
    s.channels[0].window_lo = 0;
    s.channels[0].window_hi = 255;
    s.channels[0].opacity_points = {{0.0, 0.0}, {threshold, 0.0}, {threshold + 0.002, 1.0}, {1.0, 1.0}};
    s.step_voxels = 0.5;
    s.density = 0.4;
    BrickFrameSettings f;
    BrickFrameStats on, off;
    const ImageRgba8 a = converge(r, cam, s, f, 72, 72, &on);
    f.lod.skip_empty = false;
    const ImageRgba8 b = converge(r, cam, s, f, 72, 72, &off);
    const std::string what = "threshold " + std::to_string(threshold) + ": samples " + std::to_string(on.samples) +
                             " vs " + std::to_string(off.samples);
    INFO(what);
    CHECK(test::looks_non_blank(a));
    CHECK(a.pixels == b.pixels);
    CHECK(on.samples < off.samples);
  }
}

TEST_CASE("empty-space cells: a brick that keeps every cell is marched without a walk, with the same image") {
  // The ball in 16-voxel bricks: the eight around the centre hold values
  // of at least 27 / 255, the outer ones reach the empty corners.
  test::GpuTestScope scope;
  auto src = DenseChunkSource::create({linear_ball()}, 16, 2);
  REQUIRE(src.is_ok());
  auto made = BrickRenderer::create(test::gpu_context(), **src, {});
  REQUIRE(made.is_ok());
  BrickRenderer& r = **made;
  const Camera cam = orbit_camera(r.placement(), 30, 25, 1.3);
  struct Case {
    const char* what;
    OpticalModel model;
    std::vector<OpacityPoint> opacity;
    int walked;  // -1: some bricks but not all; else how many
  };
  const Case cases[] = {
      {"every voxel visible: no brick walks", OpticalModel::kEmissionAbsorption, {{0.0, 0.1}, {1.0, 1.0}}, 0},
      {"visible from 0.05: the outer bricks walk", OpticalModel::kEmissionAbsorption,
       {{0.0, 0.0}, {0.05, 0.0}, {0.06, 1.0}, {1.0, 1.0}}, -1},
      {"MIP: every brick walks", OpticalModel::kMip, {{0.0, 0.1}, {1.0, 1.0}}, 64},
      {"MIP at a step over an eighth of a cell (4-voxel cells, step 1): no cell walk at all", OpticalModel::kMip, {{0.0, 0.1}, {1.0, 1.0}}, 0},
  };
  for (const Case& c : cases) {
    RenderSettings s;
    s.model = c.model;
    s.channels[0].colormap = "magma";
    s.channels[0].window_lo = 0;
    s.channels[0].window_hi = 255;
    s.channels[0].opacity_points = c.opacity;
    s.step_voxels = &c == &cases[3] ? 1.0 : 0.5;
    s.density = 0.05;
    BrickFrameSettings f;
    f.lod.force_level = 0;
    BrickFrameStats on, off;
    const ImageRgba8 a = converge(r, cam, s, f, 72, 72, &on);
    f.lod.skip_empty = false;
    const ImageRgba8 b = converge(r, cam, s, f, 72, 72, &off);
    INFO(std::string(c.what) << ": walked " << on.bricks_walked << " of " << on.lod.drawn << ", samples "
                             << on.samples << " vs " << off.samples);
    REQUIRE(on.lod.drawn == 64);
    CHECK(test::looks_non_blank(a));
    CHECK(a.pixels == b.pixels);
    CHECK(off.bricks_walked == 0);
    if (c.walked >= 0) {
      CHECK(on.bricks_walked == uint32_t(c.walked));
    } else {
      CHECK(on.bricks_walked > 0);
      CHECK(on.bricks_walked < on.lod.drawn);
      CHECK(on.samples < off.samples);
    }
    if (c.walked == 0) CHECK(on.samples == off.samples);
    MESSAGE(std::string(c.what) << ": walked " << on.bricks_walked << " of " << on.lod.drawn);
  }
}

TEST_CASE("empty-space cells: bricks seen from kCellEyeLimit voxels away or more march without cells, with the same image") {
  // Float positions that far from the eye are too coarse for the cells'
  // band: such bricks march their whole box. Near the limit they still walk.
  test::GpuTestScope scope;
  auto src = sparse_vessels(64);
  auto made = small_pool_renderer(*src);
  BrickRenderer& r = *made;
  const double diag = glm::length(r.placement().extent());
  BrickFrameSettings f;
  f.lod.force_level = 0;
  const RenderSettings s = vessel_settings(OpticalModel::kEmissionAbsorption);
  for (const double eye_voxels : {0.5 * BrickRenderer::kCellEyeLimit, 2.0 * BrickRenderer::kCellEyeLimit}) {
    // The volume fills about half the view at that distance.
    const double fov = glm::degrees(2.0 * std::atan(diag / eye_voxels));
    const Camera cam = orbit_camera(r.placement(), 30, 25, eye_voxels / diag, fov);
    BrickFrameStats on, off;
    const ImageRgba8 a = converge(r, cam, s, f, 64, 64, &on);
    f.lod.skip_empty = false;
    const ImageRgba8 b = converge(r, cam, s, f, 64, 64, &off);
    f.lod.skip_empty = true;
    INFO("eye " << eye_voxels << " voxels away: walked " << on.bricks_walked << " of " << on.lod.drawn);
    CHECK(test::looks_non_blank(a));
    CHECK(a.pixels == b.pixels);
    if (eye_voxels < BrickRenderer::kCellEyeLimit) {
      CHECK(on.bricks_walked > 0);
      CHECK(on.samples < off.samples);
    } else {
      CHECK(on.bricks_walked == 0);  // (empty bricks are still dropped whole: their test holds at any distance)
    }
  }
}

TEST_CASE("empty-space cells: images with skipping on and off are bit-identical for every model that skips") {
  test::GpuTestScope scope;
  auto src = sparse_vessels(128);
  auto made = small_pool_renderer(*src);
  BrickRenderer& r = *made;
  const Camera cam = orbit_camera(r.placement(), 30, 25, 1.25);
  const OpticalModel models[] = {OpticalModel::kEmissionAbsorption, OpticalModel::kEmission, OpticalModel::kMip,
                                 OpticalModel::kMinIp, OpticalModel::kAverage, OpticalModel::kIsosurface};
  const BrickPassMode modes[] = {BrickPassMode::kMultipass, BrickPassMode::kTiled};
  for (OpticalModel model : models) {
    for (BrickPassMode mode : modes) {
      const RenderSettings s = vessel_settings(model);
      BrickFrameSettings f;
      f.lod.force_level = 0;
      f.mode = mode;
      BrickFrameStats cells_on, bricks_only, none;
      const ImageRgba8 a = converge(r, cam, s, f, 96, 96, &cells_on);
      f.skip_cells = false;
      const ImageRgba8 b = converge(r, cam, s, f, 96, 96, &bricks_only);
      f.lod.skip_empty = false;
      const ImageRgba8 c = converge(r, cam, s, f, 96, 96, &none);
      const std::string what = std::string(optical_model_name(model)) +
                               (mode == BrickPassMode::kTiled ? " tiled" : " multipass") + ": samples cells " +
                               std::to_string(cells_on.samples) + ", bricks only " +
                               std::to_string(bricks_only.samples) + ", none " + std::to_string(none.samples);
      INFO(what);
      if (model != OpticalModel::kMinIp) CHECK(test::looks_non_blank(a));
      CHECK(a.pixels == b.pixels);
      CHECK(a.pixels == c.pixels);
      // MinIP over this window walks no cell (its rays could skip too few:
      // the test "one-channel MinIP walks its cells only where ..." has both sides).
      if (model == OpticalModel::kMinIp) CHECK(cells_on.samples == bricks_only.samples);
      else CHECK(cells_on.samples < bricks_only.samples);
      CHECK(bricks_only.samples <= none.samples);
      MESSAGE(what);
    }
  }
}

TEST_CASE("empty-space cells: the cell walk keeps the image for rays along the axes and from inside the volume") {
  test::GpuTestScope scope;
  auto src = sparse_vessels(128);
  auto made = small_pool_renderer(*src);
  BrickRenderer& r = *made;
  // 97x97: the middle row and column have a zero direction component, the
  // centre pixel two (the walk's exits along those axes are infinite).
  struct View {
    const char* what;
    Camera cam;
  };
  const View views[] = {{"along x", orbit_camera(r.placement(), 0, 0)},
                        {"along y", orbit_camera(r.placement(), 90, 0)},
                        {"eye inside", orbit_camera(r.placement(), 20, 10, 0.2)}};
  for (const View& v : views) {
    for (OpticalModel model : {OpticalModel::kEmissionAbsorption, OpticalModel::kMip, OpticalModel::kAverage,
                               OpticalModel::kIsosurface}) {
      const std::string what = std::string(v.what) + " " + optical_model_name(model);
      INFO(what);
      const RenderSettings s = vessel_settings(model);
      BrickFrameSettings f;
      f.lod.force_level = 0;
      f.mode = BrickPassMode::kTiled;
      check_skipping_keeps_image(r, v.cam, s, f, 97, 97);
    }
  }
}

TEST_CASE("empty-space cells: tile lists clipped to the depths of each brick's kept blocks keep the image") {
  // The tiled lists carry, per tile, the view depths where its rays can
  // meet a walked brick's blocks of kept cells, and leave the brick off
  // tiles whose rays meet none (build_tile_lists). Against the same renderer without them: the same
  // bytes, from fewer tile entries, for views from outside, along an axis,
  // from inside (blocks reaching behind the eye), with an ROI and a cut.
  test::GpuTestScope scope;
  auto src = sparse_vessels(128);
  BrickRendererOptions plain;
  plain.tile_depths = false;
  auto clipped = small_pool_renderer(*src);
  auto whole = small_pool_renderer(*src, plain);
  constexpr uint32_t kFewBlocks = 40;
  BrickRendererOptions few_blocks;
  few_blocks.max_tile_blocks = kFewBlocks;
  auto budgeted = small_pool_renderer(*src, few_blocks);
  for (const ClipView& v : clip_views(clipped->placement())) {
    for (OpticalModel model : {OpticalModel::kEmissionAbsorption, OpticalModel::kMip}) {
      const RenderSettings s = vessel_settings(model);
      const BrickFrameSettings f = v.frame();
      BrickFrameStats on, off, few;
      const ImageRgba8 a = converge(*clipped, v.cam, s, f, 97, 97, &on);
      const ImageRgba8 b = converge(*whole, v.cam, s, f, 97, 97, &off);
      // Past a view's block budget the bricks march their whole box: still the same image.
      const ImageRgba8 c = converge(*budgeted, v.cam, s, f, 97, 97, &few);
      const std::string what = std::string(v.what) + " " + optical_model_name(model) + ": tile entries " +
                               std::to_string(on.tile_entries) + " (" + std::to_string(on.tile_blocks) +
                               " blocks) vs " + std::to_string(off.tile_entries) + ", samples " +
                               std::to_string(on.samples) + " vs " + std::to_string(off.samples) +
                               "; budget of " + std::to_string(kFewBlocks) + ": " +
                               std::to_string(few.tile_entries) + " from " + std::to_string(few.tile_blocks);
      INFO(what);
      CHECK(test::looks_non_blank(a));
      CHECK(a.pixels == b.pixels);
      CHECK(on.tile_blocks > 0);
      CHECK(off.tile_blocks == 0);
      CHECK(on.tile_entries < off.tile_entries);
      CHECK(c.pixels == b.pixels);
      CHECK(few.tile_blocks > 0);
      CHECK(few.tile_blocks <= kFewBlocks);
      CHECK(few.tile_entries >= on.tile_entries);
      // (Samples are not compared: a walk that starts at the clipped depth
      // can end its runs a few samples elsewhere, and MIP's runs then take a
      // handful more; the image must not change.)
      MESSAGE(what);
    }
  }
}

TEST_CASE("empty-space cells: tiled E-A and emission frames dispatch only the 4x2 blocks some entry reaches: same image") {
  // Where a subgroup is 8 invocations (lavapipe at 256 bits), the tiles with a
  // walked brick go out as the 4x2 pixel blocks whose rays can meet a
  // brick's kept blocks; the others keep the clear, which is what their
  // rays, meeting only empty cells, would finish as (build_tile_lists,
  // BrickRendererOptions::group_lists). Against whole tiles: the same bytes,
  // 8-bit and float targets, in each of clip_views. MIP keeps whole tiles
  // (an empty MIP ray finishes otherwise than one that sampled zeros).
  test::GpuTestScope scope;
  auto src = sparse_vessels(128);
  BrickRendererOptions tiles_only;
  tiles_only.group_lists = false;
  auto by_groups = small_pool_renderer(*src);
  auto whole = small_pool_renderer(*src, tiles_only);
  const bool eight_wide = test::gpu_context().info().subgroup_size == 8;
  constexpr uint32_t kSide = 97;  // tiles and blocks cut by the image's edges
  constexpr uint32_t kTiles = (kSide + 7) / 8 * ((kSide + 7) / 8);
  for (const ClipView& v : clip_views(by_groups->placement())) {
    for (OpticalModel model : {OpticalModel::kEmissionAbsorption, OpticalModel::kEmission, OpticalModel::kMip,
                               OpticalModel::kIsosurface}) {
      const RenderSettings s = vessel_settings(model);
      const BrickFrameSettings f = v.frame();
      BrickFrameStats on, off;
      const ImageRgba8 a = converge(*by_groups, v.cam, s, f, kSide, kSide, &on);
      const ImageRgba8 b = converge(*whole, v.cam, s, f, kSide, kSide, &off);
      const uint32_t marched = kTiles - on.tiles_empty - on.tiles_plain;
      const std::string what = std::string(v.what) + " " + optical_model_name(model) + ": blocks " +
                               std::to_string(on.groups_marched) + " of " + std::to_string(8 * marched) + " on " +
                               std::to_string(marched) + " marched tiles; samples " + std::to_string(on.samples) +
                               " vs " + std::to_string(off.samples);
      INFO(what);
      CHECK(test::looks_non_blank(a));
      CHECK(a.pixels == b.pixels);
      // A block left out takes no sample that shows: the same samples or
      // fewer (where the rays walk 2x2x2 cells, one of them may hold a kept
      // cell that the block's rays never meet).
      CHECK(on.samples <= off.samples);
      CHECK(off.groups_marched == 0);
      if (eight_wide && model != OpticalModel::kMip) {
        CHECK(on.groups_marched > 0);
        CHECK(on.groups_marched < 8 * marched);
      } else {
        CHECK(on.groups_marched == 0);
      }
      // Float pixels: the accumulation image, cleared the same way, then a blit.
      auto fa = by_groups->render_float(v.cam, s, f, kSide, kSide);
      auto fb = whole->render_float(v.cam, s, f, kSide, kSide);
      REQUIRE(fa.is_ok());
      REQUIRE(fb.is_ok());
      CHECK(fa->rgba == fb->rgba);
      MESSAGE(what);
    }
  }
}

TEST_CASE("empty-space cells: isosurface frames skip what lies below the iso value, with the same image, up to kIsoBackStep") {
  // A crossing is refined against the sample one step back, read again in
  // the crossing's brick, so it does not matter whether the ray marched or
  // skipped the space before it: bricks and cells whose iso channel stays
  // below the iso value are skipped. From outside, along an axis, from
  // inside, with an ROI and with a cut (the sample back must lie inside all
  // of them, as in the CPU reference), both pass modes. Past kIsoBackStep the
  // apron no longer holds the sample back: nothing is skipped.
  test::GpuTestScope scope;
  auto src = sparse_vessels(128);
  auto made = small_pool_renderer(*src);
  BrickRenderer& r = *made;
  for (double step : {0.5, kIsoBackStep}) {
    RenderSettings s = vessel_settings(OpticalModel::kIsosurface);
    s.step_voxels = step;
    INFO("step " << step);
    check_clip_views_keep_image(r, s);
  }
  // Past the step the apron holds: the same image and every sample taken.
  RenderSettings s = vessel_settings(OpticalModel::kIsosurface);
  s.step_voxels = 2.0;
  const ClipView v = clip_views(r.placement())[0];
  BrickFrameSettings f = v.frame();
  BrickFrameStats on, off;
  const ImageRgba8 a = converge(r, v.cam, s, f, 97, 97, &on);
  f.lod.skip_empty = false;
  const ImageRgba8 b = converge(r, v.cam, s, f, 97, 97, &off);
  CHECK(test::looks_non_blank(a));
  CHECK(a.pixels == b.pixels);
  CHECK(on.samples == off.samples);
  CHECK(on.lod.skipped_empty == 0);
}

TEST_CASE("empty-space cells: average frames skip what windows to 0, their length taken from the ray's chord") {
  // An average is the windowed values' sum over the length marched. A
  // sample that windows to 0 adds nothing to the sum, and the rays take the
  // length from their chord through the volume (region_chord), not from
  // what they march, so cells and bricks whose samples all window to 0 are
  // skipped. Where the table's entry 0 is transparent, like any model's;
  // where it is opaque, a ray that takes nothing still shows it, so the
  // bricks stay listed whole and only their cells are skipped. Views from
  // outside, along an axis, from inside, with an ROI and a cut, both pass
  // modes, and a frame that mixes LOD levels.
  test::GpuTestScope scope;
  auto src = sparse_vessels(128);
  auto made = small_pool_renderer(*src);
  BrickRenderer& r = *made;
  check_clip_views_keep_image(r, vessel_settings(OpticalModel::kAverage));
  RenderSettings zero_shows = vessel_settings(OpticalModel::kAverage);
  zero_shows.channels[0].opacity_points = {{0.0, 1.0}, {1.0, 1.0}};
  {
    INFO("entry 0 opaque");
    check_clip_views_keep_image(r, zero_shows);
  }
  // Which bricks each kind skips, from the orbit view.
  const ClipView orbit = clip_views(r.placement())[0];
  BrickFrameStats transparent_zero, opaque_zero;
  converge(r, orbit.cam, vessel_settings(OpticalModel::kAverage), orbit.frame(), 97, 97, &transparent_zero);
  converge(r, orbit.cam, zero_shows, orbit.frame(), 97, 97, &opaque_zero);
  CHECK(transparent_zero.lod.skipped_empty > 0);
  CHECK(opaque_zero.lod.skipped_empty == 0);
  CHECK(transparent_zero.samples < opaque_zero.samples);
  // The same view with the automatic LOD: near bricks at level 0, far ones at level 1.
  BrickFrameSettings mixed = orbit.frame();
  mixed.lod.force_level = -1;
  const VoxelSpaceRays rays = rays_in_voxel_space(orbit.cam, r.placement(), 97, 97);
  LodQueries all;
  all.visible = [](const ChunkKey&) { return true; };
  all.resident = [](const ChunkKey&) { return true; };
  std::set<uint32_t> levels;
  for (const ChunkKey& k : traverse_lod(*src, {rays.eye, rays.forward, rays.right, rays.up, 97, 97}, mixed.lod, all).draw)
    levels.insert(k.level);
  CHECK(levels.size() > 1);
  INFO("levels mixed");
  check_skipping_keeps_image(r, orbit.cam, vessel_settings(OpticalModel::kAverage), mixed, 97, 97);

  // The ball's corners are 0 exactly: skipped under a window from 0, kept
  // under one from below 0 (0 then windows above 0), with the same image.
  auto ball = DenseChunkSource::create({linear_ball()}, 16, 2);
  REQUIRE(ball.is_ok());
  auto ball_made = BrickRenderer::create(test::gpu_context(), **ball, {});
  REQUIRE(ball_made.is_ok());
  const Camera cam = orbit_camera((*ball_made)->placement(), 30, 25, 1.3);
  for (double lo : {0.0, -10.0}) {
    RenderSettings s;
    s.model = OpticalModel::kAverage;
    s.channels[0].window_lo = lo;
    s.channels[0].window_hi = 255;
    s.step_voxels = 0.5;
    BrickFrameSettings f;
    f.lod.force_level = 0;
    BrickFrameStats on, off;
    const ImageRgba8 a = converge(**ball_made, cam, s, f, 72, 72, &on);
    f.lod.skip_empty = false;
    const ImageRgba8 b = converge(**ball_made, cam, s, f, 72, 72, &off);
    INFO("window from " << lo << ": samples " << on.samples << " vs " << off.samples << ", walked " << on.bricks_walked << " of " << on.lod.drawn);
    CHECK(test::looks_non_blank(a));
    CHECK(a.pixels == b.pixels);
    if (lo == 0.0) CHECK(on.samples < off.samples);
    else CHECK(on.samples == off.samples);
  }
}

TEST_CASE("empty-space cells: one-channel MinIP walks its cells only where rays can skip them, with the same image") {
  // Over the vessels' background noise (0..6) with the window from 0, no
  // ray's running minimum reaches a cell's minimum: walking would cost
  // every cell and skip none, so the rays march without a walk. With the
  // window from 8 the background is the floor (windowed 0): a ray that
  // crosses it can skip every later cell, and the rays walk.
  test::GpuTestScope scope;
  auto src = sparse_vessels(128);
  auto made = small_pool_renderer(*src);
  BrickRenderer& r = *made;
  const Camera cam = orbit_camera(r.placement(), 30, 25, 1.25);
  for (double lo : {0.0, 8.0}) {
    RenderSettings s = vessel_settings(OpticalModel::kMinIp);
    s.channels[0].window_lo = lo;
    BrickFrameSettings f;
    f.lod.force_level = 0;
    BrickFrameStats on, off;
    const ImageRgba8 a = converge(r, cam, s, f, 96, 96, &on);
    f.lod.skip_empty = false;
    const ImageRgba8 b = converge(r, cam, s, f, 96, 96, &off);
    INFO("window from " << lo << ": walked " << on.bricks_walked << " of " << on.lod.drawn << ", samples " << on.samples
                        << " vs " << off.samples);
    CHECK(a.pixels == b.pixels);
    if (lo == 0.0) {
      CHECK(on.bricks_walked == 0);
      CHECK(on.samples == off.samples);
    } else {
      CHECK(on.bricks_walked > 0);
      CHECK(on.samples < off.samples / 4);
    }
  }
}

TEST_CASE("empty-space cells: the iso rule for a brick's range: skipped only clearly below the iso value, and only up to kIsoBackStep") {
  RenderSettings s;
  s.model = OpticalModel::kIsosurface;
  s.channels[0].window_lo = 0;
  s.channels[0].window_hi = 200;
  s.iso_value = 100;
  s.step_voxels = 1.0;
  const TransferTable t = build_transfer_table(s);
  CHECK(iso_back_sample(s));
  CHECK_FALSE(brick_may_contribute(s, t, 0.0, 99.0));
  CHECK(brick_may_contribute(s, t, 0.0, 100.0));   // a sample at the iso value crosses
  CHECK(brick_may_contribute(s, t, 0.0, 99.999));  // within rounding of it: kept
  CHECK(brick_may_contribute(s, t, 120.0, 250.0));
  // A gamma moves the iso value with the values: still below is below.
  s.channels[0].gamma = 2.0;
  CHECK_FALSE(brick_may_contribute(s, t, 0.0, 99.0));
  CHECK(brick_may_contribute(s, t, 0.0, 101.0));
  // An iso value at or below the window's low end: every sample crosses.
  s.channels[0].gamma = 1.0;
  s.iso_value = -5;
  CHECK(brick_may_contribute(s, t, 0.0, 0.0));
  // Past kIsoBackStep: never skipped.
  s.iso_value = 100;
  s.step_voxels = 2.0;
  CHECK_FALSE(iso_back_sample(s));
  CHECK(brick_may_contribute(s, t, 0.0, 10.0));
}

TEST_CASE("empty-space cells: a pool uses 2-voxel cells where the slots its source can fill allow, else 4") {
  test::GpuTestScope scope;
  BrickPoolOptions o;
  o.slots = {8, 8, 8};
  // 128^3 in 32^3 chunks: 64 + 8 + 1 bricks, 73 slots of ranges at 2 voxels (17^3 cells each).
  auto small = sparse_vessels(128);
  auto a = BrickPool::create(test::gpu_context(), *small, o);
  REQUIRE(a.is_ok());
  CHECK((*a)->cells().cell_size == 2);
  CHECK((*a)->cells().cells_per_axis == 17);
  CHECK((*a)->cell_ranges().size == 73ull * 17 * 17 * 17 * sizeof(glm::vec2));
  // 1024^3 in 64^3 chunks: more bricks than the 512 slots, whose 2-voxel ranges
  // (512 * 33^3 cells) would pass kMaxCellRangeBytes; 4-voxel ones do not.
  ProceduralOptions po;
  po.dims = {1024, 1024, 1024};
  po.chunk_size = 64;
  auto big_src = ProceduralSource::create(po);
  REQUIRE(big_src.is_ok());
  auto b = BrickPool::create(test::gpu_context(), **big_src, o);
  REQUIRE(b.is_ok());
  CHECK((*b)->cells().cell_size == 4);
  CHECK((*b)->cell_ranges().size == 512ull * 17 * 17 * 17 * sizeof(glm::vec2));
}

namespace {

// The vessels (E-A and emission, multipass and tiled) drawn by two renderers
// made with `first` and `second`, and by the second with skipping off.
struct VariantFrames {
  std::string what;
  ImageRgba8 a, b, off;
  uint64_t a_samples = 0, b_samples = 0, off_samples = 0;
};
std::vector<VariantFrames> vessel_variants(BrickRendererOptions first, BrickRendererOptions second,
                                           std::vector<OpticalModel> models = {OpticalModel::kEmissionAbsorption,
                                                                               OpticalModel::kEmission}) {
  auto src = sparse_vessels(128);
  first.pool.slots = second.pool.slots = {8, 8, 8};
  first.pipelines = second.pipelines = std::make_shared<BrickPipelines>();
  auto ra = BrickRenderer::create(test::gpu_context(), *src, first);
  auto rb = BrickRenderer::create(test::gpu_context(), *src, second);
  REQUIRE(ra.is_ok());
  REQUIRE(rb.is_ok());
  REQUIRE((*ra)->pool().cells().cell_size == 2);
  const Camera cam = orbit_camera((*ra)->placement(), 30, 25, 1.25);
  std::vector<VariantFrames> out;
  for (OpticalModel model : models) {
    for (BrickPassMode mode : {BrickPassMode::kMultipass, BrickPassMode::kTiled}) {
      const RenderSettings s = vessel_settings(model);
      BrickFrameSettings f;
      f.lod.force_level = 0;
      f.mode = mode;
      VariantFrames v;
      v.what = std::string(optical_model_name(model)) + (mode == BrickPassMode::kTiled ? " tiled" : " multipass");
      BrickFrameStats st;
      v.a = converge(**ra, cam, s, f, 96, 96, &st);
      v.a_samples = st.samples;
      v.b = converge(**rb, cam, s, f, 96, 96, &st);
      v.b_samples = st.samples;
      f.lod.skip_empty = false;
      v.off = converge(**rb, cam, s, f, 96, 96, &st);
      v.off_samples = st.samples;
      out.push_back(std::move(v));
    }
  }
  return out;
}

}  // namespace

TEST_CASE("empty-space cells: walking 2-voxel cells or 2x2x2 groups of them gives the image without skipping") {
  test::GpuTestScope scope;
  BrickRendererOptions cells, groups;
  cells.cell_walk = BrickCellWalk::kCells;
  groups.cell_walk = BrickCellWalk::kGroups;
  for (const VariantFrames& v : vessel_variants(cells, groups)) {
    INFO(v.what);
    CHECK(test::looks_non_blank(v.a));
    CHECK(v.a.pixels == v.off.pixels);
    CHECK(v.b.pixels == v.off.pixels);
    // Finer cells skip more.
    CHECK(v.a_samples < v.b_samples);
    CHECK(v.b_samples < v.off_samples);
  }
}

TEST_CASE("empty-space cells: the cell bits, keys, brick records and work list read through their uniform windows or texels and the storage buffers agree") {
  test::GpuTestScope scope;
  BrickRendererOptions uniform, storage;
  storage.uniform_cell_bits = false;
  storage.texel_brick_records = false;
  storage.texel_cell_keys = false;
  for (const VariantFrames& v : vessel_variants(
           uniform, storage, {OpticalModel::kEmissionAbsorption, OpticalModel::kEmission, OpticalModel::kMip})) {
    INFO(v.what);
    CHECK(test::looks_non_blank(v.a));
    CHECK(v.a.pixels == v.b.pixels);
    CHECK(v.a.pixels == v.off.pixels);
    // The same cells jumped either way, and some were.
    CHECK(v.a_samples == v.b_samples);
    CHECK(v.a_samples < v.off_samples);
  }
}

TEST_CASE("empty-space cells: the classification is kept while its inputs stay, and redone when any changes") {
  test::GpuTestScope scope;
  auto src = sparse_vessels(128);
  BrickRendererOptions ro;
  ro.pipelines = std::make_shared<BrickPipelines>();
  auto made = small_pool_renderer(*src, ro);
  BrickRenderer& r = *made;
  BrickFrameSettings f;
  f.lod.force_level = 0;
  f.mode = BrickPassMode::kTiled;
  const Camera near_cam = orbit_camera(r.placement(), 30, 25, 1.25);
  // Each step changes one input of the cells' bits. A stale classification
  // jumps other cells than a fresh one: a renderer that has drawn nothing
  // else must take the same samples and give the same pixels.
  RenderSettings wide = vessel_settings(OpticalModel::kEmissionAbsorption);
  RenderSettings narrow = wide;
  narrow.channels[0].window_lo = 120;  // fewer voxels above the window: more cells empty
  RenderSettings ramp = wide;
  ramp.channels[0].opacity_points = {{0.0, 0.0}, {0.5, 0.0}, {1.0, 1.0}};  // the low half transparent
  // The same bricks drawn (every vessel brick reaches above both); the
  // transparent values end at 99 instead of 104: only the window changes.
  RenderSettings ramp_low = ramp;
  ramp_low.channels[0].window_hi = 190;
  RenderSettings ramp_shifted = ramp_low;  // the same again, the table alone changes: transparent to 103
  ramp_shifted.channels[0].opacity_points[1].x = 0.52;
  struct Step {
    const char* what;
    RenderSettings s;
    Camera cam;
    bool same_bricks = false;  // as the step before: only the cells can change
  };
  RenderSettings mip = wide;
  mip.model = OpticalModel::kMip;
  RenderSettings iso = vessel_settings(OpticalModel::kIsosurface);
  RenderSettings iso_higher = iso;  // the iso value alone changes, the same bricks drawn: more cells below it
  iso_higher.iso_value = 104;
  const Step steps[] = {{"narrow window", narrow, near_cam},
                        {"wide window", wide, near_cam},
                        {"opacity ramp", ramp, near_cam},
                        {"ramp, lower window top", ramp_low, near_cam, true},
                        {"ramp shifted", ramp_shifted, near_cam, true},
                        {"other camera", ramp_low, orbit_camera(r.placement(), 120, -10, 1.1)},
                        {"mip", mip, near_cam},
                        {"ea after mip", wide, near_cam},
                        {"iso", iso, near_cam},
                        {"iso value higher", iso_higher, near_cam, true}};
  uint64_t drawn_before = 0;
  for (const Step& step : steps) {
    INFO(std::string(step.what));
    auto fresh = small_pool_renderer(*src, ro);
    BrickFrameStats first, again, first_fresh, off;
    f.lod.skip_empty = true;
    const ImageRgba8 a = converge(r, step.cam, step.s, f, 96, 96, &first);
    const ImageRgba8 b = converge(r, step.cam, step.s, f, 96, 96, &again);
    const ImageRgba8 c = converge(*fresh, step.cam, step.s, f, 96, 96, &first_fresh);
    f.lod.skip_empty = false;
    const ImageRgba8 d = converge(r, step.cam, step.s, f, 96, 96, &off);
    CHECK(test::looks_non_blank(a));
    CHECK(a.pixels == c.pixels);
    CHECK(b.pixels == c.pixels);
    CHECK(a.pixels == d.pixels);
    CHECK(first.samples == first_fresh.samples);
    CHECK(again.samples == first_fresh.samples);
    CHECK(first.samples < off.samples);
    // The first frame classified, the repeated one marched only.
    CHECK(first.classify_passes == 1);
    CHECK(again.classify_passes == 0);
    CHECK(again.dispatches == first.dispatches - 1);
    if (step.same_bricks) CHECK(first.lod.drawn == drawn_before);
    drawn_before = first.lod.drawn;
  }
}

TEST_CASE("empty-space cells: the CPU cell test keeps every cell that can reach an opaque table entry") {
  // A ramp from the window's low end (VTK's usual opacity), u8 texels: a cell
  // below the window reaches entry 0 only (transparent); one whose top
  // reaches into the window is kept. A transparent band inside the window
  // drops cells within it, but not one reaching one entry past its edge.
  RenderSettings s;
  s.channels[0].window_lo = 75;
  s.channels[0].window_hi = 200;
  s.channels[0].opacity_points = {{0.0, 0.0}, {1.0, 1.0}};
  const std::vector<double> u8{255.0};
  const CellOpacity ramp(s, build_transfer_table(s), u8);
  auto texel = [](double v) { return float(v / 255.0); };
  CHECK_FALSE(ramp.may_contribute(0, {texel(0), texel(74)}));
  CHECK(ramp.may_contribute(0, {texel(0), texel(76)}));
  CHECK(ramp.may_contribute(0, {texel(180), texel(255)}));

  s.channels[0].window_lo = 0;
  s.channels[0].window_hi = 255;
  s.channels[0].opacity_points = {{0.0, 1.0}, {0.4, 1.0}, {0.4001, 0.0}, {0.6, 0.0}, {0.6001, 1.0}, {1.0, 1.0}};
  const CellOpacity band(s, build_transfer_table(s), u8);
  CHECK_FALSE(band.may_contribute(0, {texel(110), texel(145)}));
  CHECK(band.may_contribute(0, {texel(110), texel(160)}));  // reaches past the band's top
  CHECK(band.may_contribute(0, {texel(101), texel(145)}));  // and past its bottom
  CHECK(band.hash() != ramp.hash());
  CHECK(band.hash() == CellOpacity(s, build_transfer_table(s), u8).hash());

  s.channels[0].enabled = false;
  const CellOpacity off(s, build_transfer_table(s), u8);
  CHECK_FALSE(off.may_contribute(0, {texel(0), texel(255)}));

  // MIP: a cell below the window never raises a maximum (entry 0 transparent);
  // one that reaches the window's low end may. MinIP: the mirror image.
  s.channels[0].enabled = true;
  s.channels[0].window_lo = 75;
  s.channels[0].window_hi = 200;
  s.channels[0].opacity_points = {{0.0, 0.0}, {1.0, 1.0}};
  s.model = OpticalModel::kMip;
  const CellOpacity mip(s, build_transfer_table(s), u8);
  CHECK_FALSE(mip.may_contribute(0, {texel(0), texel(74)}));
  CHECK(mip.may_contribute(0, {texel(0), texel(75)}));
  CHECK(mip.hash() != ramp.hash());
  s.model = OpticalModel::kMinIp;
  s.channels[0].opacity_points = {{0.0, 1.0}, {1.0, 0.0}};
  const CellOpacity minip(s, build_transfer_table(s), u8);
  CHECK_FALSE(minip.may_contribute(0, {texel(201), texel(255)}));
  CHECK(minip.may_contribute(0, {texel(200), texel(255)}));
  // Average: a cell adds nothing only where every sample windows to 0 exactly:
  // clearly below the window's low end, or nothing above 0 under a window from 0 up.
  s.model = OpticalModel::kAverage;
  const CellOpacity average(s, build_transfer_table(s), u8);
  CHECK(average.may_contribute(0, {texel(201), texel(255)}));
  CHECK_FALSE(average.may_contribute(0, {texel(0), texel(74)}));
  CHECK(average.may_contribute(0, {texel(0), texel(75)}));  // at the low end: within a filter's rounding
  CHECK(average.hash() != minip.hash());
  s.channels[0].window_lo = 0;
  CHECK_FALSE(CellOpacity(s, build_transfer_table(s), u8).may_contribute(0, {texel(0), texel(0)}));
  CHECK(CellOpacity(s, build_transfer_table(s), u8).may_contribute(0, {texel(0), texel(1)}));
  s.channels[0].window_lo = -10;  // 0 windows above 0
  CHECK(CellOpacity(s, build_transfer_table(s), u8).may_contribute(0, {texel(0), texel(0)}));
  s.channels[0].enabled = false;  // the rays see a channel not drawn as 0
  CHECK_FALSE(CellOpacity(s, build_transfer_table(s), u8).may_contribute(0, {texel(0), texel(255)}));
}

TEST_CASE("bench probes: fetch-only and march-only frames take the shaded frame's samples, in both pass modes") {
  // `vxr bench roofline` splits a frame's time with them; the split is only
  // meaningful if the probes march the frame's rays, bricks and walks.
  test::GpuTestScope scope;
  auto src = sparse_vessels(128);
  auto made = small_pool_renderer(*src);
  BrickRenderer& r = *made;
  const Camera cam = orbit_camera(r.placement(), 30, 25, 1.25);
  RenderSettings s = vessel_settings(OpticalModel::kEmissionAbsorption);
  s.early_termination = 0.0;  // probe rays never terminate; here the shaded ones do not either
  for (BrickPassMode mode : {BrickPassMode::kMultipass, BrickPassMode::kTiled}) {
    BrickFrameSettings f;
    f.lod.force_level = 0;
    f.mode = mode;
    BrickFrameStats shaded, fetched, marched;
    const ImageRgba8 a = converge(r, cam, s, f, 96, 96, &shaded);
    f.sample_work = SampleWork::kFetchOnly;
    const ImageRgba8 b = converge(r, cam, s, f, 96, 96, &fetched);
    f.sample_work = SampleWork::kMarchOnly;
    const ImageRgba8 c = converge(r, cam, s, f, 96, 96, &marched);
    const std::string what = std::string(mode == BrickPassMode::kTiled ? "tiled" : "multipass") + ": samples " +
                             std::to_string(shaded.samples) + ", fetch only " + std::to_string(fetched.samples) +
                             ", march only " + std::to_string(marched.samples);
    INFO(what);
    CHECK(test::looks_non_blank(a));
    CHECK(shaded.samples > 0);
    CHECK(fetched.samples == shaded.samples);
    CHECK(marched.samples == shaded.samples);
    // The probes draw what they summed: the fetched values, the sample positions.
    CHECK(b.pixels != a.pixels);
    CHECK(c.pixels != b.pixels);
  }
}
