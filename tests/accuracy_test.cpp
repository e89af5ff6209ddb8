// Focused accuracy tests (issue 7): offset invariance, rays grazing box
// faces, positions from the step index on a long ray, and the 1,000-case
// subset of the numerical stress suite (tools/bench/stability.h).
#include <doctest/doctest.h>

#include <cmath>
#include <cstring>
#include <filesystem>
#include <set>

#include "assets/assets.h"
#include "bench/pareto.h"
#include "bench/stability.h"
#include "gpu_fixture.h"
#include "render/lod/brick_renderer.h"
#include "render/lod/memory_volume.h"
#include "render/reference_renderer.h"
#include "volume/container_reader.h"
#include "volume/memory_slab_source.h"
#include "volume/pyramid_builder.h"

using namespace vxr;

namespace {

// The one renderer over volumes in memory (64^3 bricks).
std::unique_ptr<MemoryVolumeRenderer> renderer_for(const DenseVolume& v) {
  auto r = MemoryVolumeRenderer::create(test::gpu_context(), {v});
  REQUIRE_MESSAGE(r.is_ok(), r.status().to_string());
  return std::move(r).value();
}

DenseVolume mri() {
  auto v = assets::sample_volume();
  REQUIRE(v.is_ok());
  return std::move(v).value();
}

double path_in_box(const VoxelSpaceRays& r, uint32_t w, uint32_t h, uint32_t x, uint32_t y, const glm::dvec3& box) {
  return length_in_box(r.eye, pixel_ray(r, w, h, x, y), box);
}

// A camera on a line where two coordinate planes meet (`b_at`, `c_at` in
// voxels), outside the box along axis a, looking along a with a 0.1 degree
// field of view: every ray stays within 0.07 voxel of those planes for 100
// voxels, so it grazes whatever faces lie in them.
Camera grazing_camera(int view, const glm::dvec3& box, double b_at, double c_at) {
  const int a = view % 3;
  const int b = (a + 1) % 3, c = (a + 2) % 3;
  glm::dvec3 eye_v(0.0);
  eye_v[a] = (view & 4) ? -8.0 : box[a] + 8.0;
  eye_v[b] = b_at;
  eye_v[c] = c_at;
  glm::dvec3 dir(0.0);
  dir[a] = (view & 4) ? 1.0 : -1.0;
  Camera cam;
  cam.eye = eye_v - 0.5 * box;
  cam.target = cam.eye + dir;
  cam.up = glm::dvec3(0.0);
  cam.up[b] = 1.0;
  cam.fov_y_deg = 0.1;
  return cam;
}

}  // namespace

TEST_CASE("accuracy: the same content at the origin and 2^20 voxels away differs by at most 1/255") {
  test::GpuTestScope scope;
  DenseVolume at_origin = mri();  // 186x226x27, voxel 1x1x5
  const VolumePlacement p0{at_origin.dims, at_origin.voxel_size};
  const Camera cam0 = orbit_camera(p0, 35.0, 25.0, 1.4);
  RenderSettings s;
  s.step_voxels = 0.5;
  auto img0 = renderer_for(at_origin)->render_float(cam0, s, 96, 96);
  REQUIRE(img0.is_ok());

  double coverage = 0.0;
  for (size_t i = 3; i < img0->rgba.size(); i += 4) coverage += img0->rgba[i] > 0.1f;
  CHECK(coverage > 96 * 96 * 0.2);  // the head fills the picture: there is something to compare

  for (const glm::dvec3 dir : {glm::dvec3(1, 0, 0), glm::dvec3(0.6, -0.48, 0.64), glm::dvec3(0, 0, -1)}) {
    DenseVolume far = at_origin;
    const double voxels = std::exp2(20.0);
    for (int a = 0; a < 3; ++a) far.origin[a] = dir[a] * voxels * far.voxel_size[a];
    const glm::dvec3 shift(far.origin[0], far.origin[1], far.origin[2]);
    Camera cam = cam0;
    cam.eye += shift;
    cam.target += shift;
    auto img = renderer_for(far)->render_float(cam, s, 96, 96);
    REQUIRE(img.is_ok());
    const double err = bench::max_abs_difference(*img0, *img);
    INFO("offset direction " << dir.x << "," << dir.y << "," << dir.z << ": max-abs " << err * 255.0 << "/255");
    CHECK(err <= 1.0 / 255.0);
  }
}

TEST_CASE("accuracy: world positions 2^20 voxels out lose the picture in float32, which is why placement is double") {
  // The control for the test above: composing the same placement in float
  // (what the GPU would do with world coordinates) moves the eye by up to
  // 2^20 * 2^-24 = 1/16 voxel per coordinate, enough to show in the image.
  const double world = std::exp2(20.0) + 0.3;
  const float as_float = static_cast<float>(world);
  CHECK(std::abs(double(as_float) - world) > 0.01);
  // In double the same coordinate is exact to 2^-32 voxel.
  CHECK(std::abs((world - std::exp2(20.0)) - 0.3) < 1e-9);
}

TEST_CASE("accuracy: no missed pixels among 10^6 rays grazing the faces of the box") {
  // A constant, fully windowed volume (value 255, opacity 1): every ray that
  // passes through the box's interior must come back with alpha 1 -
  // exp(-density * L), L its path length computed in double. The cameras look
  // along each axis from a face plane (rays at 0..1e-3 rad from the faces), so
  // most rays cross or touch a face at a grazing angle. A ray the double slab
  // test puts inside the box for at least one voxel must not come back empty.
  test::GpuTestScope scope;
  DenseVolume cube;
  cube.dims = {32, 32, 32};
  cube.data.assign(cube.voxel_count(), 255);
  auto renderer = renderer_for(cube);  // one brick
  RenderSettings s;
  s.density = 0.02;
  s.step_voxels = 1.0;
  s.early_termination = 0.0;
  const uint32_t w = 256, h = 256;
  uint64_t rays = 0, inside = 0, missed = 0, wrong = 0;
  const VolumePlacement p{cube.dims, cube.voxel_size};
  const glm::dvec3 box(32.0);
  for (int view = 0; view < 16; ++view) {
    // Eye on an edge line of the box (two coordinates on faces).
    const Camera cam = grazing_camera(view, box, (view & 8) ? 32.0 : 0.0, (view & 1) ? 16.0 : 0.0);
    auto img = renderer->render_float(cam, s, w, h);
    REQUIRE(img.is_ok());
    const VoxelSpaceRays r = rays_in_voxel_space(cam, p, w, h);
    for (uint32_t y = 0; y < h; ++y)
      for (uint32_t x = 0; x < w; ++x) {
        ++rays;
        const double length = path_in_box(r, w, h, x, y, box);
        const float alpha = img->rgba[(size_t(y) * w + x) * 4 + 3];
        if (!(length >= 1.0)) continue;
        ++inside;
        const double expected = -std::expm1(-0.02 * length);
        if (alpha <= 0.0f) ++missed;
        // Path lengths agree to float precision; a ray that lost or gained a
        // segment would be off by >= 0.02 * 1 voxel.
        if (std::abs(alpha - expected) > 2e-3) ++wrong;
      }
  }
  INFO("rays " << rays << ", inside " << inside << ", missed " << missed << ", wrong opacity " << wrong);
  CHECK(rays >= 1000000);
  CHECK(inside > rays / 4);
  CHECK(missed == 0);
  CHECK(wrong == 0);
}

TEST_CASE("accuracy: no missed pixels among 10^6 rays grazing the brick faces of the out-of-core renderer") {
  // The same check through the brick pool: a constant 64^3 volume in 16^3
  // chunks (4 x 4 x 4 bricks at level 0), drawn at full resolution. Each
  // camera sits where two planes of brick faces meet (x, y, z in {16, 32,
  // 48}, or a box face), so its rays run along the seams between bricks for
  // the whole volume: a ray the slab tests hand from brick to brick must
  // neither fall between two bricks (hole) nor be marched by both (double
  // opacity). Output is 8-bit, so opacity is checked to 1.5/255.
  test::GpuTestScope scope;
  namespace fs = std::filesystem;
  const fs::path dir = fs::temp_directory_path() / "vxr_accuracy_brick_faces";
  fs::remove_all(dir);
  fs::create_directories(dir);
  const std::string path = (dir / "constant.vxc").string();
  DenseVolume cube;
  cube.dims = {64, 64, 64};
  cube.data.assign(cube.voxel_count(), 255);
  MemorySlabSource slabs(cube);
  ImportOptions io;
  io.chunk_size = 16;
  REQUIRE(build_container(slabs, path, io).is_ok());
  auto reader = ContainerReader::open(path);
  REQUIRE(reader.is_ok());
  auto bricks = BrickRenderer::create(test::gpu_context(), **reader);
  REQUIRE(bricks.is_ok());
  BrickRenderer& renderer = **bricks;

  RenderSettings s;
  s.density = 0.02;
  s.step_voxels = 1.0;
  s.early_termination = 0.0;
  BrickFrameSettings f;
  f.lod.force_level = 0;
  f.lod.skip_empty = false;
  const uint32_t w = 256, h = 256;
  const glm::dvec3 box(64.0);
  const VolumePlacement p = renderer.placement();
  const double seams[] = {0.0, 16.0, 32.0, 48.0, 64.0};
  uint64_t rays = 0, inside = 0, missed = 0, wrong = 0, seams_crossed = 0;
  for (int view = 0; view < 16; ++view) {
    const Camera cam = grazing_camera(view, box, seams[1 + view % 3], seams[(view / 2) % 5]);
    BrickFrameStats st;
    ImageRgba8 img;
    for (int i = 0;; ++i) {
      auto frame = renderer.render(cam, s, f, w, h, &st);
      REQUIRE(frame.is_ok());
      img = std::move(*frame);
      if (st.lod.missing == 0) break;
      REQUIRE(i < 32);
    }
    seams_crossed += st.lod.drawn;
    const VoxelSpaceRays r = rays_in_voxel_space(cam, p, w, h);
    for (uint32_t y = 0; y < h; ++y)
      for (uint32_t x = 0; x < w; ++x) {
        ++rays;
        const double length = path_in_box(r, w, h, x, y, box);
        const double alpha = img.pixels[(size_t(y) * w + x) * 4 + 3] / 255.0;
        if (!(length >= 1.0)) continue;
        ++inside;
        if (alpha <= 0.0) ++missed;
        if (std::abs(alpha - -std::expm1(-0.02 * length)) > 1.5 / 255.0) ++wrong;

      }
  }
  fs::remove_all(dir);
  INFO("rays " << rays << ", inside " << inside << ", missed " << missed << ", wrong opacity " << wrong
               << ", bricks drawn over all views " << seams_crossed);
  CHECK(rays >= 1000000);
  CHECK(inside > rays / 4);
  CHECK(seams_crossed >= 16 * 4);  // every view marches several bricks
  CHECK(missed == 0);
  CHECK(wrong == 0);
}

TEST_CASE("accuracy: sample positions come from the step index: no drift along a 10,800-step ray") {
  // A 2x2x4096 float volume holding its own z coordinate up to z = 4000 (voxel
  // centres z + 0.5 hold z + 0.5, so trilinear filtering returns the sample's
  // z) and 0 beyond, seen straight down the z axis. MIP then returns the z of
  // the last sample before 3999.5, about 10,800 steps (dt = 0.37) into the
  // ray: a sample position read back directly. Positions t0 + (i + 1/2) dt are
  // exact to float rounding there; t += dt drifts by a large fraction of a voxel.
  test::GpuTestScope scope;
  const uint32_t cut = 4000;
  DenseVolume ramp;
  ramp.dims = {2, 2, 4096};
  ramp.dtype = DType::kF32;
  ramp.data.resize(ramp.voxel_count() * 4);
  for (uint32_t z = 0, i = 0; z < 4096; ++z)
    for (int k = 0; k < 4; ++k, ++i) {
      const float v = z < cut ? static_cast<float>(z + 0.5) : 0.0f;
      std::memcpy(&ramp.data[size_t(i) * 4], &v, 4);
    }
  auto renderer = renderer_for(ramp);  // 64 bricks along z
  Camera cam;  // world = voxel - dims/2: the eye 10 voxels below the box, looking up +z
  cam.eye = {0, 0, -2048.0 - 10.0};
  cam.target = {0, 0, 0};
  cam.up = {0, 1, 0};
  cam.fov_y_deg = 1.0;
  RenderSettings s;
  s.model = OpticalModel::kMip;
  s.channels[0].window_lo = 0.0;
  s.channels[0].window_hi = 4096.0;
  s.step_voxels = 0.37;
  s.max_steps = 1u << 20;

  // In double: samples at t = (i + 1/2) dt from the eye (z = t - 10, the
  // renderer's grid), the value the volume holds there, and the largest.
  const double dt = 0.37;
  auto value = [&](double z) {
    const double p = z - 0.5;  // trilinear along z between voxel centres
    const double f0 = std::floor(p);
    const double f = p - f0;
    auto at = [&](double k) { return k < 0 ? 0.5 : (k >= cut ? 0.0 : k + 0.5); };
    return at(f0) * (1 - f) + at(f0 + 1) * f;
  };
  double best = 0.0, best_z = 0.0;
  uint64_t best_i = 0;
  const uint64_t first = uint64_t(std::ceil(10.0 / dt - 0.5));  // the first sample in the box
  for (uint64_t i = first; (i + 0.5) * dt - 10.0 < 4096.0; ++i) {
    const double z = (i + 0.5) * dt - 10.0;
    if (value(z) > best) best = value(z), best_z = z, best_i = i;
  }
  CHECK(best_i > 10000);

  // The drifting alternative for comparison: float t accumulated step by step.
  float t_acc = static_cast<float>((first + 0.5) * dt);
  for (uint64_t i = first; i < best_i; ++i) t_acc += static_cast<float>(dt);
  const double drift = std::abs(double(t_acc) - 10.0 - best_z);
  INFO("accumulated float t drifts " << drift << " voxels over " << best_i << " steps");
  CHECK(drift > 0.05);  // so the check below would catch an accumulating marcher

  auto mip = renderer->render_float(cam, s, 1, 1);
  REQUIRE(mip.is_ok());
  // MIP alpha is the transfer function's opacity of the windowed max: value / 4096.
  const double got = double(mip->rgba[3]) * 4096.0;
  INFO("sample " << best_i << ": z read back " << got << ", exact " << best);
  CHECK(std::abs(got - best) < 0.01);
}

TEST_CASE("accuracy: stress cases are deterministic and cover every class") {
  const auto a = bench::make_stability_case(7, 123), b = bench::make_stability_case(7, 123);
  CHECK(a.volume.data == b.volume.data);
  CHECK(a.camera.eye == b.camera.eye);
  CHECK(a.settings == b.settings);
  const auto c = bench::make_stability_case(8, 123);
  CHECK((c.volume.data != a.volume.data || c.camera.eye != a.camera.eye));
  std::set<uint32_t> classes;
  for (uint32_t i = 0; i < 2 * bench::stability_classes().size(); ++i)
    classes.insert(bench::make_stability_case(1, i).class_index);
  CHECK(classes.size() == bench::stability_classes().size());
  // The hard cases are what they claim to be.
  for (uint32_t i = 0; i < 200; ++i) {
    const auto k = bench::make_stability_case(3, i);
    const std::string name = bench::stability_classes()[k.class_index].name;
    if (name == "zero_size") CHECK(k.volume.voxel_count() == 0);
    if (name == "one_voxel_thick")
      CHECK((k.volume.dims[0] == 1 || k.volume.dims[1] == 1 || k.volume.dims[2] == 1));
    if (name == "huge_offset") {
      const double voxels = std::abs(k.volume.origin[0] / k.volume.voxel_size[0]) +
                            std::abs(k.volume.origin[1] / k.volume.voxel_size[1]) +
                            std::abs(k.volume.origin[2] / k.volume.voxel_size[2]);
      CHECK(voxels >= 1024.0);
      CHECK(voxels <= 3.0 * std::exp2(24.0));
    }
    if (name == "fine_step") CHECK(k.settings.step_voxels <= 1.0 / 8.0 + 1e-12);
    if (name == "coarse_step") CHECK(k.settings.step_voxels >= 2.0);
  }
}

TEST_CASE("accuracy: 1,000 seeded stress cases: no NaN/Inf, every error within its class bound") {
  test::GpuTestScope scope;
  const auto& classes = bench::stability_classes();
  const auto pipelines = std::make_shared<BrickPipelines>();  // compiled once for every case
  std::vector<uint32_t> per_class(classes.size(), 0);
  uint32_t failures = 0;
  for (uint32_t i = 0; i < 1000; ++i) {
    const auto c = bench::make_stability_case(1, i);
    const auto o = bench::run_stability_case(test::gpu_context(), c, pipelines);
    ++per_class[c.class_index];
    if (!o.passed) {
      ++failures;
      if (failures <= 10)
        FAIL_CHECK("case " << i << " (" << classes[c.class_index].name << ", " << c.note << "): " << o.failure
                           << "; re-run: vxr bench stability --seed 1 --first " << i << " --cases 1");
    }
  }
  CHECK(failures == 0);
  for (size_t k = 0; k < classes.size(); ++k) CHECK(per_class[k] >= 50);
}

TEST_CASE("accuracy: the Pareto front keeps exactly the undominated points and prices the default against it") {
  using bench::TradeoffPoint;
  //                                   0: fast, bad  1: dominated by 0  2: mid      3: slow, good  4: tie in time, worse
  const std::vector<TradeoffPoint> p = {{1.0, 10.0}, {2.0, 12.0}, {3.0, 2.0}, {9.0, 0.5}, {3.0, 2.5}};
  const auto front = bench::pareto_front(p);
  REQUIRE(front.size() == 3);
  CHECK(front[0] == 0);
  CHECK(front[1] == 2);
  CHECK(front[2] == 3);
  // Point 4 (error 2.5) costs 3.0; the front reaches error <= 2.5 at time 3.0 (point 2): 0% over.
  CHECK(bench::front_time_at_error(p, front, 2.5) == doctest::Approx(3.0));
  // Point 1 (error 12) is matched by point 0 at time 1: it is 100% over the front.
  CHECK(bench::front_time_at_error(p, front, 12.0) == doctest::Approx(1.0));
  CHECK(std::isinf(bench::front_time_at_error(p, front, 0.1)));
}
