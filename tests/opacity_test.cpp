// Opacity per world unit (RenderSettings::opacity_unit_distance): a volume
// whose z voxels are twice as thick renders like the same field sampled on a
// grid twice as fine in z with cubic voxels, on the CPU reference and on the
// brick renderer; per-voxel opacity (the default) does not, which is why the
// setting exists. Also the shared flag parser of vxr render / vxr view.
#include <doctest/doctest.h>

#include <cmath>
#include <algorithm>
#include <fstream>

#include "cli_runner.h"
#include "core/image.h"
#include "golden.h"
#include "gpu_fixture.h"
#include "render/lod/brick_renderer.h"
#include "render/reference_renderer.h"
#include "render/transfer_function.h"
#include "render/volume_session.h"
#include "scene/render_settings.h"
#include "volume/dense_chunk_source.h"

using namespace vxr;

namespace {

// Two soft blobs in world units (box centred at 0, 32 x 32 x 32 world units):
// smooth on both grids, so trilinear reconstruction differs little between them.
double field(double x, double y, double z) {
  auto blob = [](double dx, double dy, double dz, double sigma) {
    return std::exp(-(dx * dx + dy * dy + dz * dz) / (2.0 * sigma * sigma));
  };
  return 0.8 * blob(x - 3, y + 2, z - 4, 6.0) + 0.6 * blob(x + 5, y - 4, z + 5, 4.5);
}

// The field on a 32 x 32 x (32 / vz) grid of voxels vz world units thick in z.
DenseVolume sampled(double vz) {
  DenseVolume v;
  v.dtype = DType::kF32;
  v.dims = {32, 32, uint32_t(std::lround(32.0 / vz))};
  v.voxel_size = {1.0, 1.0, vz};
  v.data.resize(v.byte_size());
  float* out = reinterpret_cast<float*>(v.data.data());
  for (uint32_t z = 0; z < v.dims[2]; ++z)
    for (uint32_t y = 0; y < v.dims[1]; ++y)
      for (uint32_t x = 0; x < v.dims[0]; ++x)
        *out++ = float(field(x + 0.5 - 16.0, y + 0.5 - 16.0, (z + 0.5) * vz - 16.0));
  return v;
}

RenderSettings world_settings(double unit_distance) {
  RenderSettings s;
  s.channels[0].window_lo = 0.0;
  s.channels[0].window_hi = 1.0;
  s.channels[0].colormap = "hot";
  s.density = 0.12;
  s.step_voxels = 0.25;
  s.opacity_unit_distance = unit_distance;
  return s;
}

// Oblique, with a large z component: the thick voxels matter along the ray.
Camera view() {
  Camera c;
  c.eye = {22.0, 18.0, 44.0};
  c.target = {0.0, 0.0, 0.0};
  c.up = {0.0, 1.0, 0.0};
  c.fov_y_deg = 40.0;
  return c;
}

ImageRgba8 reference(const DenseVolume& v, const RenderSettings& s) {
  auto img = render_reference(std::span(&v, 1), view(), s, 64, 64, {1.0 / 16.0, 1});
  REQUIRE(img.is_ok());
  return to_rgba8(*img);
}

ImageRgba8 bricks(const DenseVolume& v, const RenderSettings& s) {
  std::vector<DenseVolume> channels{v};
  auto src = DenseChunkSource::create(std::move(channels));
  REQUIRE(src.is_ok());
  BrickRendererOptions o;
  auto r = BrickRenderer::create(test::gpu_context(), **src, o);
  REQUIRE(r.is_ok());
  BrickFrameSettings f;
  f.lod.force_level = 0;
  BrickFrameStats st;
  for (int i = 0; i < 64; ++i) {
    auto img = (*r)->render(view(), s, f, 64, 64, &st);
    REQUIRE(img.is_ok());
    if (st.lod.missing == 0) return *img;
  }
  FAIL("the brick renderer did not converge in 64 frames");
  return {};
}

test::ImageDiff diff(const ImageRgba8& a, const ImageRgba8& b, const char* what) {
  const test::ImageDiff d = test::diff_images(a, b);
  MESSAGE(std::string(what) << ": max_abs " << d.max_abs << ", rmse " << d.rmse << ", differing " << d.differing);
  return d;
}

}  // namespace

TEST_CASE("opacity: voxels 1x1x2 with opacity per world unit render like the field at 1x1x1 (CPU reference)") {
  const DenseVolume thick = sampled(2.0), cubic = sampled(1.0);
  const ImageRgba8 a = reference(thick, world_settings(1.0)), b = reference(cubic, world_settings(1.0));
  CHECK(test::looks_non_blank(a));
  const test::ImageDiff world = diff(a, b, "world-unit opacity, 1x1x2 vs 1x1x1");
  CHECK(world.rmse <= 1.0);
  CHECK(world.max_abs <= 4);
  // Per voxel, the thick grid has half the voxels along z: visibly thinner.
  const test::ImageDiff voxel =
      diff(reference(thick, world_settings(0.0)), reference(cubic, world_settings(0.0)), "per-voxel opacity");
  CHECK(voxel.rmse >= 4.0 * std::max(world.rmse, 0.5));
}

TEST_CASE("opacity: a unit distance of one voxel on cubic voxels is the per-voxel image, bit for bit") {
  const DenseVolume cubic = sampled(1.0);
  CHECK(reference(cubic, world_settings(1.0)).pixels == reference(cubic, world_settings(0.0)).pixels);
  // Twice the unit distance: half the extinction, as density / 2 per voxel.
  RenderSettings half = world_settings(0.0);
  half.density /= 2.0;
  const test::ImageDiff d = diff(reference(cubic, world_settings(2.0)), reference(cubic, half), "D = 2 vs density / 2");
  CHECK(d.max_abs <= 1);
}

TEST_CASE("opacity: the brick renderer follows the same rule, within 2/255 of the CPU reference (golden)") {
  test::GpuTestScope scope;
  const DenseVolume thick = sampled(2.0), cubic = sampled(1.0);
  const RenderSettings s = world_settings(1.0);
  const ImageRgba8 gpu_thick = bricks(thick, s), gpu_cubic = bricks(cubic, s);
  CHECK(test::looks_non_blank(gpu_thick));
  const test::ImageDiff vs_ref = diff(gpu_thick, reference(thick, s), "GPU 1x1x2 vs CPU reference");
  CHECK(vs_ref.max_abs <= 2);
  const test::ImageDiff grids = diff(gpu_thick, gpu_cubic, "GPU 1x1x2 vs GPU 1x1x1");
  CHECK(grids.rmse <= 1.0);
  CHECK(grids.max_abs <= 4);
  auto g = test::check_golden("opacity_world_unit_1x1x2", gpu_thick, test::gpu_context().info().fingerprint(), 3,
                              "two soft blobs sampled on 1x1x2 voxels with opacity per world unit; the same picture "
                              "as the field on cubic voxels and as the CPU reference (opacity_test.cpp)");
  INFO(g.message);
  CHECK(g.passed);
}

TEST_CASE("opacity: the opacity flags become settings, and bad values are refused naming the flag") {
  SessionFlags f;
  f.opacity = "0.2:0.1,0.8:0.9";
  f.opacity_unit_distance = "2.5";
  RenderSettings s;
  REQUIRE(apply_opacity_flags(f, s).is_ok());
  CHECK(s.opacity_unit_distance == 2.5);
  const std::vector<OpacityPoint> ramp{{0.0, 0.0}, {0.2, 0.0}, {0.2, 0.1}, {0.8, 0.9}, {1.0, 0.9}};
  CHECK(s.channels[0].opacity_points == ramp);
  CHECK(validate_render_settings(s, 1).is_ok());

  auto vs = parse_voxel_size_flag("0.5,0.5,2");
  REQUIRE(vs.is_ok());
  REQUIRE(vs->has_value());
  CHECK(**vs == std::array<double, 3>{0.5, 0.5, 2.0});
  CHECK(!parse_voxel_size_flag("").value().has_value());

  for (const char* bad : {"1,1", "1,1,0", "1,-1,1", "1,1,nan", "1,1,inf", "1,1,2,3", "1,,2", "1,1,2,", "a,b,c"}) {
    auto r = parse_voxel_size_flag(bad);
    CHECK_MESSAGE(!r.is_ok(), bad);
    if (!r.is_ok()) CHECK(r.status().message().find("--voxel-size") != std::string::npos);
  }
  for (const char* bad : {"0.2:0.1", "0.8:0,0.2:1", "0:0,1:1.5", "-0.1:0,1:1", "0:0,1.2:1", "x:0,1:1", "0:0,1:"}) {
    SessionFlags g;
    g.opacity = bad;
    RenderSettings t;
    const Status st = apply_opacity_flags(g, t);
    CHECK_MESSAGE(!st.is_ok(), bad);
    if (!st.is_ok()) CHECK(st.message().find("--opacity") != std::string::npos);
  }
  for (const char* bad : {"-1", "nan", "inf", "x"}) {
    SessionFlags g;
    g.opacity_unit_distance = bad;
    RenderSettings t;
    CHECK_MESSAGE(!apply_opacity_flags(g, t).is_ok(), bad);
  }
  RenderSettings neg;
  neg.opacity_unit_distance = -1.0;
  CHECK(!validate_render_settings(neg, 1).is_ok());
}

TEST_CASE("opacity: vxr render and vxr view refuse a bad --voxel-size or --opacity with exit code 2") {
  const auto dir = test::scratch_dir("opacity", "flags");
  const std::string out = test::shell_quote((dir / "x.png").string());
  struct Case {
    std::string args, message;
  };
  for (const Case& c : std::vector<Case>{
           {"render procedural:vessels:64 -o " + out + " --voxel-size 1,0,1", "--voxel-size"},
           {"render procedural:vessels:64 -o " + out + " --opacity 0.5:0,0.2:1", "--opacity"},
           {"render procedural:vessels:64 -o " + out + " --opacity-unit-distance -3", "--opacity-unit-distance"},
           {"view --sample --headless --frames 1 --voxel-size 1,1,inf", "--voxel-size"},
           {"view --sample --headless --frames 1 --opacity 0:0,1:2", "--opacity"}}) {
    const test::CliRun r = test::run_vxr(c.args, dir, 120);
    INFO(c.args << "\nstderr: " << r.err);
    CHECK(r.rc == 2);
    CHECK(r.err.find(c.message) != std::string::npos);
    CHECK(std::count(r.err.begin(), r.err.end(), '\n') == 1);
  }
  CHECK(!std::filesystem::exists(dir / "x.png"));
}

TEST_CASE("opacity: vxr render applies --voxel-size and --opacity-unit-distance on the GPU and in the CPU reference") {
  const auto dir = test::scratch_dir("opacity", "render");
  // The blobs as a raw u8 volume with a JSON sidecar (cubic voxels in the file).
  const DenseVolume f = sampled(1.0);
  std::string bytes;
  for (size_t i = 0; i < f.voxel_count(); ++i)
    bytes.push_back(char(std::lround(255.0 * reinterpret_cast<const float*>(f.data.data())[i])));
  {
    std::ofstream(dir / "blobs.u8.raw", std::ios::binary) << bytes;
    std::ofstream(dir / "blobs.json") << R"({"file": "blobs.u8.raw", "dims": [32, 32, 32], "dtype": "u8", "voxel_size": [1, 1, 1]})";
  }
  const std::string in = test::shell_quote((dir / "blobs.json").string());
  auto render = [&](const std::string& name, const std::string& flags) {
    const std::string png = (dir / (name + ".png")).string();
    const test::CliRun r = test::run_vxr("render " + in + " -o " + test::shell_quote(png) +
                                             " --size 64x64 --window 0,255 --camera 22,18,44,0,0,0,0,1,0 " + flags,
                                         dir, 300);
    INFO(name << ": " << r.err);
    REQUIRE(r.rc == 0);
    auto img = read_png(png);
    REQUIRE(img.is_ok());
    return std::move(img).value();
  };
  for (const std::string base : {"--lod-bias -4 ", "--reference --reference-step 0.25 "}) {
    INFO(base);
    // Cubic voxels, one world unit: the per-voxel picture.
    CHECK(render("cubic", base).pixels == render("cubic_world", base + "--opacity-unit-distance 1").pixels);
    // Thick z voxels: world-unit opacity absorbs more along z than per-voxel opacity.
    const ImageRgba8 per_voxel = render("thick", base + "--voxel-size 1,1,2");
    const ImageRgba8 world = render("thick_world", base + "--voxel-size 1,1,2 --opacity-unit-distance 1");
    CHECK(diff(per_voxel, world, "1x1x2, per voxel vs per world unit").rmse >= 1.5);
    // The file's voxel size was overridden: the box is twice as deep, a different picture.
    CHECK(diff(render("cubic", base), per_voxel, "1x1x1 vs --voxel-size 1,1,2").rmse >= 2.0);
  }
}

TEST_CASE("opacity: a card keeps --voxel-size and the unit distance, and restores the same picture") {
  const auto dir = test::scratch_dir("opacity", "card");
  const std::string store = (dir / "store").string();
  REQUIRE(test::run_vxr("annotate init " + test::shell_quote(store), dir).rc == 0);
  const test::CliRun a = test::run_vxr("render procedural:vessels:64 -o " + test::shell_quote((dir / "a.png").string()) +
                                           " --size 64x48 --voxel-size 1,1,2.5 --opacity-unit-distance 0.75 --save-card " +
                                           test::shell_quote(store),
                                       dir, 300);
  INFO(a.err);
  REQUIRE(a.rc == 0);
  const test::CliRun b =
      test::run_vxr("render --card " + test::shell_quote(store + ":1") + " -o " + test::shell_quote((dir / "b.png").string()), dir, 300);
  INFO(b.err);
  REQUIRE(b.rc == 0);
  CHECK(test::read_bytes(dir / "a.png") == test::read_bytes(dir / "b.png"));
  // Without the card's voxel size the picture differs: the restore did use it.
  const test::CliRun c = test::run_vxr("render --card " + test::shell_quote(store + ":1") + " --voxel-size 1,1,1 -o " +
                                           test::shell_quote((dir / "c.png").string()),
                                       dir, 300);
  REQUIRE(c.rc == 0);
  CHECK(test::read_bytes(dir / "a.png") != test::read_bytes(dir / "c.png"));
  Scene sc;
  sc.voxel_size = {1.0, 1.0, 2.5};
  sc.render.opacity_unit_distance = 0.75;
  auto back = scene_from_json(scene_to_json(sc));
  REQUIRE(back.is_ok());
  CHECK(*back == sc);
  CHECK(!scene_from_json(R"({"voxel_size": [1, 0, 1]})").is_ok());
  CHECK(scene_from_json("{}").value().voxel_size == std::array<double, 3>{0, 0, 0});
}
