// The first end-to-end ray caster, pinned by golden images of the bundled
// MRI head. Why the images are right: the head's outline and skull are
// visible from the front-left-above, MIP shows the brightest tissue (skull,
// scalp fat) and emission-absorption the hot-coloured surface; the same
// settings on u16 data (value * 257) give the same picture.
#include <doctest/doctest.h>

#include <cstring>

#include "assets/assets.h"
#include "golden.h"
#include "gpu_fixture.h"
#include "render/raycaster.h"

using namespace vxr;

namespace {

struct Scene {
  std::unique_ptr<Raycaster> caster;
  DenseVolume volume;
  Camera camera;
};

Scene make_scene(const DenseVolume& v) {
  Scene s;
  s.volume = v;
  auto caster = Raycaster::create(test::gpu_context());
  REQUIRE(caster.is_ok());
  s.caster = std::move(caster).value();
  REQUIRE(s.caster->set_volume(v).is_ok());
  s.camera = orbit_camera({v.dims, v.voxel_size}, 30.0, 25.0, 1.25);
  return s;
}

DenseVolume sample() {
  auto v = assets::sample_volume();
  REQUIRE(v.is_ok());
  return std::move(v).value();
}

DenseVolume to_u16(const DenseVolume& v8) {
  DenseVolume v = v8;
  v.dtype = DType::kU16;
  v.data.resize(v8.voxel_count() * 2);
  for (uint64_t i = 0; i < v8.voxel_count(); ++i) {
    const uint16_t x = static_cast<uint16_t>(v8.data[i] * 257);
    std::memcpy(&v.data[i * 2], &x, 2);
  }
  return v;
}

RaycastSettings settings(OpticalModel model) {
  RaycastSettings s;
  s.model = model;
  s.colormap = model == OpticalModel::kMip ? "gray" : "hot";
  s.window_lo = 20;
  s.window_hi = 220;
  s.step_voxels = 0.5;
  s.density = 0.08;
  return s;
}

void check(const std::string& name, const ImageRgba8& img, const std::string& why) {
  CHECK(test::looks_non_blank(img));
  auto r = test::check_golden(name, img, test::gpu_context().info().fingerprint(), 2, why);
  INFO(r.message);
  CHECK(r.passed);
}

}  // namespace

TEST_CASE("raycast: MIP of the MRI head (r8) matches its golden image") {
  test::GpuTestScope scope;
  Scene s = make_scene(sample());
  auto img = s.caster->render(s.camera, settings(OpticalModel::kMip), 160, 128);
  REQUIRE(img.is_ok());
  check("first_raycast_mip_r8", *img, "MIP, gray colormap, window 20..220: brightest tissue along each ray");
}

TEST_CASE("raycast: emission-absorption of the MRI head (r8) matches its golden image") {
  test::GpuTestScope scope;
  Scene s = make_scene(sample());
  auto img = s.caster->render(s.camera, settings(OpticalModel::kEmissionAbsorption), 160, 128);
  REQUIRE(img.is_ok());
  check("first_raycast_ea_r8", *img, "emission-absorption, hot colormap: the head surface, opaque where bright");
}

TEST_CASE("raycast: r16 data renders like the same values in r8") {
  test::GpuTestScope scope;
  const DenseVolume v8 = sample();
  Scene s8 = make_scene(v8);
  Scene s16 = make_scene(to_u16(v8));
  RaycastSettings st8 = settings(OpticalModel::kMip);
  RaycastSettings st16 = st8;
  st16.window_lo *= 257;
  st16.window_hi *= 257;
  auto a = s8.caster->render(s8.camera, st8, 96, 96);
  auto b = s16.caster->render(s16.camera, st16, 96, 96);
  REQUIRE(a.is_ok());
  REQUIRE(b.is_ok());
  // lavapipe filters 8-bit textures with 8-bit weights (up to 2/255 from exact,
  // ../shared/design/lavapipe.md); the window 20..220 stretches that by 255/200.
  CHECK(test::diff_images(*a, *b).max_abs <= 3);
  check("first_raycast_mip_r16", *b, "same MIP as first_raycast_mip_r8 on u16 data (value * 257)");
}

TEST_CASE("raycast: the same render twice is bit-identical") {
  test::GpuTestScope scope;
  Scene s = make_scene(sample());
  auto a = s.caster->render(s.camera, settings(OpticalModel::kEmissionAbsorption), 64, 64);
  auto b = s.caster->render(s.camera, settings(OpticalModel::kEmissionAbsorption), 64, 64);
  REQUIRE(a.is_ok());
  REQUIRE(b.is_ok());
  CHECK(a->pixels == b->pixels);
}

TEST_CASE("raycast: bad settings are refused with a reason") {
  test::GpuTestScope scope;
  Scene s = make_scene(sample());
  RaycastSettings bad = settings(OpticalModel::kMip);
  bad.step_voxels = 0;
  CHECK(s.caster->render(s.camera, bad, 8, 8).status().code() == ErrorCode::kInvalidArgument);
  bad = settings(OpticalModel::kMip);
  bad.window_lo = bad.window_hi;
  CHECK(s.caster->render(s.camera, bad, 8, 8).status().code() == ErrorCode::kInvalidArgument);
  bad = settings(OpticalModel::kMip);
  bad.colormap = "no-such-map";
  auto r = s.caster->render(s.camera, bad, 8, 8);
  CHECK(r.status().message().find("no-such-map") != std::string::npos);
}
