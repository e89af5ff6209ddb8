// Empty-space skipping on a real container: the ImageJ MRI stack (186x226x27
// u8, ../shared/testdata/slices/mri-stack) imported to .vxc with 16^3 chunks,
// drawn by the out-of-core renderer with skipping on and off. Skipping rests
// on the container's per-chunk min/max, so the first test checks that those
// cover every payload voxel (interior and apron): a brick whose samples can
// filter apron voxels is only skipped when the apron maps to zero opacity too.
#include <doctest/doctest.h>
#include <unistd.h>

#include <algorithm>
#include <filesystem>
#include <string>
#include <vector>

#include "gpu_fixture.h"
#include "render/lod/brick_renderer.h"
#include "volume/container_reader.h"
#include "volume/importers/import_source.h"
#include "volume/pyramid_builder.h"

using namespace vxr;

namespace {

// Imports the MRI slices once per process; returns the .vxc path.
const std::string& mri_container() {
  static const std::string path = [] {
    const std::string out = std::string(VXR_TEST_OUT_DIR) + "/brick_container_mri16.vxc";
    std::filesystem::create_directories(VXR_TEST_OUT_DIR);
    // ctest runs test cases as parallel processes that share this file: build
    // under a name of this process, then rename over (readers keep the old one).
    const std::string tmp = out + "." + std::to_string(getpid()) + ".tmp";
    std::filesystem::remove(tmp);
    auto src = open_import_source({std::string(VXR_TESTDATA_DIR) + "/slices/mri-stack"});
    REQUIRE(src.is_ok());
    ImportOptions opt;
    opt.chunk_size = 16;
    opt.apron = 1;
    REQUIRE(build_container(**src, tmp, opt).is_ok());
    std::filesystem::rename(tmp, out);
    return out;
  }();
  return path;
}

std::unique_ptr<ContainerReader> open_mri() {
  auto r = ContainerReader::open(mri_container());
  REQUIRE(r.is_ok());
  REQUIRE((*r)->info().dims == std::array<uint64_t, 3>{186, 226, 27});
  REQUIRE((*r)->info().dtype == DType::kU8);
  return std::move(r).value();
}

// MRI head: tissue up to ~255, background below ~30. A window starting at 90
// leaves the air and most soft tissue at zero opacity.
RenderSettings head(OpticalModel model) {
  RenderSettings s;
  s.model = model;
  s.channels[0].colormap = "magma";
  s.channels[0].window_lo = 90;
  s.channels[0].window_hi = 230;
  s.step_voxels = 0.5;
  s.density = 0.4;
  return s;
}

ImageRgba8 converge(BrickRenderer& r, const Camera& cam, const RenderSettings& s, const BrickFrameSettings& f,
                    BrickFrameStats* st) {
  for (int i = 0; i < 64; ++i) {
    auto img = r.render(cam, s, f, 80, 80, st);
    REQUIRE(img.is_ok());
    if (st->lod.missing == 0) return *img;
  }
  FAIL("did not converge in 64 frames");
  return {};
}

}  // namespace

TEST_CASE("brick container: every chunk's min/max covers its whole payload, apron included") {
  auto src = open_mri();
  uint64_t chunks = 0, apron_widens = 0;
  for (uint32_t l = 0; l < src->levels().size(); ++l) {
    const auto& li = src->levels()[l];
    for (uint32_t z = 0; z < li.chunk_counts[2]; ++z)
      for (uint32_t y = 0; y < li.chunk_counts[1]; ++y)
        for (uint32_t x = 0; x < li.chunk_counts[0]; ++x) {
          const ChunkKey k{l, x, y, z, 0, 0};
          auto st = src->stats(k);
          auto c = src->read(k);
          REQUIRE(st.is_ok());
          REQUIRE(c.is_ok());
          const auto [lo, hi] = std::minmax_element((*c)->data.begin(), (*c)->data.end());
          CHECK(st->min <= double(*lo));
          CHECK(st->max >= double(*hi));
          // The interior alone: how often the apron is what widens the range.
          const uint32_t e = (*c)->edge, a = src->apron();
          uint8_t imax = 0;
          for (uint32_t zz = a; zz < e - a; ++zz)
            for (uint32_t yy = a; yy < e - a; ++yy)
              for (uint32_t xx = a; xx < e - a; ++xx) imax = std::max(imax, (*c)->data[(size_t(zz) * e + yy) * e + xx]);
          if (*hi > imax) ++apron_widens;
          ++chunks;
        }
  }
  MESSAGE(chunks << " chunks, " << apron_widens << " where the apron raises the max");
  CHECK(chunks > 300);
  CHECK(apron_widens > 0);  // the test would notice an interior-only max
}

TEST_CASE("brick container: empty-space skipping on the imported MRI stack gives the identical image") {
  test::GpuTestScope scope;
  auto src = open_mri();
  BrickRendererOptions ro;
  ro.pool.slots = {8, 8, 8};
  auto r = BrickRenderer::create(test::gpu_context(), *src, ro);
  REQUIRE(r.is_ok());
  const Camera cam = orbit_camera((*r)->placement(), 30, 25, 1.25);
  // The models the brick shader draws, and transfer functions whose zero-
  // opacity range is not just "below the window": a brick is skipped only when
  // skipping cannot change a pixel (brick_may_contribute).
  struct Case {
    const char* name;
    RenderSettings s;
  };
  std::vector<Case> cases{{"ea ramp", head(OpticalModel::kEmissionAbsorption)},
                          {"mip ramp", head(OpticalModel::kMip)},
                          {"emission ramp", head(OpticalModel::kEmission)}};
  {
    // Opacity zero up to x = 0.3 of the window, then rising: more bricks empty.
    RenderSettings s = head(OpticalModel::kEmissionAbsorption);
    s.channels[0].opacity_points = {{0.0, 0.0}, {0.3, 0.0}, {1.0, 1.0}};
    cases.push_back({"ea opacity points", s});
    // MIP with opacity falling to zero at the top: a bright brick must still
    // be marched, it is what hides the dimmer ones behind the maximum.
    s.model = OpticalModel::kMip;
    s.channels[0].opacity_points = {{0.0, 1.0}, {0.6, 1.0}, {0.8, 0.0}, {1.0, 0.0}};
    cases.push_back({"mip falling opacity", s});
  }
  for (const Case& c : cases) {
    CAPTURE(c.name);
    const OpticalModel model = c.s.model;
    (void)model;
    BrickFrameSettings f;
    f.lod.force_level = 0;
    BrickFrameStats on, off;
    const ImageRgba8 a = converge(**r, cam, c.s, f, &on);
    f.lod.skip_empty = false;
    const ImageRgba8 b = converge(**r, cam, c.s, f, &off);
    uint64_t lit = 0;
    for (size_t i = 0; i < a.pixels.size(); i += 4) lit += (a.pixels[i] | a.pixels[i + 1] | a.pixels[i + 2]) > 0;
    MESSAGE("drawn on " << on.lod.drawn << " off " << off.lod.drawn << ", skipped " << on.lod.skipped_empty
                        << ", samples on " << on.samples << " off " << off.samples << ", lit pixels " << lit);
    CHECK(lit > 300);
    CHECK(a.pixels == b.pixels);
    if (std::string(c.name) == "mip falling opacity") {
      CHECK(on.lod.skipped_empty == 0);  // opacity 1 at value 0: nothing may be skipped
    } else {
      CHECK(on.lod.skipped_empty > 50);
    }
    if (std::string(c.name) == "ea opacity points") CHECK(on.lod.skipped_empty > 108);  // more than the ramp
    CHECK(off.lod.skipped_empty == 0);
    CHECK(on.lod.drawn + on.lod.skipped_empty == off.lod.drawn);
    if (on.lod.skipped_empty > 0) CHECK(double(on.samples) < 0.85 * double(off.samples));
  }
}

TEST_CASE("brick container: the empty-space test is exact per model and transfer function") {
  RenderSettings s;
  s.channels[0].window_lo = 90;
  s.channels[0].window_hi = 230;
  auto may = [&](double lo, double hi) { return brick_may_contribute(s, build_transfer_table(s), lo, hi); };
  // Ramp opacity: zero at and below the window's low end only.
  CHECK_FALSE(may(0, 90));
  CHECK(may(0, 91));
  CHECK(may(200, 255));
  // Opacity zero up to x = 0.3 (value 132): [0, 130] is empty, [0, 135] is not.
  s.channels[0].opacity_points = {{0.0, 0.0}, {0.3, 0.0}, {1.0, 1.0}};
  CHECK_FALSE(may(0, 130));
  CHECK(may(0, 135));
  // Opacity zero above x = 0.8: a bright-only brick is empty for ea...
  s.channels[0].opacity_points = {{0.0, 1.0}, {0.6, 1.0}, {0.8, 0.0}, {1.0, 0.0}};
  CHECK_FALSE(may(215, 255));
  CHECK(may(100, 255));
  // ...but never for mip (its maximum decides what the ray shows), and with
  // opacity at value 0 not even a brick below the window: a ray through only
  // such bricks shows colour(0) at opacity 1, a ray that skipped them nothing.
  s.model = OpticalModel::kMip;
  CHECK(may(215, 255));
  CHECK(may(0, 90));
  s.channels[0].opacity_points.clear();  // the ramp: opacity 0 at value 0
  CHECK_FALSE(may(0, 90));
  CHECK(may(0, 91));
  // Gamma keeps the ends: still empty at the window's low end.
  s.model = OpticalModel::kEmissionAbsorption;
  s.channels[0].opacity_points.clear();
  s.channels[0].gamma = 2.0;
  CHECK_FALSE(may(0, 90));
  CHECK(may(0, 100));
}
