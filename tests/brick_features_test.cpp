// Every feature through the out-of-core BrickRenderer: each optical model,
// multi-channel (additive and composite), a timepoint > 0, signed i8 data,
// gradient opacity across brick seams, depth colour, cut plane + ROI. The
// scenes are tests/raycast_golden_test.cpp's (the MRI
// head, the four balls) imported to .vxc with 16^3 chunks, so brick seams
// cross everything in view, plus real OME-TIFF files for i8, channels and
// timepoints.
//
// Each golden case checks two things:
//  1. the GPU image against golden_images/<name>.png (bit for bit on the
//     fingerprint it was blessed on, 3/255 elsewhere);
//  2. the GPU image (step 1/4 voxel) against the CPU reference (double
//     precision, exact trilinear) on the same level-0 voxels read back from
//     the source, max-abs <= 2/255 unless a case says otherwise and why. The
//     reference samples on the brick renderer's grid (midpoints anchored at
//     the eye, ReferenceOptions::grid_from_eye) at step 1/16 for integrals
//     (ea, emission, average) and at the GPU's own step for models that pick
//     one sample (mip, minip, iso, depth of the maximum), as the dense goldens
//     do: a finer step finds a different maximum or crossing. Why 2/255 holds:
//     lavapipe filters 8-bit textures with 8-bit weights (up to ~1/255 in the
//     value, ../shared/design/lavapipe.md), the step-1/4 integration error is
//     well under 1/255, and the one rounding rule (round to nearest, in the
//     shader's RGBA8 store and in to_rgba8) adds at most one more level.
#include <doctest/doctest.h>

#include <cstring>
#include <filesystem>
#include <unistd.h>

#include "golden.h"
#include "gpu_fixture.h"
#include "render/lod/brick_renderer.h"
#include "render/reference_renderer.h"
#include "volume/container_reader.h"
#include "volume/dense_chunk_source.h"
#include "render_scenes.h"
#include "volume/importers/import_source.h"
#include "volume/memory_slab_source.h"
#include "volume/procedural_source.h"
#include "volume/pyramid_builder.h"

using namespace vxr;

namespace {

std::unique_ptr<ProceduralSource> vessels_source(uint32_t chunk = 16, uint32_t apron = 1) {
  ProceduralOptions o;
  o.dims = {64, 64, 64};
  o.chunk_size = chunk;
  o.apron = apron;
  o.radius = 0.035;
  o.occupancy = 0.3;
  o.noise_max = 6;
  auto r = ProceduralSource::create(o);
  REQUIRE(r.is_ok());
  return std::move(r).value();
}

// Imports `make()`'s slab source to <test_out>/brick_features_<name>.vxc once per process.
std::unique_ptr<ContainerReader> imported_as(const std::string& name, uint32_t chunk, uint32_t apron,
                                             const std::function<std::unique_ptr<SlabSource>()>& make) {
  static std::map<std::string, std::string> done;
  const std::string key = name + "/" + std::to_string(chunk) + "/" + std::to_string(apron);
  std::string& path = done[key];
  if (path.empty()) {
    path = std::string(VXR_TEST_OUT_DIR) + "/brick_features_" + name + "_c" + std::to_string(chunk) + "_a" +
           std::to_string(apron) + ".vxc";
    std::filesystem::create_directories(VXR_TEST_OUT_DIR);
    // ctest runs test cases as parallel processes that share these files:
    // build under a name of this process, then rename over (readers keep the old one).
    const std::string tmp = path + "." + std::to_string(getpid()) + ".tmp";
    std::filesystem::remove(tmp);
    auto src = make();
    ImportOptions opt;
    opt.chunk_size = chunk;
    opt.apron = apron;
    auto built = build_container(*src, tmp, opt);
    REQUIRE_MESSAGE(built.is_ok(), built.status().to_string());
    std::filesystem::rename(tmp, path);
  }
  auto r = ContainerReader::open(path);
  REQUIRE(r.is_ok());
  return std::move(r).value();
}

// A file from ../shared/testdata.
std::unique_ptr<ContainerReader> imported(const std::string& rel, uint32_t chunk, uint32_t apron = 1) {
  return imported_as(std::filesystem::path(rel).stem().string(), chunk, apron, [&] {
    auto src = open_import_source({std::string(VXR_TESTDATA_DIR) + "/" + rel});
    REQUIRE_MESSAGE(src.is_ok(), src.status().to_string());
    return std::move(src).value();
  });
}

// The MRI head (186x226x27 u8, voxel 1x1x5) of the dense goldens.
std::unique_ptr<ContainerReader> mri(uint32_t apron = 1) {
  return imported_as("mri", 16, apron, [] { return std::make_unique<MemorySlabSource>(test::mri()); });
}

// The dense goldens' four balls (4 u8 channels of 48^3), or for MinIP the
// inverted ones (a bright block with a darker ball per channel).
std::unique_ptr<ContainerReader> balls(bool inverted) {
  return imported_as(inverted ? "balls_inverted" : "balls", 16, 1, [&] {
    std::vector<DenseVolume> ch = test::four_balls(inverted ? 40 : 48);
    VolumeInfo info;
    info.dims = {ch[0].dims[0], ch[0].dims[1], ch[0].dims[2]};
    info.channels = 4;
    std::vector<std::vector<uint8_t>> data;
    for (DenseVolume& v : ch) {
      if (inverted)
        for (auto& b : v.data) b = static_cast<uint8_t>(255 - b / 2);
      data.push_back(v.data);
    }
    return std::make_unique<MemorySlabSource>(info, std::move(data));
  });
}

std::unique_ptr<BrickRenderer> renderer(const ChunkSource& src, std::vector<uint32_t> channels = {}) {
  BrickRendererOptions o;
  o.pool.slots = {8, 8, 8};
  o.pool.channels = std::move(channels);
  auto r = BrickRenderer::create(test::gpu_context(), src, o);
  REQUIRE_MESSAGE(r.is_ok(), r.status().to_string());
  return std::move(r).value();
}

// Renders until nothing is missing; returns the last frame.
ImageRgba8 converge(BrickRenderer& r, const Camera& cam, const RenderSettings& s, const BrickFrameSettings& f,
                    uint32_t w, uint32_t h, BrickFrameStats* st = nullptr) {
  BrickFrameStats local;
  for (int i = 0; i < 64; ++i) {
    auto img = r.render(cam, s, f, w, h, &local);
    REQUIRE_MESSAGE(img.is_ok(), img.status().to_string());
    if (local.lod.missing == 0) {
      if (st) *st = local;
      return *img;
    }
  }
  FAIL("did not converge in 64 frames");
  return {};
}

RenderSettings vessels(OpticalModel m) {
  RenderSettings s;
  s.model = m;
  s.channels[0].colormap = "hot";
  s.channels[0].window_lo = 8;  // above the background noise (0..6)
  s.channels[0].window_hi = 200;
  s.step_voxels = 0.25;
  s.density = 0.3;
  s.iso_value = 60;
  if (m == OpticalModel::kMinIp) {
    // MinIP of the vessels is the background almost everywhere; a window over
    // the noise with an inverted ramp (low values opaque) shows the darkest
    // value along each ray, lowest where the ray crosses only noise.
    s.channels[0].window_lo = 0;
    s.channels[0].window_hi = 12;
    s.channels[0].opacity_points = {{0.0, 1.0}, {1.0, 0.2}};
    s.channels[0].colormap = "viridis";
  }
  return s;
}

struct Case {
  std::string name, why;
  const ChunkSource* src = nullptr;
  std::vector<uint32_t> channels;  // source channels drawn ({} = the first up to 4)
  RenderSettings settings;
  Camera camera;
  BrickFrameSettings frame;
  uint32_t width = 96, height = 96;
  double reference_step = 1.0 / 16.0;
  int reference_bound = 2;
  double outlier_share = 0.0;  // pixels allowed past the bound (iso silhouettes only)
};

// The drawn channels at level 0 of the frame's timepoint, for the reference.
std::vector<DenseVolume> level0(const ChunkSource& src, const std::vector<uint32_t>& channels, uint32_t timepoint) {
  std::vector<DenseVolume> out;
  for (uint32_t c : channels) {
    auto d = read_level_dense(src, 0, c, timepoint, uint64_t(256) << 20);
    REQUIRE(d.is_ok());
    out.push_back(std::move(d).value());
  }
  return out;
}

ImageRgba8 run(Case c) {
  test::GpuTestScope scope;
  c.frame.lod.force_level = 0;  // the reference draws level 0
  auto r = renderer(*c.src, c.channels);
  std::vector<uint32_t> drawn;
  for (uint32_t i = 0; i < r->channels(); ++i) drawn.push_back(r->pool().source_channel(i));
  const ImageRgba8 img = converge(*r, c.camera, c.settings, c.frame, c.width, c.height);
  CHECK(test::looks_non_blank(img));
  auto g = test::check_golden(c.name, img, test::gpu_context().info().fingerprint(), 3, c.why);
  INFO(g.message);
  CHECK(g.passed);

  ReferenceOptions ro;
  ro.step_voxels = c.reference_step;
  ro.grid_from_eye = true;
  if (c.frame.lod.roi.enabled) {
    ro.clip_lo = c.frame.lod.roi.lo;
    ro.clip_hi = c.frame.lod.roi.hi;
  }
  if (c.frame.lod.cut.enabled) ro.plane = glm::dvec4(c.frame.lod.cut.normal, c.frame.lod.cut.offset);
  const auto vols = level0(*c.src, drawn, c.frame.lod.timepoint);
  auto ref = render_reference(vols, c.camera, c.settings, c.width, c.height, ro);
  REQUIRE(ref.is_ok());
  const ImageRgba8 ref8 = to_rgba8(*ref);
  const test::ImageDiff d = test::diff_images(img, ref8);
  uint64_t past = 0;
  for (size_t i = 0; i < img.pixels.size(); i += 4) {
    int m = 0;
    for (int k = 0; k < 4; ++k) m = std::max(m, std::abs(int(img.pixels[i + k]) - int(ref8.pixels[i + k])));
    if (m > c.reference_bound) {
      ++past;
      if (past <= 3) MESSAGE("pixel " << (i / 4) % c.width << "," << (i / 4) / c.width << " differs by " << m);
    }
  }
  if (d.max_abs > c.reference_bound) {
    const std::filesystem::path out = std::filesystem::path(VXR_TEST_OUT_DIR);
    std::filesystem::create_directories(out);
    (void)write_png((out / (c.name + ".reference.png")).string(), ref8);
    (void)write_png((out / (c.name + ".gpu.png")).string(), img);
  }
  MESSAGE(c.name << " vs CPU reference: max_abs " << d.max_abs << ", rmse " << d.rmse << ", differing " << d.differing
                 << ", past the bound of " << c.reference_bound << ": " << past);
  CHECK(double(past) <= c.outlier_share * double(c.width) * c.height);
  return img;
}

// Models that pick one sample (see the header): the reference at the GPU's step.
Case same_step(Case c) {
  c.reference_step = c.settings.step_voxels;
  return c;
}

Case mri_case(const ChunkSource& src, const std::string& name, RenderSettings s, const std::string& why) {
  Case c;
  c.name = name;
  c.why = why;
  c.src = &src;
  c.settings = std::move(s);
  c.camera = orbit_camera({{186, 226, 27}, {1, 1, 5}}, 30.0, 25.0, 1.25);
  c.width = c.height = 128;
  return c;
}

Case balls_case(const ChunkSource& src, const std::string& name, ChannelBlend blend, const std::string& why) {
  Case c;
  c.name = name;
  c.why = why;
  c.src = &src;
  c.camera = orbit_camera({{48, 48, 48}, {1, 1, 1}}, 20.0, 30.0, 1.1);
  const char* maps[4] = {"red", "green", "blue", "yellow"};
  c.settings.channels.clear();
  for (int k = 0; k < 4; ++k) {
    ChannelSettings ch;
    ch.colormap = maps[k];
    ch.window_lo = 0;
    ch.window_hi = 255;
    c.settings.channels.push_back(ch);
  }
  c.settings.blend = blend;
  c.settings.density = 0.3;
  c.settings.step_voxels = 0.25;
  return c;
}

// The OME-TIFF test planes (439 x 167) from below, text readable: each plane
// prints its size, dimension order and channel / time point (1-based).
Camera ome_camera() {
  Camera cam;
  cam.eye = {0, 0, -250};
  cam.target = {0, 0, 0};
  cam.up = {0, -1, 0};
  cam.fov_y_deg = 40;
  return cam;
}

}  // namespace

TEST_CASE("brick features: empty-space skip rule per model (CPU)") {
  // One channel, window 8..200, gray ramp (opacity = value). A brick in
  // [0, 6] is below the window, one in [210, 250] above it.
  RenderSettings s;
  s.channels[0].window_lo = 8;
  s.channels[0].window_hi = 200;
  auto may = [&](OpticalModel m, double lo, double hi) {
    s.model = m;
    return brick_may_contribute(s, build_transfer_table(s), lo, hi);
  };
  for (OpticalModel m : {OpticalModel::kEmissionAbsorption, OpticalModel::kEmission}) {
    CHECK_FALSE(may(m, 0, 6));  // every value maps to opacity 0
    CHECK(may(m, 0, 9));
    CHECK(may(m, 210, 250));
  }
  CHECK_FALSE(may(OpticalModel::kMip, 0, 6));   // never raises the maximum
  CHECK(may(OpticalModel::kMip, 0, 9));
  CHECK(may(OpticalModel::kMinIp, 0, 6));       // a zero lowers the minimum: never skip it
  // Average (its length comes from the ray's chord): clearly below the window, skipped;
  // reaching its low end, kept.
  CHECK_FALSE(may(OpticalModel::kAverage, 0, 6));
  CHECK(may(OpticalModel::kAverage, 0, 8));
  // Iso (default iso value 128, step 0.5): below the iso value no sample crosses.
  CHECK_FALSE(may(OpticalModel::kIsosurface, 0, 100));
  CHECK(may(OpticalModel::kIsosurface, 0, 130));
  s.step_voxels = 2.0;  // past kIsoBackStep the crossing reads the sample the ray carried: never skip
  CHECK(may(OpticalModel::kIsosurface, 0, 100));
  s.step_voxels = 0.5;
  // MinIP skips a brick at or above the window's top only when entry 255 is
  // transparent (a ray that took no samples must look like one that took only those).
  s.channels[0].opacity_points = {{0.0, 1.0}, {0.99, 1.0}, {1.0, 0.0}};
  CHECK_FALSE(may(OpticalModel::kMinIp, 200, 250));
  CHECK(may(OpticalModel::kMinIp, 199, 250));
  // MIP: entry 0 opaque -> no skipping (the ray's colour at value 0 is visible); nor for average.
  s.channels[0].opacity_points = {{0.0, 0.5}, {1.0, 1.0}};
  CHECK(may(OpticalModel::kMip, 0, 6));
  CHECK(may(OpticalModel::kAverage, 0, 6));
  // Average under a window from 0: a brick of zeros is skipped, one reaching above 0 kept.
  s.channels[0].opacity_points = {{0.0, 0.0}, {1.0, 1.0}};
  s.channels[0].window_lo = 0;
  CHECK_FALSE(may(OpticalModel::kAverage, 0, 0));
  CHECK(may(OpticalModel::kAverage, 0, 1));
  s.channels[0].window_lo = 8;
  // Default ramp: entry 255 is opaque -> MinIP never skips.
  s.channels[0].opacity_points.clear();
  CHECK(may(OpticalModel::kMinIp, 200, 250));

  // Two channels: EA skips only when every enabled channel is transparent.
  s.model = OpticalModel::kEmissionAbsorption;
  s.channels.push_back(s.channels[0]);
  const TransferTable t2 = build_transfer_table(s);
  const ChunkStats both_empty[2] = {{0, 6}, {0, 6}}, second_lit[2] = {{0, 6}, {0, 100}};
  CHECK_FALSE(brick_may_contribute(s, t2, both_empty));
  CHECK(brick_may_contribute(s, t2, second_lit));
  s.channels[1].enabled = false;  // a disabled channel never makes a brick visible
  CHECK_FALSE(brick_may_contribute(s, build_transfer_table(s), second_lit));
}

TEST_CASE("brick features: single-hue colour maps factor as hue times value, others do not (CPU)") {
  RenderSettings s;
  s.channels.resize(4);
  const std::pair<const char*, std::optional<glm::vec3>> maps[] = {
      {"gray", glm::vec3(1, 1, 1)},    {"green", glm::vec3(0, 1, 0)}, {"magenta", glm::vec3(1, 0, 1)},
      {"#00ffff", glm::vec3(0, 1, 1)}, {"hot", std::nullopt},        {"viridis", std::nullopt},
      {"#ff8000", std::nullopt}};
  for (const auto& [name, hue] : maps) {
    CAPTURE(name);
    s.channels[2].colormap = name;
    const TransferTable t = build_transfer_table(s);
    REQUIRE(t.hue[2].has_value() == hue.has_value());
    if (!hue) continue;
    CHECK(*t.hue[2] == *hue);
    // The rule the GPU's hue rows rely on: every colour is the hue times one value, exactly.
    for (int i = 0; i < VXR_TF_SIZE; ++i) {
      const glm::vec4 e = t.rgba[2 * VXR_TF_SIZE + i];
      const float v = std::max({e.r, e.g, e.b});
      CHECK(glm::vec3(e) == *hue * v);
    }
  }
  // Colour points factor where they stay on one hue.
  s.channels[1].color_points = {{0.0, {0, 0, 0}}, {0.5, {0.25, 0, 0.25}}, {1.0, {1, 0, 1}}};
  CHECK(build_transfer_table(s).hue[1] == glm::vec3(1, 0, 1));
  s.channels[1].color_points = {{0.0, {0, 0, 0}}, {1.0, {1, 0.5, 0}}};
  CHECK_FALSE(build_transfer_table(s).hue[1].has_value());
}

TEST_CASE("brick features: multipass carries the ray state of every model that fits a texel (CPU)") {
  RenderSettings s;
  for (OpticalModel m : {OpticalModel::kEmissionAbsorption, OpticalModel::kEmission, OpticalModel::kMip,
                         OpticalModel::kMinIp, OpticalModel::kAverage, OpticalModel::kIsosurface}) {
    s.model = m;
    CHECK(brick_state_fits_texel(s, 1));
  }
  s.model = OpticalModel::kEmissionAbsorption;
  CHECK_FALSE(brick_state_fits_texel(s, 2));  // additive: an optical depth per channel
  s.blend = ChannelBlend::kComposite;
  CHECK(brick_state_fits_texel(s, 4));  // one medium
  s.model = OpticalModel::kMip;
  CHECK_FALSE(brick_state_fits_texel(s, 2));
  s.model = OpticalModel::kAverage;
  CHECK(brick_state_fits_texel(s, 3));
  CHECK_FALSE(brick_state_fits_texel(s, 4));
}

TEST_CASE("brick features: every model gives the same image multipass, tiled, and with skipping off") {
  test::GpuTestScope scope;
  auto src = vessels_source();
  auto r = renderer(*src);
  const Camera cam = orbit_camera({{64, 64, 64}, {1, 1, 1}}, 30, 25, 1.25);
  for (OpticalModel m : {OpticalModel::kEmission, OpticalModel::kMip, OpticalModel::kMinIp, OpticalModel::kAverage,
                         OpticalModel::kIsosurface}) {
    const std::string model = optical_model_name(m);
    CAPTURE(model);
    RenderSettings s = vessels(m);
    s.step_voxels = 0.5;
    BrickFrameSettings f;
    f.lod.force_level = 0;
    f.mode = BrickPassMode::kMultipass;
    BrickFrameStats ms;
    const ImageRgba8 multi = converge(*r, cam, s, f, 64, 64, &ms);
    CHECK(test::looks_non_blank(multi));
    CHECK(ms.dispatches > 2);  // really waves
    f.mode = BrickPassMode::kTiled;
    CHECK(converge(*r, cam, s, f, 64, 64).pixels == multi.pixels);
    f.lod.skip_empty = false;
    CHECK(converge(*r, cam, s, f, 64, 64).pixels == multi.pixels);
  }
}

TEST_CASE("brick features: lookups through the single-hue rows give the images of the table itself") {
  test::GpuTestScope scope;
  auto src = vessels_source();
  const Camera cam = orbit_camera({{64, 64, 64}, {1, 1, 1}}, 30, 25, 1.25);
  struct Variant {
    OpticalModel model;
    const char* colormap;
    DepthColorMode depth;
  };
  const auto pipelines = std::make_shared<BrickPipelines>();  // each variant compiled once for all renderers
  // The rows serve E-A and emission (a lookup every sample), not MIP (one a ray), nor hot (no hue).
  for (const Variant& v : {Variant{OpticalModel::kEmissionAbsorption, "gray", DepthColorMode::kOff},
                           Variant{OpticalModel::kEmission, "green", DepthColorMode::kOff},
                           Variant{OpticalModel::kEmissionAbsorption, "cyan", DepthColorMode::kAxisZ},
                           Variant{OpticalModel::kEmissionAbsorption, "hot", DepthColorMode::kOff},
                           Variant{OpticalModel::kMip, "magenta", DepthColorMode::kOff}}) {
    const std::string model = optical_model_name(v.model);
    CAPTURE(model);
    CAPTURE(v.colormap);
    RenderSettings s = vessels(v.model);
    s.channels[0].colormap = v.colormap;
    s.depth_color = v.depth;
    s.step_voxels = 0.5;
    BrickFrameSettings f;
    f.lod.force_level = 0;
    std::vector<ImageRgba8> images;
    for (bool hue_tables : {true, false}) {
      BrickRendererOptions o;
      o.pool.slots = {8, 8, 8};
      o.hue_tables = hue_tables;
      o.pipelines = pipelines;
      auto r = BrickRenderer::create(test::gpu_context(), *src, o);
      REQUIRE(r.is_ok());
      BrickFrameStats st;
      images.push_back(converge(**r, cam, s, f, 64, 64, &st));
      CHECK(st.hue_lookups == (hue_tables && std::string(v.colormap) != "hot" && v.model != OpticalModel::kMip));
      // Multipass waves carry one-channel E-A's colour between passes (as the hue times its value).
      if (v.model == OpticalModel::kEmissionAbsorption) {
        BrickFrameSettings waves = f;
        waves.mode = BrickPassMode::kMultipass;
        images.push_back(converge(**r, cam, s, waves, 64, 64));
      }
    }
    CHECK(test::looks_non_blank(images[0]));
    for (const ImageRgba8& image : images) CHECK(image.pixels == images[0].pixels);
  }
}

TEST_CASE("brick features: a sample offset and per-pixel jitter hold across brick seams and match the CPU reference "
          "on the same grid") {
  test::GpuTestScope scope;
  auto src = vessels_source();  // 16^3 chunks: seams cross the whole view
  auto r = renderer(*src);
  const Camera cam = orbit_camera({{64, 64, 64}, {1, 1, 1}}, 30, 25, 1.25);
  std::vector<DenseVolume> vols;
  {
    auto d = read_level_dense(*src, 0, 0, 0, uint64_t(64) << 20);
    REQUIRE(d.is_ok());
    vols.push_back(std::move(d).value());
  }
  // A coarse step, where the offset moves samples by a visible amount.
  struct Grid { const char* name; double offset; bool jitter; };
  std::map<std::string, ImageRgba8> images;
  for (const Grid g : {Grid{"offset 0.5", 0.5, false}, Grid{"offset 0", 0.0, false}, Grid{"jitter", 0.5, true}}) {
    for (OpticalModel m : {OpticalModel::kEmissionAbsorption, OpticalModel::kMip}) {
      const std::string label = std::string(g.name) + " " + optical_model_name(m);
      CAPTURE(label);
      RenderSettings s = vessels(m);
      s.step_voxels = 1.5;
      s.sample_offset = g.offset;
      s.jitter = g.jitter;
      // MIP shows one filtered value: lavapipe's 8-bit filter weights (up to
      // 1/255 in the value, ../shared/design/lavapipe.md) times the window's
      // gain (255/192) plus the one rounding give up to 3/255 in gray; hot's
      // steepest channel (3x) would reach 5.
      if (m == OpticalModel::kMip) s.channels[0].colormap = "gray";
      const int bound = m == OpticalModel::kMip ? 3 : 2;
      BrickFrameSettings f;
      f.lod.force_level = 0;
      f.mode = BrickPassMode::kMultipass;
      BrickFrameStats ms;
      const ImageRgba8 multi = converge(*r, cam, s, f, 64, 64, &ms);
      CHECK(test::looks_non_blank(multi));
      // The offset is one value per ray: waves (the state carried between
      // passes), tiles and skipping off take the same samples.
      f.mode = BrickPassMode::kTiled;
      CHECK(converge(*r, cam, s, f, 64, 64).pixels == multi.pixels);
      f.lod.skip_empty = false;
      CHECK(converge(*r, cam, s, f, 64, 64).pixels == multi.pixels);

      ReferenceOptions ro;
      ro.step_voxels = s.step_voxels;
      ro.grid_from_eye = true;
      auto ref = render_reference(vols, cam, s, 64, 64, ro);
      REQUIRE(ref.is_ok());
      const test::ImageDiff d = test::diff_images(multi, to_rgba8(*ref));
      MESSAGE(label << " vs CPU reference on the same grid: max_abs " << d.max_abs << ", rmse " << d.rmse);
      CHECK(d.max_abs <= bound);
      images[label] = multi;
    }
  }
  // Each grid really moves the samples.
  for (OpticalModel m : {OpticalModel::kEmissionAbsorption, OpticalModel::kMip}) {
    const std::string model = optical_model_name(m);
    CAPTURE(model);
    CHECK(images["offset 0.5 " + model].pixels != images["offset 0 " + model].pixels);
    CHECK(images["jitter " + model].pixels != images["offset 0.5 " + model].pixels);
    CHECK(images["jitter " + model].pixels != images["offset 0 " + model].pixels);
  }
}

TEST_CASE("brick features: multi-channel states that fit a texel give the same image multipass, tiled and with skipping off") {
  test::GpuTestScope scope;
  auto src = balls(false);
  const Camera cam = orbit_camera({{48, 48, 48}, {1, 1, 1}}, 20.0, 30.0, 1.1);
  struct Variant {
    OpticalModel model;
    ChannelBlend blend;
    std::vector<uint32_t> channels;
  };
  // Emission packs the colour summed over channels, composite ea one medium,
  // average up to three sums and the length.
  for (const Variant& v : {Variant{OpticalModel::kEmission, ChannelBlend::kAdditive, {0, 1, 2, 3}},
                           Variant{OpticalModel::kEmissionAbsorption, ChannelBlend::kComposite, {0, 1, 2, 3}},
                           Variant{OpticalModel::kAverage, ChannelBlend::kAdditive, {0, 1, 2}}}) {
    const std::string model = optical_model_name(v.model);
    CAPTURE(model);
    auto r = renderer(*src, v.channels);
    RenderSettings s;
    s.model = v.model;
    s.blend = v.blend;
    s.density = 0.1;
    s.channels.resize(v.channels.size());
    const char* maps[4] = {"red", "green", "blue", "yellow"};
    for (size_t k = 0; k < v.channels.size(); ++k) {
      s.channels[k].colormap = maps[k];
      if (v.model == OpticalModel::kAverage) {  // as the dense average golden: the mean is small, make it opaque
        s.channels[k].window_hi = 120;
        s.channels[k].opacity_points = {{0.0, 1.0}, {1.0, 1.0}};
      }
    }
    REQUIRE(brick_state_fits_texel(s, uint32_t(v.channels.size())));
    BrickFrameSettings f;
    f.lod.force_level = 0;
    f.mode = BrickPassMode::kMultipass;
    BrickFrameStats ms;
    const ImageRgba8 multi = converge(*r, cam, s, f, 64, 64, &ms);
    CHECK(test::looks_non_blank(multi));
    CHECK(ms.dispatches > 2);
    f.mode = BrickPassMode::kTiled;
    BrickFrameStats ts;
    CHECK(converge(*r, cam, s, f, 64, 64, &ts).pixels == multi.pixels);
    // Skipping keeps the image: a cell is clear only where every drawn channel is.
    f.lod.skip_empty = false;
    BrickFrameStats off;
    CHECK(converge(*r, cam, s, f, 64, 64, &off).pixels == multi.pixels);
    INFO("samples with skipping " << ts.samples << ", without " << off.samples);
    CHECK(ts.samples <= off.samples);
    // The balls' background is 0: average (entry 0 opaque, so over whole bricks) walks past it.
    if (v.model == OpticalModel::kAverage) CHECK(ts.samples < off.samples);
  }
}

TEST_CASE("brick features: each optical model matches the CPU reference (goldens)") {
  auto src = mri();
  using test::mri_settings;
  run(mri_case(*src, "brick_model_ea", mri_settings(OpticalModel::kEmissionAbsorption, "hot"),
               "the MRI head (16^3 bricks) by front-to-back emission-absorption, hot, window 20..220: skin and "
               "skull opaque where bright; the dense golden model_ea's picture"));
  {
    RenderSettings s = mri_settings(OpticalModel::kEmission, "gray");
    s.density = 0.01;
    run(mri_case(*src, "brick_model_emission", s,
                 "emission only (alpha 0): brightness adds along each ray, the thick middle of the head glows most"));
  }
  run(same_step(mri_case(*src, "brick_model_mip", mri_settings(OpticalModel::kMip, "gray"),
                         "maximum intensity: the brightest tissue (scalp fat, skull marrow) along each ray, gray")));
  {
    RenderSettings s = mri_settings(OpticalModel::kAverage, "gray");
    s.channels[0].window_lo = 0;
    s.channels[0].window_hi = 120;
    s.channels[0].opacity_points = {{0.0, 1.0}, {1.0, 1.0}};
    Case c = mri_case(*src, "brick_model_average", s,
                      "mean value along each ray (an X-ray-like projection), window 0..120, gray; each ray divides "
                      "by its chord through the volume; entry 0 is opaque, so every brick is cast (cells that "
                      "window to 0 are skipped)");
    // A ray grazing the box's silhouette for less than a step takes one
    // sample or none depending on whether float or double places its entry
    // (average shows any sample at full opacity): a few such edge pixels.
    c.outlier_share = 0.0005;
    run(c);
  }
  {
    Case c = same_step(mri_case(*src, "brick_model_iso", mri_settings(OpticalModel::kIsosurface, "gray"),
                                "first crossing of 60 (the skin), refined linearly between samples, headlight "
                                "Lambert + specular on central-difference normals taken across brick seams from "
                                "the 2-voxel apron"));
    // As the dense golden: grazing silhouette rays can find or miss a
    // crossing on a filtering difference, so 1% of pixels may differ more.
    c.reference_bound = 3;
    c.outlier_share = 0.01;
    run(c);
  }
}

TEST_CASE("brick features: MinIP of four channels matches the CPU reference (golden)") {
  auto src = balls(true);
  Case c;
  c.name = "brick_model_minip";
  c.why = "minimum intensity from above of four u8 channels, each a bright block with one darker ball: each "
          "channel's colour dims where its ball is (cyan, magenta, yellow, gray quadrants); four channels of MinIP "
          "do not fit the multipass texel, so this also proves the tiled fallback";
  c.src = src.get();
  c.camera = orbit_camera({{40, 40, 40}, {1, 1, 1}}, 0.0, 90.0 - 1e-3, 1.2);
  c.settings.model = OpticalModel::kMinIp;
  c.settings.channels.clear();
  for (const char* m : {"cyan", "magenta", "yellow", "gray"}) {
    ChannelSettings ch;
    ch.colormap = m;
    ch.window_lo = 120;
    ch.window_hi = 255;
    ch.opacity_points = {{0.0, 0.25}, {1.0, 0.25}};
    c.settings.channels.push_back(ch);
  }
  c.settings.step_voxels = 0.25;
  run(same_step(c));
}

TEST_CASE("brick features: four channels additive and composite match the CPU reference (goldens)") {
  auto src = balls(false);
  run(balls_case(*src, "brick_channels_additive", ChannelBlend::kAdditive,
                 "four u8 channels, each a soft ball, red/green/blue/yellow; additive: each channel absorbs only its "
                 "own light, overlaps add (the dense golden multichannel_additive's picture)"));
  run(balls_case(*src, "brick_channels_composite", ChannelBlend::kComposite,
                 "the same four balls as one medium: extinctions add, colour is the extinction-weighted mix, so a "
                 "front ball hides the one behind"));
}

TEST_CASE("brick features: depth colour matches the CPU reference (golden)") {
  auto src = mri();
  RenderSettings s = test::mri_settings(OpticalModel::kEmissionAbsorption, "turbo");
  s.depth_color = DepthColorMode::kView;
  s.density = 0.2;
  Case dc = mri_case(*src, "brick_depth_color", s,
               "colour by distance along the view through turbo, measured along the whole ray (not per brick): the "
               "near cheek blue, the far side of the head red");
  // Turbo is steep: the step-1/4 integral on this grid differs from the
  // converged one by up to 4/255 at 8 pixels (measured against step 1/16);
  // at the same step and grid it is within 1/255 (measured).
  dc = same_step(dc);
  run(dc);
}

TEST_CASE("brick features: gradient opacity across brick seams, an apron-1 source filled from neighbours equals "
          "an apron-2 source") {
  auto src2 = mri(2);
  RenderSettings s = test::mri_settings(OpticalModel::kEmissionAbsorption, "gray");
  s.gradient_opacity = {true, 0.02, 0.15};
  s.density = 0.4;
  Case c = mri_case(*src2, "brick_gradient_seams", s,
                    "opacity scaled by a ramp of the central-difference gradient magnitude (0.02..0.15 per voxel): "
                    "skin and skull edges show, flat tissue is clear; 16^3 bricks, no seam visible");
  // The gradient ramp is steep: on this grid the step-1/4 integral differs
  // from the converged one by up to 7/255 at a few dozen edge pixels
  // (measured: 18 past 2/255 against step 1/16, 33 against 1/8). Against the
  // reference at the same step and grid (the same samples) it is within
  // 1/255 (measured), which is what this pins: seams, apron and arithmetic.
  c = same_step(c);
  const ImageRgba8 two = run(c);

  test::GpuTestScope scope;
  auto src1 = mri(1);
  REQUIRE(src1->apron() == 1);
  auto r = renderer(*src1);
  CHECK(r->pool().apron() == 1);
  BrickFrameSettings f;
  f.lod.force_level = 0;
  const ImageRgba8 one = converge(*r, c.camera, c.settings, f, c.width, c.height);
  CHECK(r->pool().apron() == 2);  // raised on the first gradient frame
  // The slots hold the same texels (next test), but the apron-2 container's
  // per-chunk min/max cover two apron layers, so fewer of its bricks are
  // skipped, the uploads go to other slots, and the float atlas coordinate
  // of a sample rounds differently: 1/255 at most (measured 1, also with
  // skipping off; tiled vs multipass on one renderer: 0).
  CHECK(test::diff_images(one, two).max_abs <= 1);
}

TEST_CASE("brick features: a slot filled from apron-1 chunks and their neighbours equals the apron-2 chunk") {
  test::GpuTestScope scope;
  auto src1 = mri(1), src2 = mri(2);
  BrickPoolOptions o;
  o.slots = {2, 2, 2};
  o.apron = 2;
  auto p1 = BrickPool::create(test::gpu_context(), *src1, o);
  auto p2 = BrickPool::create(test::gpu_context(), *src2, o);
  REQUIRE(p1.is_ok());
  REQUIRE(p2.is_ok());
  REQUIRE((*p1)->slot_edge() == 20);
  const size_t n = size_t(20) * 20 * 20;
  std::vector<uint8_t> a(n), b(n);
  // Corner, edge and interior chunks: every neighbour direction and the volume's border clamp.
  for (ChunkKey k : {ChunkKey{0, 0, 0, 0}, ChunkKey{0, 5, 7, 1}, ChunkKey{0, 11, 14, 1}, ChunkKey{0, 3, 0, 0},
                     ChunkKey{1, 2, 3, 0}}) {
    CAPTURE(k.level);
    CAPTURE(k.x);
    CAPTURE(k.y);
    CAPTURE(k.z);
    REQUIRE((*p1)->fill_slot(k, a.data()).is_ok());
    REQUIRE((*p2)->fill_slot(k, b.data()).is_ok());
    CHECK(a == b);
  }
}

TEST_CASE("brick features: a brick draws the same in any atlas slot: other slot grids, other session histories") {
  // Which slot a brick lands in depends on the pool's grid and on what the
  // session loaded before (a viewer that looked elsewhere first, a full pool
  // that evicted and reloaded). The rays' own filter takes a sample's weights
  // relative to its brick's slot, so none of that moves a pixel: taken from
  // atlas coordinates they rounded differently in far slots (1 LSB here).
  test::GpuTestScope scope;
  auto vessels_src = vessels_source();
  auto head = mri();
  DenseVolume head16 = test::mri();  // u16: the filter's texel pairs instead of quads
  {
    std::vector<uint8_t> wide(head16.data.size() * 2);
    for (size_t i = 0; i < head16.data.size(); ++i) {
      const uint16_t v = uint16_t(head16.data[i] * 257u);
      std::memcpy(&wide[i * 2], &v, 2);
    }
    head16.data = std::move(wide);
    head16.dtype = DType::kU16;
  }
  auto head16_src = DenseChunkSource::create({head16}, 16, 1);
  REQUIRE_MESSAGE(head16_src.is_ok(), head16_src.status().to_string());
  RenderSettings ea16 = test::mri_settings(OpticalModel::kEmissionAbsorption, "gray");
  ea16.channels[0].window_lo *= 257;
  ea16.channels[0].window_hi *= 257;
  struct Scene {
    const ChunkSource* src;
    RenderSettings s;
    Camera cam, away;
    glm::uvec3 compact, far;  // slot grids: every brick near the atlas's origin, or far along z
  };
  // `away`: far off, where the coarse levels load first and take the first slots.
  const VolumePlacement head_box{head16.dims, head16.voxel_size}, cube{{64, 64, 64}, {1, 1, 1}};
  const Camera mri_cam = orbit_camera(head_box, 30.0, 25.0, 1.25), mri_away = orbit_camera(head_box, 200, -20, 8);
  for (const Scene& sc :
       {Scene{vessels_src.get(), vessels(OpticalModel::kEmissionAbsorption), orbit_camera(cube, 30, 25, 1.25),
              orbit_camera(cube, 210, -30, 8), {4, 4, 5}, {1, 1, 100}},
        Scene{vessels_src.get(), vessels(OpticalModel::kMip), orbit_camera(cube, 120, 10, 1.1),
              orbit_camera(cube, 300, 40, 8), {4, 4, 5}, {1, 1, 100}},
        Scene{head.get(), test::mri_settings(OpticalModel::kEmissionAbsorption, "gray"), mri_cam, mri_away,
              {8, 8, 8}, {2, 3, 100}},
        Scene{head16_src.value().get(), ea16, mri_cam, mri_away, {8, 8, 8}, {2, 3, 100}}}) {
    CAPTURE(sc.src->info().dims[0]);
    const std::string dtype = dtype_name(sc.src->info().dtype), model = optical_model_name(sc.s.model);
    CAPTURE(dtype);
    CAPTURE(model);
    auto draw = [&](glm::uvec3 slots, bool looked_away_first) {
      BrickRendererOptions o;
      o.pool.slots = slots;
      auto r = BrickRenderer::create(test::gpu_context(), *sc.src, o);
      REQUIRE_MESSAGE(r.is_ok(), r.status().to_string());
      if (looked_away_first) (void)converge(**r, sc.away, sc.s, {}, 160, 128);
      return converge(**r, sc.cam, sc.s, {}, 160, 128);
    };
    const ImageRgba8 fresh = draw(sc.compact, false);
    CHECK(test::looks_non_blank(fresh));
    CHECK(draw(sc.far, false).pixels == fresh.pixels);
    CHECK(draw(sc.compact, true).pixels == fresh.pixels);
  }
}

TEST_CASE("brick features: an automatic pool holds at most twice a small source's bricks, and still preloads it") {
  test::GpuTestScope scope;
  // 64^3 in 16^3 chunks: 64 + 8 + 1 bricks. The automatic grid (up to 16 x
  // 16 x 8) loses a row of slots while twice the bricks still fit.
  auto small = vessels_source();
  const uint64_t bricks = 73;
  auto pool = BrickPool::create(test::gpu_context(), *small, {});
  REQUIRE(pool.is_ok());
  const glm::uvec3 g = (*pool)->slot_grid();
  const uint32_t largest = std::max({g.x, g.y, g.z});
  CHECK((*pool)->capacity() >= 2 * bricks);
  CHECK(uint64_t((*pool)->capacity()) / largest * (largest - 1) < 2 * bricks);
  BrickRendererOptions o;
  o.preload_if_fits = true;
  auto r = BrickRenderer::create(test::gpu_context(), *small, o);
  REQUIRE(r.is_ok());
  CHECK((*r)->pool().capacity() == (*pool)->capacity());
  BrickFrameStats st;
  auto img = (*r)->render(orbit_camera({{64, 64, 64}, {1, 1, 1}}, 30, 25, 1.25),
                          vessels(OpticalModel::kEmissionAbsorption), {}, 64, 64, &st);
  REQUIRE(img.is_ok());
  CHECK(st.lod.missing == 0);  // every brick was resident from the first frame
  // A source with more bricks than the budget's grid (32^3 bricks of 34^3 texels: 16 x 16 x 8 fit 1 GiB) keeps it.
  ProceduralOptions po;
  po.dims = {4096, 4096, 4096};
  auto big = ProceduralSource::create(po);
  REQUIRE(big.is_ok());
  auto big_pool = BrickPool::create(test::gpu_context(), **big, {});
  REQUIRE(big_pool.is_ok());
  CHECK((*big_pool)->slot_grid() == glm::uvec3(16, 16, 8));
}

TEST_CASE("brick features: atlases read by hand hold a word per texel: u8 (x, y) quads, u16 (x) pairs") {
  // The rays load a u8 texel with its +x, +y and +xy neighbours, or a u16
  // texel with its +x neighbour, as one 32-bit word (BrickPool
  // write_texel_words); past a slot's last texel of an axis the texel itself stands in.
  const uint8_t row[3] = {7, 9, 200}, next[3] = {1, 2, 3};
  uint8_t quads[12];
  write_texel_words(VK_FORMAT_R8_UNORM, row, next, 3, quads);
  CHECK(std::vector<uint8_t>(quads, quads + 12) == std::vector<uint8_t>{7, 9, 1, 2, 9, 200, 2, 3, 200, 200, 3, 3});
  const uint16_t row16[2] = {700, 65535};
  uint16_t pairs16[4];
  write_texel_words(VK_FORMAT_R16_UNORM, reinterpret_cast<const uint8_t*>(row16), nullptr, 2,
                    reinterpret_cast<uint8_t*>(pairs16));
  CHECK(std::vector<uint16_t>(pairs16, pairs16 + 4) == std::vector<uint16_t>{700, 65535, 65535, 65535});
  test::GpuTestScope scope;
  auto src = mri(2);
  BrickPoolOptions o;
  o.slots = {2, 2, 2};
  auto made = BrickPool::create(test::gpu_context(), *src, o);
  REQUIRE(made.is_ok());
  BrickPool& pool = **made;
  // Texel views (and so words) on a CPU device only; GPUs sample.
  CHECK(pool.texel_words() == test::gpu_context().info().is_cpu());
  if (!pool.texel_words()) return;
  const uint32_t e = pool.slot_edge();
  CHECK(pool.atlas().extent.width == 4 * 2 * e);
  const ChunkKey k{0, 5, 7, 1};
  REQUIRE(pool.upload({k}, 1 << 20).is_ok());
  std::vector<uint8_t> texels(size_t(e) * e * e), want(4 * e);
  REQUIRE(pool.fill_slot(k, texels.data()).is_ok());
  const glm::uvec3 at = pool.touch(k) - glm::uvec3(pool.apron());
  const gpu::Image& a = pool.atlas();
  for (uint32_t z : {0u, e / 2, e - 1})
    for (uint32_t y : {0u, e / 2, e - 1}) {
      CAPTURE(z);
      CAPTURE(y);
      const uint8_t* from = &texels[(size_t(z) * e + y) * e];
      write_texel_words(VK_FORMAT_R8_UNORM, from, y + 1 < e ? from + e : from, e, want.data());
      const uint8_t* got = a.mapped + (at.z + z) * a.depth_pitch + (at.y + y) * a.row_pitch + size_t(at.x) * 4;
      CHECK(std::vector<uint8_t>(got, got + 4 * e) == want);
    }
}

namespace {
// The head clipped to the box [20,160]x[30,200]x[0,20] and cut by the
// oblique plane (1,1,0) through the centre, the +x+y side kept.
void clip_head(Case& c) {
  c.frame.lod.roi = {true, {20, 30, 0}, {160, 200, 20}};
  const glm::dvec3 n = glm::normalize(glm::dvec3(1, 1, 0));
  c.frame.lod.cut = {true, n, -glm::dot(n, glm::dvec3(93, 113, 13.5))};
}
}  // namespace

TEST_CASE("brick features: cut plane and ROI together match the CPU reference (golden)") {
  auto src = mri();
  Case c = mri_case(*src, "brick_cut_roi", test::mri_settings(OpticalModel::kEmissionAbsorption, "hot"),
                    "the head clipped to the box [20,160]x[30,200]x[0,20] (voxels) and cut by the oblique plane "
                    "(1,1,0) through the centre, the +x+y side kept: the inside of the head shows on both cuts; "
                    "matches the CPU reference clipped the same way");
  clip_head(c);
  run(c);
}

TEST_CASE("brick features: average with a cut plane and an ROI matches the CPU reference (golden)") {
  // Average divides by the ray's chord through the clipped volume
  // (brick_raycast.comp region_chord): a chord that missed the ROI or the
  // cut would darken or brighten the clipped rays against the reference.
  auto src = mri();
  RenderSettings s = test::mri_settings(OpticalModel::kAverage, "gray");
  s.channels[0].window_lo = 0;
  s.channels[0].window_hi = 120;
  s.channels[0].opacity_points = {{0.0, 0.0}, {0.02, 1.0}, {1.0, 1.0}};  // entry 0 clear: bricks of air skipped
  Case c = mri_case(*src, "brick_average_cut_roi", s,
                    "mean value along each ray of the head clipped to the box [20,160]x[30,200]x[0,20] and cut by "
                    "the oblique plane (1,1,0) through the centre (the +x+y side kept), each ray divided by its "
                    "chord through what is kept; matches the CPU reference clipped the same way");
  clip_head(c);
  // The reference on the GPU's own grid: the same samples, so each ray's
  // count is compared as well as its sum (at a finer reference step the
  // short rays along the clipped faces average other samples).
  run(same_step(c));
}

TEST_CASE("brick features: signed i8 data (OME-TIFF z-series) matches the CPU reference (golden)") {
  auto src = imported("ome-tiff/z-series.ome.tif", 32);
  REQUIRE(src->info().dtype == DType::kI8);
  Case c;
  c.name = "brick_i8_zseries";
  c.why = "OME-TIFF z-series (439x167x5, signed int8, 32^3 chunks) by MIP from below, window -64..127 (data "
          "units, signed as the dense path maps them): a dark-to-bright ramp with the plane labels (size, XYZCT, "
          "Z = 5/5, the maximum over the slices) printed in black";
  c.src = src.get();
  c.settings.model = OpticalModel::kMip;
  c.settings.step_voxels = 0.25;
  c.settings.channels[0].window_lo = -64;
  c.settings.channels[0].window_hi = 127;
  c.settings.channels[0].colormap = "gray";
  c.camera = ome_camera();
  c.width = 440;
  c.height = 170;
  run(same_step(c));
}

TEST_CASE("brick features: three signed channels of a real OME-TIFF match the CPU reference (golden)") {
  auto src = imported("ome-tiff/multi-channel-z-series.ome.tif", 32);
  REQUIRE(src->info().channels == 3);
  REQUIRE(src->info().dtype == DType::kI8);
  Case c;
  c.src = src.get();
  c.settings.model = OpticalModel::kMip;
  c.settings.step_voxels = 0.25;
  c.settings.channels.resize(3);
  const char* hues[3] = {"green", "magenta", "cyan"};
  for (int i = 0; i < 3; ++i) {
    c.settings.channels[i].colormap = hues[i];
    c.settings.channels[i].window_lo = 0;
    c.settings.channels[i].window_hi = 127;
  }
  c.camera = ome_camera();
  c.width = 440;
  c.height = 170;
  c.name = "brick_channels_ome";
  c.why = "OME-TIFF multi-channel z-series (439x167x5, 3 channels of signed int8) by MIP from below, window "
          "0..127, channels green, magenta, cyan added: the three ramps sum to grey-white, each channel's own "
          "label shows where the other two stay bright";
  // The printed text jumps by up to 255 units within one voxel; lavapipe's
  // 8-bit filter weights put up to 1/256 of such a jump in a sample, and the
  // 0..127 window doubles it: 3/255 at a text edge (measured at one pixel).
  c.reference_bound = 3;
  run(same_step(c));
}

TEST_CASE("brick features: a timepoint > 0 draws that timepoint's data (golden)") {
  auto src = imported("ome-tiff/multi-channel-time-series.ome.tif", 32);
  REQUIRE(src->info().timepoints == 7);
  Case c;
  c.src = src.get();
  c.channels = {1};  // one channel of three, picked like --channel 1
  c.settings.model = OpticalModel::kMip;
  c.settings.step_voxels = 0.25;
  c.settings.channels[0].window_lo = 0;
  c.settings.channels[0].window_hi = 127;
  c.settings.channels[0].colormap = "gray";
  c.camera = ome_camera();
  c.width = 440;
  c.height = 170;
  c.frame.lod.timepoint = 5;
  c.name = "brick_timepoint5";
  c.why = "OME-TIFF multi-channel time series, channel 1 at timepoint 5 drawn from below, window 0..127: the "
          "plane's printed label reads Channel = 2/3, Time point = 6/7 (1-based); matches the CPU reference on "
          "timepoint 5's voxels";
  const ImageRgba8 t5 = run(same_step(c));
  // Timepoint 0 of the same renderer setup is a different picture.
  test::GpuTestScope scope;
  auto r = renderer(*src, {1});
  BrickFrameSettings f;
  f.lod.force_level = 0;
  const ImageRgba8 t0 = converge(*r, c.camera, c.settings, f, c.width, c.height);
  CHECK(test::diff_images(t0, t5).differing > 0);
  f.lod.timepoint = 7;
  auto bad = r->render(c.camera, c.settings, f, c.width, c.height);
  REQUIRE_FALSE(bad.is_ok());
  CHECK(bad.status().message().find("timepoint 7") != std::string::npos);
}

TEST_CASE("brick features: u8 slots whose atlas of texel words outgrows one texel view with the driver's row "
          "padding sample their texels instead") {
  // 1 x 20 x 20 slots of 68^3: 503 MB of texel quads fit lavapipe's 512 MiB
  // view, its rows padded to 320 bytes (592 MB) do not. The pool keeps the
  // texels as they are and the rays sample them: the image is the sampler's.
  test::GpuTestScope scope;
  auto src = imported_as("mri64", 64, 2, [] { return std::make_unique<MemorySlabSource>(test::mri()); });
  const RenderSettings s = test::mri_settings(OpticalModel::kEmissionAbsorption, "gray");
  const Camera cam = test::mri_camera(test::mri());
  ImageRgba8 img[2];
  for (int views = 0; views < 2; ++views) {
    BrickRendererOptions o;
    o.pool.slots = {1, 20, 20};
    o.pool.texel_views = views == 1;
    auto r = BrickRenderer::create(test::gpu_context(), *src, o);
    REQUIRE_MESSAGE(r.is_ok(), r.status().to_string());
    CAPTURE(views);
    if (test::gpu_context().info().is_cpu()) CHECK_FALSE((*r)->pool().texel_words());
    if ((*r)->pool().texel_words()) return;  // a driver whose padded rows fit: nothing to fall back from
    img[views] = converge(**r, cam, s, {}, 96, 80);
  }
  CHECK(test::looks_non_blank(img[0]));
  CHECK(img[0].pixels == img[1].pixels);
}

TEST_CASE("brick features: direct writes into host-mapped atlases give the same images as the staging ring") {
  // lavapipe's memory is the host's: the pool writes bricks in place there
  // (no staging copy). Three kinds of slot: the chunk's own bytes (u8 and
  // four u8 channels), slots assembled from neighbours (apron 1 raised to 2
  // by gradient opacity), and converted texels (signed i8 -> float). A small
  // upload budget, so bricks arrive over many frames.
  test::GpuTestScope scope;
  REQUIRE(test::gpu_context().info().is_cpu());
  auto mri1 = mri(1);
  auto four = balls(false);
  auto i8 = imported("ome-tiff/z-series.ome.tif", 32);
  struct Scene {
    const ChunkSource* src;
    RenderSettings s;
    Camera cam;
    std::vector<uint32_t> channels;
  };
  RenderSettings grad = test::mri_settings(OpticalModel::kEmissionAbsorption, "gray");
  grad.gradient_opacity = {true, 0.02, 0.15};
  RenderSettings mip;
  mip.model = OpticalModel::kMip;
  mip.channels[0].window_lo = -64;
  mip.channels[0].window_hi = 127;
  RenderSettings additive;
  additive.model = OpticalModel::kEmission;
  additive.channels.resize(4);
  const char* maps[4] = {"red", "green", "blue", "yellow"};
  for (int k = 0; k < 4; ++k) additive.channels[k].colormap = maps[k];
  const Camera mri_cam = test::mri_camera(test::mri());
  for (const Scene& sc : {Scene{mri1.get(), grad, mri_cam, {}},
                          Scene{four.get(), additive, orbit_camera({{48, 48, 48}, {1, 1, 1}}, 20.0, 30.0, 1.1), {0, 1, 2, 3}},
                          Scene{i8.get(), mip, ome_camera(), {}}}) {
    CAPTURE(sc.src->info().dims[0]);
    ImageRgba8 img[2];
    for (int direct = 0; direct < 2; ++direct) {
      BrickRendererOptions o;
      o.pool.slots = {8, 8, 8};
      o.pool.channels = sc.channels;
      o.pool.direct_writes = direct == 1;
      o.pool.texel_views = false;  // the staging ring has none: both sample, so the atlases' bytes are compared
      auto r = BrickRenderer::create(test::gpu_context(), *sc.src, o);
      REQUIRE_MESSAGE(r.is_ok(), r.status().to_string());
      CHECK((*r)->pool().writes_direct() == (direct == 1));
      CAPTURE(direct);
      BrickFrameSettings f;
      f.upload_budget_bytes = 256 << 10;  // a few bricks per frame: many uploads, evictions between frames
      img[direct] = converge(**r, sc.cam, sc.s, f, 96, 80);
    }
    CHECK(test::looks_non_blank(img[0]));
    CHECK(img[0].pixels == img[1].pixels);
  }
}
