// Annotation imposters (engine/render/annotation_renderer.h): spheres and the
// cones tangent to them, ray-cast in a fragment shader over GPU-built guide
// boxes. Checked against an independent CPU reference (sphere tracing the
// exact distance to the convex hull of two spheres, in double), by goldens,
// and composited with the volume by the brick renderer (the underlay): rays
// end at the annotations' depth, checked against the CPU reference ended at
// the same depth.
#include <doctest/doctest.h>

#include <cmath>
#include <cstring>
#include <limits>

#include "golden.h"
#include "gpu_fixture.h"
#include "annotate/obj.h"
#include "render/annotation_renderer.h"
#include "render/lod/brick_renderer.h"
#include "render/reference_renderer.h"
#include "render_scenes.h"
#include "volume/dense_chunk_source.h"

using namespace vxr;

namespace {

// Distance from p to the convex hull of balls (a, ra) and (b, rb): the union
// of the balls swept between them, so min over s of |p - c(s)| - r(s), a
// convex function of s (ternary search is exact up to its tolerance).
double hull_distance(const glm::dvec3& p, const glm::dvec3& a, double ra, const glm::dvec3& b, double rb) {
  auto f = [&](double s) { return glm::length(p - (a + s * (b - a))) - (ra + s * (rb - ra)); };
  double lo = 0.0, hi = 1.0;
  for (int i = 0; i < 100; ++i) {
    const double m1 = lo + (hi - lo) / 3, m2 = hi - (hi - lo) / 3;
    (f(m1) < f(m2) ? hi : lo) = f(m1) < f(m2) ? m2 : m1;
  }
  return std::min({f(0.0), f(1.0), f(0.5 * (lo + hi))});
}

double scene_distance(const AnnotationScene& s, const glm::dvec3& p) {
  double d = std::numeric_limits<double>::infinity();
  for (const auto& sp : s.spheres) d = std::min(d, glm::length(p - sp.centre) - sp.radius);
  for (const auto& c : s.cones) d = std::min(d, hull_distance(p, c.a, c.ra, c.b, c.rb));
  return d;
}

// View depth of the first surface along each pixel's ray (the ray casters'
// pixel mapping), +inf where the ray misses.
std::vector<double> reference_depth(const Camera& cam, const AnnotationScene& s, uint32_t w, uint32_t h) {
  const PixelRays r = rays_in_world(cam, w, h);
  std::vector<double> out(size_t(w) * h, std::numeric_limits<double>::infinity());
  for (uint32_t y = 0; y < h; ++y)
    for (uint32_t x = 0; x < w; ++x) {
      const double nx = (2.0 * x + 1.0 - w) / w, ny = (2.0 * y + 1.0 - h) / h;
      const glm::dvec3 d = r.forward + nx * r.right - ny * r.up;
      const glm::dvec3 u = glm::normalize(d);
      double t = 0.0;
      for (int i = 0; i < 400 && t < 1e3; ++i) {
        const double dist = scene_distance(s, r.eye + t * u);
        if (dist < 1e-9) {
          out[size_t(y) * w + x] = t / glm::length(d);  // along d: view depth
          break;
        }
        t += dist;
      }
    }
  return out;
}

// Two traced branches of unequal radii, loose markers, one marker inside a cone.
AnnotationScene test_scene() {
  AnnotationScene s;
  const glm::vec4 cyan{0.2f, 0.8f, 1.0f, 1.0f}, yellow{1.0f, 0.9f, 0.1f, 1.0f}, red{1.0f, 0.2f, 0.2f, 1.0f};
  const glm::dvec3 n0{-0.6, -0.3, 0.0}, n1{0.0, 0.0, 0.1}, n2{0.55, 0.35, 0.0}, n3{0.1, -0.5, -0.2};
  const double r0 = 0.18, r1 = 0.1, r2 = 0.05, r3 = 0.03;
  for (auto [p, r] : {std::pair{n0, r0}, {n1, r1}, {n2, r2}, {n3, r3}}) s.spheres.push_back({p, r, cyan});
  s.cones.push_back({n0, n1, r0, r1, cyan});
  s.cones.push_back({n1, n2, r1, r2, cyan});
  s.cones.push_back({n1, n3, r1, r3, cyan});
  s.spheres.push_back({{0.5, -0.3, 0.3}, 0.12, yellow});
  s.spheres.push_back({{-0.3, 0.4, -0.3}, 0.08, red});
  return s;
}

Camera test_camera() {
  Camera c;
  c.eye = {0.4, -2.2, 1.0};
  c.target = {0.0, 0.0, 0.0};
  c.up = {0, 0, 1};
  c.fov_y_deg = 40.0;
  return c;
}

}  // namespace

TEST_CASE("annotations: imposter spheres and cones match the CPU reference in coverage and depth") {
  test::GpuTestScope scope;
  auto r = AnnotationRenderer::create(test::gpu_context());
  REQUIRE_MESSAGE(r.is_ok(), r.status().to_string());
  const AnnotationScene scene = test_scene();
  const uint32_t w = 96, h = 80;  // not square: the aspect is part of the mapping
  for (const Camera& cam : {test_camera(), [] {
         Camera c = test_camera();  // off-axis, like a headset eye
         c.frustum = FrustumTangents{-0.5, 0.3, -0.35, 0.45};
         return c;
       }()}) {
    auto img = (*r)->render(cam, scene, w, h);
    REQUIRE_MESSAGE(img.is_ok(), img.status().to_string());
    const std::vector<double> ref = reference_depth(cam, scene, w, h);
    size_t covered = 0, mismatched = 0;
    double worst = 0.0;
    for (size_t i = 0; i < ref.size(); ++i) {
      const bool gpu_hit = std::isfinite(img->view_depth[i]), cpu_hit = std::isfinite(ref[i]);
      CHECK((img->color.pixels[i * 4 + 3] > 0) == gpu_hit);
      if (gpu_hit != cpu_hit) {
        ++mismatched;  // a silhouette pixel whose centre grazes the surface
        continue;
      }
      if (!cpu_hit) continue;
      ++covered;
      worst = std::max(worst, std::abs(img->view_depth[i] - ref[i]) / ref[i]);
    }
    INFO("covered " << covered << ", mismatched " << mismatched << ", worst relative depth error " << worst);
    CHECK(covered > 600);
    CHECK(mismatched <= covered / 100);
    CHECK(worst < 1e-4);
  }
}

TEST_CASE("annotations: golden image of imposter spheres and tangent cones") {
  test::GpuTestScope scope;
  auto r = AnnotationRenderer::create(test::gpu_context());
  REQUIRE(r.is_ok());
  auto img = (*r)->render(test_camera(), test_scene(), 128, 128);
  REQUIRE(img.is_ok());
  const ImageRgba8 shown = over_black(img->color);
  CHECK(test::looks_non_blank(shown));
  auto g = test::check_golden("annotation_imposters", shown, test::gpu_context().info().fingerprint(), 3,
                              "a traced tree (cyan spheres of radii 0.18, 0.1, 0.05, 0.03 joined by their tangent "
                              "cones) and two loose markers, ray-cast per fragment, headlight shading; checked against "
                              "the CPU sphere-traced reference in the test above");
  CHECK_MESSAGE(g.passed, g.message);
}

TEST_CASE("meshes: OBJ files read with polygons, negative indices, groups as a hierarchy and line-numbered errors") {
  const std::string data = VXR_TESTDATA_DIR;
  auto ico = annotate::read_obj(data + "/obj/ico4.obj");
  REQUIRE_MESSAGE(ico.is_ok(), ico.status().to_string());
  CHECK(ico->mesh.positions.size() == 642);
  CHECK(ico->mesh.triangles.size() == 1280);
  REQUIRE(ico->mesh.parts.size() == 1);
  CHECK(ico->mesh.parts[0].name == "Icosphere_Icosphere.001");
  CHECK(ico->mesh.parts[0].triangle_count == 1280);
  REQUIRE(ico->mesh.materials.size() == 2);  // the default grey, then the file's
  CHECK(ico->mesh.materials[1].name == "None");
  CHECK(ico->mesh.materials[1].color[0] == doctest::Approx(0.8f));
  CHECK(ico->warnings.empty());
  // A unit sphere: every vertex one unit from the centroid.
  glm::dvec3 c(0.0);
  for (const auto& p : ico->mesh.positions) c += glm::dvec3(p[0], p[1], p[2]);
  c /= double(ico->mesh.positions.size());
  for (const auto& p : ico->mesh.positions) CHECK(glm::length(glm::dvec3(p[0], p[1], p[2]) - c) == doctest::Approx(1.0).epsilon(1e-4));

  auto cube = annotate::read_obj(data + "/obj/negative_indices.obj");
  REQUIRE_MESSAGE(cube.is_ok(), cube.status().to_string());
  CHECK(cube->mesh.positions.size() == 8);
  CHECK(cube->mesh.triangles.size() == 12);  // six quads, two triangles each
  for (const auto& t : cube->mesh.triangles)
    for (uint32_t v : t) CHECK(v < 8);

  auto tree = annotate::parse_obj("o tissue\nv 0 0 0\nv 1 0 0\nv 0 1 0\nv 0 0 1\ng cell_a\nf 1 2 3\ng cell_b\nf 1 2 4\n"
                                  "f 1 3 4\no tissue2\nf -4 -3 -1\nfoo bar\nfoo again\n",
                                  "t.obj", "");
  REQUIRE(tree.is_ok());
  const auto& parts = tree->mesh.parts;
  REQUIRE(parts.size() == 4);
  CHECK(parts[0].name == "tissue");
  CHECK(parts[0].triangle_count == 0);
  CHECK((parts[1].name == "cell_a" && parts[1].parent == 0 && parts[1].triangle_count == 1));
  CHECK((parts[2].name == "cell_b" && parts[2].parent == 0 && parts[2].triangle_count == 2));
  CHECK((parts[3].name == "tissue2" && parts[3].parent == -1 && parts[3].triangle_count == 1));
  REQUIRE(tree->warnings.size() == 1);  // one warning per unknown keyword
  CHECK(tree->warnings[0] == "t.obj:13: unknown keyword 'foo'; lines with it are skipped");

  CHECK(annotate::parse_obj("v 0 0 0\nv 1 0 0\nf 1 2 9\n", "bad.obj", "").status().message() ==
        "bad.obj:3: face vertex 9 is outside the 2 vertices read so far");
  CHECK(annotate::parse_obj("v 0 nan 0\n", "bad.obj", "").status().message() ==
        "bad.obj:1: vertex coordinate 'nan' is not a finite number");
  CHECK(annotate::parse_obj("v 0 0 0\n", "empty.obj", "").status().message() == "empty.obj: has no faces to draw");
  CHECK(annotate::read_obj("/nonexistent/x.obj").status().code() == ErrorCode::kNotFound);
}

// ---------------------------------------------------------------------------
// Volume and annotations through the one renderer: the brick renderer takes the
// annotations as an underlay (RenderTarget::under) recorded into its command
// buffer, ends its rays at their depth and composites their colour under the
// volume in its last pass.

namespace {

struct BrickHeadScene {
  DenseVolume volume = test::mri();
  std::shared_ptr<DenseChunkSource> source;
  std::unique_ptr<BrickRenderer> bricks;
  std::unique_ptr<AnnotationRenderer> annotations;
  Camera camera = test::mri_camera(volume);
  RenderSettings settings = test::mri_settings(OpticalModel::kEmissionAbsorption, "gray");
  BrickHeadScene() {
    auto s = DenseChunkSource::create({volume}, 32, 2);  // several bricks: the depth ends rays in any of them
    REQUIRE(s.is_ok());
    source = *s;
    BrickRendererOptions o;
    o.preload_if_fits = true;  // every brick resident from the first frame
    auto b = BrickRenderer::create(test::gpu_context(), *source, o);
    REQUIRE_MESSAGE(b.is_ok(), b.status().to_string());
    bricks = std::move(*b);
    auto a = AnnotationRenderer::create(test::gpu_context());
    REQUIRE(a.is_ok());
    annotations = std::move(*a);
  }
  // One frame with the scene as its underlay (empty scene: none), over black.
  ImageRgba8 render(const AnnotationScene* scene, uint32_t w, uint32_t h, BrickPassMode mode = BrickPassMode::kAuto) {
    BrickFrameSettings frame;
    frame.mode = mode;
    BrickFrameStats st;
    BrickRenderer::UnderlayRecorder under;
    if (scene)
      under = [&](VkCommandBuffer cmd) { return annotations->record(cmd, 0, camera, *scene, w, h); };
    auto img = bricks->render(camera, settings, frame, w, h, &st, under);
    REQUIRE_MESSAGE(img.is_ok(), img.status().to_string());
    CHECK(st.lod.missing == 0);
    return over_black(*img);
  }
  // The CPU reference on the same samples, its rays ended at the annotations'
  // depth, composited over their colour on the CPU.
  ImageRgba8 reference(const AnnotationImage& ann, uint32_t w, uint32_t h) const {
    ReferenceOptions ro{settings.step_voxels, 0};
    ro.grid_from_eye = true;
    ro.view_depth = ann.view_depth;
    auto vol = render_reference(std::span(&volume, 1), camera, settings, w, h, ro);
    REQUIRE(vol.is_ok());
    return over_black(composite_volume_over(*vol, ann.color));
  }
};

// Largest per-byte difference of two images of the same size.
int max_abs_diff(const ImageRgba8& a, const ImageRgba8& b) {
  int m = 0;
  for (size_t i = 0; i < a.pixels.size(); ++i) m = std::max(m, std::abs(int(a.pixels[i]) - int(b.pixels[i])));
  return m;
}

}  // namespace

TEST_CASE("annotations through the brick renderer: rays end at the markers, which composite under the volume") {
  test::GpuTestScope scope;
  BrickHeadScene head;
  const Camera& cam = head.camera;
  const uint32_t w = 128, h = 128;
  const VolumePlacement placement{head.volume.dims, head.volume.voxel_size};
  const PixelRays rays = rays_in_world(cam, w, h);
  const double centre = glm::length(cam.target - cam.eye), radius = 0.02 * glm::length(placement.extent());
  auto along = [&](double nx, double depth) { return rays.eye + depth * (rays.forward + nx * rays.right); };
  AnnotationScene scene;
  scene.spheres.push_back({along(-0.4, 0.35 * centre), radius, {1.0f, 0.2f, 0.2f, 1.0f}});  // in front
  scene.spheres.push_back({along(0.25, 1.0 * centre), radius, {1.0f, 0.2f, 0.2f, 1.0f}});   // inside the head

  auto ann = head.annotations->render(cam, scene, w, h);  // coverage, read back for the checks
  REQUIRE(ann.is_ok());
  const ImageRgba8 plain = head.render(nullptr, w, h);
  const ImageRgba8 with = head.render(&scene, w, h);
  // Exactly the pixels the markers cover change.
  size_t covered = 0, changed_covered = 0, changed_elsewhere = 0;
  for (size_t i = 0; i < size_t(w) * h; ++i) {
    const bool differs = std::memcmp(&plain.pixels[i * 4], &with.pixels[i * 4], 4) != 0;
    if (std::isfinite(ann->view_depth[i])) {
      ++covered;
      changed_covered += differs ? 1 : 0;
    } else {
      changed_elsewhere += differs ? 1 : 0;
    }
  }
  INFO("covered " << covered << ", changed there " << changed_covered << ", changed elsewhere " << changed_elsewhere);
  CHECK(covered > 100);
  CHECK(changed_elsewhere == 0);
  CHECK(changed_covered == covered);

  // The front marker shows its own red; the one inside is seen through the head.
  auto pixel_at = [&](const glm::dvec3& p) {
    const glm::dvec3 c = glm::inverse(glm::dmat3(rays.forward, rays.right, rays.up)) * (p - rays.eye);
    const uint32_t x = uint32_t((c.y / c.x + 1.0) * 0.5 * w), y = uint32_t((-c.z / c.x + 1.0) * 0.5 * h);
    return size_t(y) * w + x;
  };
  const uint8_t* pf = &with.pixels[pixel_at(scene.spheres[0].centre) * 4];
  const uint8_t* pi = &with.pixels[pixel_at(scene.spheres[1].centre) * 4];
  INFO("front " << int(pf[0]) << "," << int(pf[1]) << "," << int(pf[2]) << "  inside " << int(pi[0]) << ","
                << int(pi[1]) << "," << int(pi[2]));
  CHECK(pf[0] > 200);
  CHECK(pf[0] > pf[1] + 100);
  CHECK(int(pi[0]) - int(pi[1]) < int(pf[0]) - int(pf[1]) - 60);

  // Every pass mode ends the rays at the same depth: the same bytes.
  for (BrickPassMode mode : {BrickPassMode::kSinglePass, BrickPassMode::kTiled, BrickPassMode::kMultipass}) {
    CAPTURE(int(mode));
    CHECK(head.render(&scene, w, h, mode).pixels == with.pixels);
  }

  // The CPU reference, ended at the same depth: GPU filtering is all that differs.
  const int diff = max_abs_diff(head.reference(*ann, w, h), with);
  INFO("brick renderer vs CPU reference, max abs " << diff);
  CHECK(diff <= 2);

  auto g = test::check_golden("brick_annotation_markers_in_volume", with, test::gpu_context().info().fingerprint(), 3,
                              "annotation_markers_in_volume's scene through the brick renderer (32^3 bricks): the red "
                              "marker between the eye and the MRI head shown whole, the one inside the head seen "
                              "through the tissue in front of it; rays end at the markers' depth in the compute pass, "
                              "annotation colour composited under the volume there");
  CHECK_MESSAGE(g.passed, g.message);
}

TEST_CASE("annotations through the brick renderer: a mesh inside the volume stops the rays at its surface (golden)") {
  test::GpuTestScope scope;
  BrickHeadScene head;
  const uint32_t w = 128, h = 128;
  auto ico = annotate::read_obj(std::string(VXR_TESTDATA_DIR) + "/obj/ico4.obj");
  REQUIRE(ico.is_ok());
  glm::dvec3 c(0.0);
  for (const auto& p : ico->mesh.positions) c += glm::dvec3(p[0], p[1], p[2]);
  c /= double(ico->mesh.positions.size());
  const VolumePlacement placement{head.volume.dims, head.volume.voxel_size};
  const double radius = 0.12 * glm::length(placement.extent());
  AnnotationScene scene;
  scene.meshes.push_back(annotation_mesh(ico->mesh, -radius * c, radius));

  const ImageRgba8 plain = head.render(nullptr, w, h);
  const ImageRgba8 with = head.render(&scene, w, h);
  CHECK(std::memcmp(&plain.pixels[0], &with.pixels[0], 4) == 0);  // a corner sees no mesh
  const size_t mid = size_t(h / 2) * w + w / 2;
  CHECK(std::memcmp(&plain.pixels[mid * 4], &with.pixels[mid * 4], 4) != 0);

  auto ann = head.annotations->render(head.camera, scene, w, h);
  REQUIRE(ann.is_ok());
  // The centre pixel sees the sphere's near side: camera distance minus the
  // radius, to the mesh's flattening (subdivision 4: under 0.3% of the radius).
  const double expect = glm::length(head.camera.eye - head.camera.target) - radius;
  CHECK(std::abs(ann->view_depth[mid] - expect) < 0.01 * radius);
  CHECK(!std::isfinite(ann->view_depth[0]));
  const int diff = max_abs_diff(head.reference(*ann, w, h), with);
  INFO("brick renderer vs CPU reference, max abs " << diff);
  CHECK(diff <= 2);

  auto g = test::check_golden("brick_annotation_mesh_in_volume", with, test::gpu_context().info().fingerprint(), 3,
                              "annotation_mesh_in_volume's scene through the brick renderer (32^3 bricks): the ico4.obj "
                              "sphere centred in the MRI head, volume rays end at its surface in the compute pass, "
                              "the tissue in front of it composited over its grey");
  CHECK_MESSAGE(g.passed, g.message);
}
