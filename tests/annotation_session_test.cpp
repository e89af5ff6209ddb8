// Annotations drawn by `vxr render` and `vxr view` through the one renderer:
// the eye renderer (every view target's) with an annotation scene, and the
// commands on a project, whose store they pick up, or with --annotations.
// With and without annotations the pictures differ exactly where markers are.
#include <doctest/doctest.h>

#include <cmath>
#include <cstring>

#include "annotate/annotation_store.h"
#include "assets/assets.h"
#include "cli_runner.h"
#include "core/image.h"
#include "core/output_file.h"
#include "gpu_fixture.h"
#include "render/annotation_renderer.h"
#include "render/volume_session.h"
#include "volume/dense_chunk_source.h"
#include "xr/eye_renderer.h"

using namespace vxr;
using namespace vxr::test;
using namespace vxr::xr;
namespace fs = std::filesystem;

namespace {

std::string q(const fs::path& p) { return shell_quote(p.string()); }

CliRun vxr_ok(const std::string& args, const fs::path& dir) {
  CliRun r = run_vxr(args, dir, 120);
  INFO("vxr " << args << "\nstdout: " << r.out << "\nstderr: " << r.err);
  REQUIRE(r.rc == 0);
  return r;
}

// Pixels of `a` and `b` (same size) that differ in any byte.
std::vector<bool> differing(const ImageRgba8& a, const ImageRgba8& b) {
  REQUIRE(a.width == b.width);
  REQUIRE(a.height == b.height);
  std::vector<bool> d(size_t(a.width) * a.height);
  for (size_t i = 0; i < d.size(); ++i) d[i] = std::memcmp(&a.pixels[i * 4], &b.pixels[i * 4], 4) != 0;
  return d;
}

// Pixels more than `margin` pixels (Chebyshev) from every covered one.
size_t changed_away_from(const std::vector<bool>& changed, const std::vector<float>& depth, uint32_t w, uint32_t h,
                         int margin) {
  size_t n = 0;
  for (uint32_t y = 0; y < h; ++y)
    for (uint32_t x = 0; x < w; ++x) {
      if (!changed[size_t(y) * w + x]) continue;
      bool near = false;
      for (int dy = -margin; dy <= margin && !near; ++dy)
        for (int dx = -margin; dx <= margin && !near; ++dx) {
          const int xx = int(x) + dx, yy = int(y) + dy;
          near = xx >= 0 && yy >= 0 && xx < int(w) && yy < int(h) && std::isfinite(depth[size_t(yy) * w + xx]);
        }
      n += near ? 0 : 1;
    }
  return n;
}

}  // namespace

TEST_CASE("annotations in the view path: an eye with markers differs from one without exactly where they are") {
  GpuTestScope scope;
  auto volume = assets::sample_volume();
  REQUIRE(volume.is_ok());
  std::vector<DenseVolume> channels{*volume};
  auto source = DenseChunkSource::create(std::move(channels));
  REQUIRE(source.is_ok());
  auto eyes = EyeRenderer::create(gpu_context(), *source);
  REQUIRE(eyes.is_ok());
  const xr::VolumeTransform t = default_volume_transform((*eyes)->placement());
  ViewSpec view;
  view.pose.position = {0.03, 1.62, -0.30};
  view.fov = {-0.785398, 0.698132, 0.785398, -0.785398};  // off-axis, like a headset eye
  view.width = view.height = 128;
  const Camera camera = camera_for_view(view, t);

  // Markers of the store kind, placed by voxel: one on the head's top slice, one deep inside, one outside.
  std::vector<annotate::Marker> markers(3);
  markers[0].pos = {93, 113, 26};
  markers[0].color = {1, 1, 0, 1};
  markers[1].pos = {60, 100, 13};
  markers[1].color = {1, 0, 0, 1};
  markers[2].pos = {93, 113, 40};
  markers[2].color = {0, 1, 0, 1};
  const AnnotationScene scene = annotation_scene(markers, {}, (*eyes)->placement(), 0, 10.0, 1.0);
  auto ar = AnnotationRenderer::create(gpu_context());
  REQUIRE(ar.is_ok());
  auto coverage = (*ar)->render(camera, scene, view.width, view.height);
  REQUIRE(coverage.is_ok());
  size_t covered = 0;
  for (float d : coverage->view_depth) covered += std::isfinite(d) ? 1 : 0;

  const RenderSettings s = default_view_settings();
  auto plain = (*eyes)->render(view, t, s, {});
  auto plain_warped = (*eyes)->render(view, t, s, {true, 0.5, 2});
  REQUIRE((*eyes)->set_annotations(scene).is_ok());
  auto with = (*eyes)->render(view, t, s, {});
  auto with_warped = (*eyes)->render(view, t, s, {true, 0.5, 2});
  for (auto* r : {&plain, &plain_warped, &with, &with_warped}) REQUIRE_MESSAGE(r->is_ok(), r->status().to_string());

  const std::vector<bool> changed = differing(*plain, *with);
  size_t changed_covered = 0, changed_elsewhere = 0;
  for (size_t i = 0; i < changed.size(); ++i)
    (std::isfinite(coverage->view_depth[i]) ? changed_covered : changed_elsewhere) += changed[i] ? 1 : 0;
  INFO("covered " << covered << ", changed there " << changed_covered << ", elsewhere " << changed_elsewhere);
  CHECK(covered > 60);
  CHECK(changed_elsewhere == 0);
  CHECK(changed_covered > covered * 9 / 10);  // a marker behind opaque tissue may not change its pixel

  // Lens warp: the outer bands' rays read the pixel they pass through; the
  // blit's bilinear stretch spreads a change by at most a couple of pixels.
  const std::vector<bool> changed_warped = differing(*plain_warped, *with_warped);
  size_t n_warped = 0;
  for (bool c : changed_warped) n_warped += c ? 1 : 0;
  INFO("lens warp: changed " << n_warped);
  CHECK(n_warped > covered / 2);
  CHECK(changed_away_from(changed_warped, coverage->view_depth, view.width, view.height, 2) == 0);

  // No annotations again: the plain picture.
  REQUIRE((*eyes)->set_annotations({}).is_ok());
  auto again = (*eyes)->render(view, t, s, {});
  REQUIRE(again.is_ok());
  CHECK(again->pixels == plain->pixels);
}

TEST_CASE("annotations: vxr render and vxr view draw a project's store, or the one --annotations names") {
  const fs::path dir = scratch_dir("annotations", "session");
  vxr_ok("project create " + q(dir / "head") + " --from " + q(std::string(VXR_TESTDATA_DIR) + "/tiff/mri-stack-calibrated.tif"),
         dir);
  const fs::path project = dir / "head.vxr", store = project / "annotations", volume = project / "volume.vxc";
  vxr_ok("annotate add-marker " + q(store) + " --pos 93,113,26 --color 1,1,0", dir);
  vxr_ok("annotate add-marker " + q(store) + " --pos 60,100,13 --color 1,0,0", dir);

  // Where the markers are: the annotation pass alone, with the camera the renders get.
  auto session = open_volume_session(volume.string(), {});
  REQUIRE_MESSAGE(session.is_ok(), session.status().to_string());
  CHECK(session->annotation_store.empty());  // a container alone has no store
  const VolumeInfo& info = session->source->info();
  const VolumePlacement placement{{uint32_t(info.dims[0]), uint32_t(info.dims[1]), uint32_t(info.dims[2])},
                                  info.voxel_size};
  auto project_session = open_volume_session(project.string(), {});
  REQUIRE(project_session.is_ok());
  CHECK(fs::equivalent(project_session->annotation_store, store));
  Camera camera;
  const glm::dvec3 extent = placement.extent();
  camera.eye = {0.3 * extent.x, -0.9 * extent.y, 1.6 * extent.z};
  camera.target = {0, 0, 0};
  camera.up = {0, 0, 1};
  camera.fov_y_deg = 45.0;
  const uint32_t w = 96, h = 80;
  std::vector<float> depth;
  {
    GpuTestScope scope;
    auto scene = load_annotation_scene(store.string(), placement, 0);
    REQUIRE_MESSAGE(scene.is_ok(), scene.status().to_string());
    CHECK(scene->spheres.size() == 2);
    auto ar = AnnotationRenderer::create(gpu_context());
    REQUIRE(ar.is_ok());
    auto cov = (*ar)->render(camera, *scene, w, h);
    REQUIRE(cov.is_ok());
    depth = cov->view_depth;
  }
  char cam[256];
  std::snprintf(cam, sizeof cam, " --size %ux%u --fov 45 --camera %.17g,%.17g,%.17g,0,0,0,0,0,1", w, h, camera.eye.x,
                camera.eye.y, camera.eye.z);
  vxr_ok("render " + q(project) + " -o " + q(dir / "with.png") + cam, dir);
  vxr_ok("render " + q(volume) + " -o " + q(dir / "without.png") + cam, dir);
  vxr_ok("render " + q(volume) + " --annotations " + q(store) + " -o " + q(dir / "named.png") + cam, dir);
  auto with = read_png((dir / "with.png").string());
  auto without = read_png((dir / "without.png").string());
  REQUIRE(with.is_ok());
  REQUIRE(without.is_ok());
  CHECK(read_bytes(dir / "with.png") == read_bytes(dir / "named.png"));  // the same store, found or named
  const std::vector<bool> changed = differing(*with, *without);
  size_t covered = 0, changed_covered = 0, changed_elsewhere = 0;
  for (size_t i = 0; i < changed.size(); ++i) {
    covered += std::isfinite(depth[i]) ? 1 : 0;
    (std::isfinite(depth[i]) ? changed_covered : changed_elsewhere) += changed[i] ? 1 : 0;
  }
  INFO("render: covered " << covered << ", changed there " << changed_covered << ", elsewhere " << changed_elsewhere);
  CHECK(covered > 10);
  CHECK(changed_elsewhere == 0);
  CHECK(changed_covered > covered / 2);

  // A card of a picture with annotations restores them: the same bytes.
  vxr_ok("render " + q(volume) + " --annotations " + q(store) + " -o " + q(dir / "card.png") + cam + " --save-card " +
             q(store),
         dir);
  vxr_ok("render --card 1 --annotations " + q(store) + " -o " + q(dir / "card_again.png"), dir);
  CHECK(read_bytes(dir / "card.png") == read_bytes(dir / "card_again.png"));
  CHECK(read_bytes(dir / "card.png") == read_bytes(dir / "with.png"));

  // vxr view --headless: the eye images show the markers too.
  vxr_ok("view " + q(project) + " --headless --frames 2 --width 96 --height 96 --png-dir " + q(dir / "view_with"), dir);
  vxr_ok("view " + q(volume) + " --headless --frames 2 --width 96 --height 96 --png-dir " + q(dir / "view_without"), dir);
  for (const char* eye : {"last_left.png", "last_right.png"}) {
    CAPTURE(eye);
    auto a = read_png((dir / "view_with" / eye).string());
    auto b = read_png((dir / "view_without" / eye).string());
    REQUIRE(a.is_ok());
    REQUIRE(b.is_ok());
    size_t n = 0;
    for (bool c : differing(*a, *b)) n += c ? 1 : 0;
    CHECK(n > 0);
    CHECK(n < size_t(96) * 96 / 10);  // only where markers are
  }

  // A store that is not there: one line naming it.
  CliRun bad = run_vxr("view " + q(volume) + " --headless --frames 1 --annotations " + q(dir / "nowhere"), dir);
  CHECK(bad.rc == 2);
  CHECK(bad.err.find("nowhere: no annotation store here") != std::string::npos);
  bad = run_vxr("render " + q(volume) + " --annotations " + q(dir / "nowhere") + " -o " + q(dir / "x.png"), dir);
  CHECK(bad.rc != 0);
  CHECK(bad.err.find("nowhere: no annotation store here") != std::string::npos);
  CHECK(!fs::exists(dir / "x.png"));
}

TEST_CASE("cards: vxr view --card restores a card's scene and draws its snapshot bit for bit") {
  const fs::path dir = scratch_dir("annotations", "view_card");
  vxr_ok("project create " + q(dir / "head") + " --from " + q(std::string(VXR_TESTDATA_DIR) + "/tiff/mri-stack-calibrated.tif"),
         dir);
  const fs::path project = dir / "head.vxr", store = project / "annotations";
  vxr_ok("annotate add-marker " + q(store) + " --pos 93,113,26 --color 1,1,0", dir);
  // A moved, turned and scaled volume seen from a chosen pose, with settings the defaults are not.
  const fs::path scene = dir / "scene.json";
  REQUIRE(write_file_atomically(scene.string(),
                                R"({"transform": {"position": [4, -6, 10], "rotation": [0.9, 0.1, 0.3, 0.2], "scale": 1.3},
                                    "camera": {"eye": [40, -120, 150], "target": [0, 0, 0], "up": [0, 0, 1], "fov_y_deg": 40}})")
              .is_ok());
  vxr_ok("render " + q(project) + " --settings " + q(scene) + " --colormap viridis --window 10,200 --step 0.75 " +
             "--size 88x72 -o " + q(dir / "card1.png") + " --save-card " + q(store),
         dir);
  // Another volume's card in the same store: channels 1 and 2 at timepoint 5 of a time series.
  vxr_ok("import " + q(std::string(VXR_TESTDATA_DIR) + "/ome-tiff/multi-channel-time-series.ome.tif") + " -o " +
             q(dir / "series.vxc"),
         dir);
  vxr_ok("render " + q(dir / "series.vxc") + " --timepoint 5 --channel 1,2 --model mip --size 64x48 -o " +
             q(dir / "card2.png") + " --save-card " + q(store),
         dir);

  std::string snapshots[3];
  {
    auto opened = annotate::AnnotationStore::open(store.string(), /*create=*/false);  // closed before the commands run
    REQUIRE(opened.is_ok());
    for (int id : {1, 2}) {
      auto card = (*opened)->card(annotate::Id(id), /*with_media=*/true);
      REQUIRE(card.is_ok());
      snapshots[id].assign(card->snapshot_png.begin(), card->snapshot_png.end());
      REQUIRE(!snapshots[id].empty());
    }
  }
  for (int id : {1, 2}) {
    CAPTURE(id);
    const std::string& snapshot = snapshots[id];
    const fs::path out = dir / ("view" + std::to_string(id));
    // Card 1 by ID of the project given as the input; card 2 by STORE:ID alone (the card names its volume).
    const std::string which = id == 1 ? q(project) + " --card 1" : "--card " + q(store.string() + ":2");
    vxr_ok("view " + which + " --headless --frames 2 --png-dir " + q(out), dir);
    CHECK(read_bytes(out / "last_view.png") == snapshot);
    vxr_ok("render " + which + " -o " + q(out / "render.png"), dir);
    CHECK(read_bytes(out / "render.png") == snapshot);
  }
  // The card of the annotated picture shows its marker: without the store the picture differs.
  vxr_ok("render " + q(project / "volume.vxc") + " --settings " + q(scene) +
             " --colormap viridis --window 10,200 --step 0.75 --size 88x72 -o " + q(dir / "bare.png"),
         dir);
  CHECK(read_bytes(dir / "bare.png") != read_bytes(dir / "card1.png"));

  // The card holds the settings: a flag that would change them is refused, in one line.
  CliRun bad = run_vxr("view " + q(project) + " --card 1 --headless --frames 1 --colormap gray", dir);
  CHECK(bad.rc == 2);
  CHECK(bad.err.find("--card restores the card's render settings") != std::string::npos);
  bad = run_vxr("view " + q(project) + " --card 7 --headless --frames 1", dir);
  CHECK(bad.rc == 2);
  CHECK(bad.err.find("no card 7") != std::string::npos);
  bad = run_vxr("view --card 1 --headless --frames 1", dir);  // no store to take ID from
  CHECK(bad.rc == 2);
  CHECK(bad.err.find("give STORE:ID") != std::string::npos);
}
