// The desktop viewer's trace, track and ROI tools, the annotation list, movie
// export along camera keyframes, a card's camera restored in the window, and
// clicks through either eye of the side-by-side stereo window: the
// device-independent parts (ViewerTools, viewer_pick.h, viewer_movie.h) on
// their own, then scripted sessions under Xvfb checked on the store and on
// the screenshots' pixels.
#include <doctest/doctest.h>

#include <cmath>
#include <filesystem>
#include <fstream>

#include "annotate/annotation_store.h"
#include "core/image.h"
#include "xr/desktop/viewer_movie.h"
#include "xr/desktop/viewer_pick.h"
#include "xr/desktop/viewer_setup.h"
#include "xr/desktop/viewer_tools.h"
#include "xr/headless/movie.h"
#include "xr_test_util.h"

using namespace vxr;
using annotate::ToolAction;

namespace {

const std::string kMri = std::string(VXR_TESTDATA_DIR) + "/slices/mri-stack";
constexpr uint32_t kWidth = 480, kHeight = 360;

std::unique_ptr<annotate::AnnotationStore> fresh_store(const std::string& name) {
  const std::string dir = test::xr_out_dir(name) + "/store";
  auto s = annotate::AnnotationStore::open(dir, true);
  REQUIRE(s.is_ok());
  return std::move(s).value();
}

ImageRgba8 png(const std::string& path) {
  auto p = read_png(path);
  REQUIRE_MESSAGE(p.is_ok(), path);
  return std::move(p).value();
}

// Pixels of exactly (r, g, b) within `radius` of (cx, cy).
size_t colour_near(const ImageRgba8& img, double cx, double cy, int radius, uint8_t r, uint8_t g, uint8_t b) {
  size_t n = 0;
  for (int y = int(cy) - radius; y <= int(cy) + radius; ++y)
    for (int x = int(cx) - radius; x <= int(cx) + radius; ++x) {
      if (x < 0 || y < 0 || x >= int(img.width) || y >= int(img.height)) continue;
      const uint8_t* p = img.at(uint32_t(x), uint32_t(y));
      n += p[0] == r && p[1] == g && p[2] == b;
    }
  return n;
}

// Pixels of exactly (r, g, b) on the ring r0..r1 pixels from (cx, cy).
size_t colour_on_ring(const ImageRgba8& img, int cx, int cy, double r0, double r1, uint8_t r, uint8_t g, uint8_t b) {
  size_t n = 0;
  for (int y = cy - int(r1); y <= cy + int(r1); ++y)
    for (int x = cx - int(r1); x <= cx + int(r1); ++x) {
      const double d = std::hypot(x - cx, y - cy);
      const uint8_t* p = img.at(uint32_t(x), uint32_t(y));
      n += d >= r0 && d <= r1 && p[0] == r && p[1] == g && p[2] == b;
    }
  return n;
}

size_t differing(const ImageRgba8& a, const ImageRgba8& b) {
  size_t n = 0;
  for (size_t i = 0; i < a.pixels.size(); i += 4)
    n += a.pixels[i] != b.pixels[i] || a.pixels[i + 1] != b.pixels[i + 1] || a.pixels[i + 2] != b.pixels[i + 2];
  return n;
}

std::string viewer(const std::string& input, const std::string& script, const std::string& extra) {
  return test::own_config(std::filesystem::path(script).parent_path().string()) +
         "xvfb-run -a -s '-screen 0 1280x768x24' " + std::string(VXR_BINARY) + " view " + input +
         " --desktop --width " + std::to_string(kWidth) + " --height " + std::to_string(kHeight) + " --ui-script " +
         script + " " + extra;
}

}  // namespace

TEST_CASE("viewer tools: trace clicks chain nodes, a click on a node continues from it, finish starts a root") {
  auto store = fresh_store("viewer_tools_trace");
  REQUIRE(store->set_voxel_space({{0.5, 0.5, 2.0}, "um"}).is_ok());
  xr::ViewerTools tools(*store);
  REQUIRE(tools.trace_click({10, 10, 1}, 0).is_ok());
  REQUIRE(tools.trace_click({40, 10, 1}, 0).is_ok());   // 30 voxels along x: 15 um
  REQUIRE(tools.trace_click({40, 10, 9}, 0).is_ok());   // 8 along z: 16 um
  auto st = tools.status(0);
  REQUIRE(st.is_ok());
  CHECK(st->nodes == 3);
  CHECK(st->traced_length == doctest::Approx(31.0));
  const int64_t third = st->current_node;
  REQUIRE(tools.finish(0).is_ok());
  CHECK(tools.status(0)->current_node == annotate::kNoParent);
  const uint64_t revision = tools.revision();
  REQUIRE(tools.trace_click({41, 11, 1}, 0).is_ok());  // within the pick radius of node 2: picks it
  CHECK(tools.revision() == revision);                 // nothing stored
  REQUIRE(tools.trace_click({40, 40, 1}, 0).is_ok());  // a branch below node 2
  auto sk = store->skeleton(st->skeleton);
  REQUIRE(sk.is_ok());
  REQUIRE(sk->size() == 4);
  std::map<int64_t, int64_t> parent;
  for (const auto& [id, n] : sk->nodes()) parent[id] = n.parent;
  const int64_t first = sk->nodes().begin()->first;
  CHECK(parent[first] == annotate::kNoParent);
  int children_of_second = 0;
  for (const auto& [id, p] : parent) children_of_second += p == first + 1;
  CHECK(children_of_second == 2);  // the chain's third node and the branch
  CHECK(parent[third] == first + 1);
  // The list shows it with its length, and removing it drops it from the tool too.
  auto rows = tools.annotation_list();
  REQUIRE(rows.is_ok());
  REQUIRE(rows->size() == 1);
  CHECK(rows->front().kind == xr::AnnotationKind::kSkeleton);
  CHECK(rows->front().text.find("4 nodes, 46.000 um") != std::string::npos);  // 31 + 15 um
  REQUIRE(tools.remove(xr::AnnotationKind::kSkeleton, st->skeleton).is_ok());
  CHECK(tools.status(0)->skeleton == 0);
  REQUIRE(tools.trace_click({5, 5, 1}, 0).is_ok());  // a new skeleton, not an edit of the removed one
  CHECK(store->skeletons()->size() == 1);
  CHECK(tools.status(0)->nodes == 1);
}

TEST_CASE("viewer tools: track clicks link timepoints, an ROI drag counts the markers inside, remove takes a track whole") {
  auto store = fresh_store("viewer_tools_track");
  xr::ViewerTools tools(*store);
  REQUIRE(tools.track_click({10, 10, 1}, "cell", 0).is_ok());
  REQUIRE(tools.track_click({12, 11, 1}, "cell", 1).is_ok());
  REQUIRE(tools.track_click({15, 12, 1}, "cell", 3).is_ok());
  CHECK_FALSE(tools.track_click({15, 12, 1}, "cell", 3).is_ok());  // one marker per timepoint
  auto st = tools.status(3);
  REQUIRE(st.is_ok());
  CHECK(st->track != 0);
  CHECK(st->track_markers == 3);
  CHECK(st->first_timepoint == 0);
  CHECK(st->last_timepoint == 3);
  REQUIRE(tools.finish(3).is_ok());
  REQUIRE(tools.track_click({50, 50, 1}, "cell", 0).is_ok());  // a second track
  CHECK(store->tracks()->size() == 2);
  REQUIRE(tools.count({11, 10, 1}, "cell", 1).is_ok());

  REQUIRE(tools.roi_drag(ToolAction::kPress, {0, 0, 0}, 1).is_ok());
  REQUIRE(tools.roi_drag(ToolAction::kMove, {20, 20, 2}, 1).is_ok());
  CHECK(tools.status(1)->roi->id == 0);  // being dragged
  REQUIRE(tools.roi_drag(ToolAction::kRelease, {20, 20, 2}, 1).is_ok());
  st = tools.status(1);
  REQUIRE(st->roi.has_value());
  CHECK(st->roi->id != 0);
  CHECK(st->roi_markers == 2);  // at timepoint 1: the first track's and the count marker
  CHECK(tools.status(0)->roi_markers == 1);

  auto rows = tools.annotation_list();
  REQUIRE(rows.is_ok());
  size_t markers = 0, tracks = 0, rois = 0;
  for (const xr::AnnotationRow& r : *rows) {
    markers += r.kind == xr::AnnotationKind::kMarker;
    tracks += r.kind == xr::AnnotationKind::kTrack;
    rois += r.kind == xr::AnnotationKind::kRoi;
    if (r.kind == xr::AnnotationKind::kMarker) CHECK(r.group == "cell");
  }
  CHECK(markers == 5);
  CHECK(tracks == 2);
  CHECK(rois == 1);
  const annotate::Id first_track = store->tracks()->front().id;
  REQUIRE(tools.remove(xr::AnnotationKind::kTrack, first_track).is_ok());
  CHECK(store->tracks()->size() == 1);
  CHECK(store->markers()->size() == 2);  // its 3 markers went with it
  CHECK_FALSE(tools.remove(xr::AnnotationKind::kTrack, first_track).is_ok());
  REQUIRE(tools.remove(xr::AnnotationKind::kRoi, st->roi->id).is_ok());
  CHECK_FALSE(tools.status(1)->roi.has_value());
  CHECK(xr::annotation_kind_from_name("measurement") == xr::AnnotationKind::kMeasurement);
  CHECK_FALSE(xr::annotation_kind_from_name("cell").has_value());
}

TEST_CASE("viewer pick: a pixel and the voxel it shows map both ways, through either eye of a stereo window") {
  const VolumePlacement placement{{200, 100, 20}, {1.0, 1.0, 2.0}};
  const xr::VolumeTransform t = xr::default_volume_transform(placement);
  const xr::Pose head{glm::angleAxis(0.3, glm::dvec3(0, 1, 0)), t.to_reference({30, -20, 250})};
  const xr::Fov fov{-0.6, 0.5, 0.45, -0.4};
  const auto eyes = xr::stereo_views(head, 0.064, fov, 300, 200);
  const std::vector<xr::WindowView> views{{eyes[0], 0.0}, {eyes[1], 300.0}};
  CHECK(xr::view_at(views, 10) == 0u);
  CHECK(xr::view_at(views, 299.5) == 0u);
  CHECK(xr::view_at(views, 300) == 1u);
  CHECK_FALSE(xr::view_at(views, -1).has_value());
  const glm::dvec3 focus{5, 3, 1};
  for (size_t v = 0; v < 2; ++v)
    for (const auto& [x, y] : {std::pair{40.0, 30.0}, std::pair{150.0, 100.0}, std::pair{280.0, 190.0}}) {
      const double wx = views[v].x0 + x;
      const auto voxel = xr::voxel_under(views[v], t, placement, focus, wx, y);
      REQUIRE(voxel.has_value());
      const auto back = xr::project_voxel(views[v], t, placement, *voxel);
      REQUIRE(back.has_value());
      CHECK((*back)[0] == doctest::Approx(wx).epsilon(1e-9));
      CHECK((*back)[1] == doctest::Approx(y).epsilon(1e-9));
    }
  // The two eyes see one voxel at different pixels (parallax) and pick different voxels at one eye-pixel.
  const auto left = xr::voxel_under(views[0], t, placement, focus, 150, 100);
  const auto right = xr::voxel_under(views[1], t, placement, focus, 450, 100);
  CHECK(std::abs((*left)[0] - (*right)[0]) + std::abs((*left)[1] - (*right)[1]) + std::abs((*left)[2] - (*right)[2]) > 0.5);
  // A click within a few pixels of where a voxel is drawn picks it, whatever its depth, in the eye clicked only.
  const auto deep = xr::voxel_under(views[0], t, placement, glm::dvec3{5, 40, 1}, 60, 50);  // pixel (60, 50), deeper
  REQUIRE(deep.has_value());
  const std::vector<std::array<double, 3>> nodes{*deep, *left};
  CHECK(xr::nearest_on_screen(views[0], t, placement, nodes, 63, 48, 8.0) == 0u);
  CHECK(xr::nearest_on_screen(views[0], t, placement, nodes, 150, 100, 8.0) == 1u);
  CHECK_FALSE(xr::nearest_on_screen(views[0], t, placement, nodes, 72, 50, 8.0).has_value());
  CHECK_FALSE(xr::nearest_on_screen(views[1], t, placement, {*left}, 300 + 150, 100, 1.0).has_value());  // parallax
  // Looking mostly along the volume's -z: a dragged box spans z.
  const xr::Pose along_z{t.orientation, t.to_reference({0, 0, 300})};
  CHECK(xr::depth_axis({{along_z, fov, 300, 200}, 0.0}, t) == 2);
  CHECK(xr::on_volume_face({3, 4, 5}, 2, placement, true) == std::array<double, 3>{3, 4, 20});
  CHECK(xr::on_volume_face({3, 4, 5}, 0, placement, false) == std::array<double, 3>{0, 4, 5});
}

TEST_CASE("movie export: the path passes through each keyframe, frames go to checked outputs") {
  const std::string dir = test::xr_out_dir("viewer_movie_plan");
  const std::vector<xr::Pose> keys{{glm::dquat(1, 0, 0, 0), {0, 0, 1}},
                                   {glm::angleAxis(0.5, glm::dvec3(0, 1, 0)), {0.5, 0, 0.8}},
                                   {glm::angleAxis(1.0, glm::dvec3(0, 1, 0)), {0.8, 0.2, 0.3}}};
  const std::string inputs[] = {kMri};
  auto m = xr::MovieExport::start({dir + "/frames", 9, 30.0}, keys, inputs);
  REQUIRE(m.is_ok());
  for (const auto& [frame, key] : {std::pair{0, 0}, std::pair{4, 1}, std::pair{8, 2}}) {
    const xr::Pose p = m->pose(uint64_t(frame));
    CHECK(glm::length(p.position - keys[key].position) < 1e-12);
    CHECK(std::abs(std::abs(glm::dot(p.orientation, keys[key].orientation)) - 1.0) < 1e-12);
  }
  CHECK(glm::length(m->pose(2).position - keys[0].position) > 0.01);  // moving between keys
  auto f3 = m->frame_path(3);
  REQUIRE(f3.is_ok());
  CHECK(*f3 == dir + "/frames/frame-00003.png");
  CHECK(std::filesystem::is_directory(dir + "/frames"));
  CHECK_FALSE(xr::MovieExport::start({dir + "/x", 9, 30.0}, {keys[0]}, inputs).is_ok());  // one keyframe
  CHECK_FALSE(xr::MovieExport::start({dir + "/x", 2, 30.0}, keys, inputs).is_ok());       // fewer frames than keys
  // Outputs: never an input, never a file where the frames' folder should be, never a folder for an .mp4.
  std::ofstream(dir + "/file") << "x";
  CHECK_FALSE(xr::check_movie_output({dir + "/file", 9, 30.0}, inputs).is_ok());
  CHECK_FALSE(xr::check_movie_output({kMri, 9, 30.0}, inputs).is_ok());
  std::filesystem::create_directories(dir + "/folder.mp4");
  if (!xr::find_ffmpeg().empty()) {
    CHECK_FALSE(xr::check_movie_output({dir + "/folder.mp4", 9, 30.0}, inputs).is_ok());
    CHECK(xr::check_movie_output({dir + "/ok.mp4", 9, 30.0}, inputs).is_ok());
  }
}

TEST_CASE("desktop viewer: trace, track and ROI by mouse in a scripted session show in the store and the window") {
  const std::string dir = test::xr_out_dir("desktop_ui_trace");
  const std::string vxc = dir + "/ts.vxc";  // 7 timepoints: the track tool needs more than one
  const test::ChildResult import = test::run_child(std::string(VXR_BINARY) + " import " + std::string(VXR_TESTDATA_DIR) +
                                                   "/ome-tiff/multi-channel-time-series.ome.tif -o " + vxc);
  REQUIRE_MESSAGE(import.exit_code == 0, import.output);
  auto shot = [&](const std::string& name) { return dir + "/" + name + ".png"; };
  // Window pixels of the clicks (the volume fills the middle of the window).
  const double ax = 180, ay = 150, bx = 260, by = 150, cx = 260, cy = 210, dx = 320, dy = 210;
  const double px = 200, py = 190, qx = 300, qy = 170;
  const std::string script = dir + "/session.json";
  std::ofstream(script) << nlohmann::json::array({
                               "wait 2",
                               "ui off",
                               "screenshot " + shot("before"),
                               "tool trace",
                               "click 180 150",
                               "click 260 150",
                               "click 260 210",
                               "finish",
                               "click 180 150",  // on the first node: continue from it
                               "click 320 210",
                               "screenshot " + shot("traced"),
                               "tool track cell",
                               "click 200 190",
                               "time 1",
                               "click 300 170",
                               "wait 2",
                               "screenshot " + shot("tracked"),
                               "tool count",
                               "click 150 250",
                               "remove marker 3",
                               "tool roi",
                               "drag 170 160 330 230",
                               "screenshot " + shot("roi"),
                               "ui on",
                               "tool trace",
                               "screenshot " + shot("panel"),
                           })
                               .dump(1);
  const std::string store_dir = dir + "/store";
  REQUIRE(annotate::AnnotationStore::open(store_dir, true).is_ok());
  const test::ChildResult r = test::run_child(viewer(vxc, script, "--annotations " + store_dir));
  INFO(r.output);
  REQUIRE(r.exit_code == 0);  // validation is on: any Vulkan message would exit 3

  auto store = annotate::AnnotationStore::open(store_dir, false);
  REQUIRE(store.is_ok());
  // Trace: one skeleton of 4 nodes: A - B - C, and D below A (the click on A after finish picked it).
  auto skeletons = (*store)->skeletons();
  REQUIRE(skeletons.is_ok());
  REQUIRE(skeletons->size() == 1);
  auto sk = (*store)->skeleton(skeletons->front().id);
  REQUIRE(sk.is_ok());
  REQUIRE(sk->size() == 4);
  std::vector<annotate::SkeletonNode> nodes;
  for (const auto& [id, n] : sk->nodes()) nodes.push_back(n);
  CHECK(nodes[0].parent == annotate::kNoParent);
  CHECK(nodes[1].parent == nodes[0].id);
  CHECK(nodes[2].parent == nodes[1].id);
  CHECK(nodes[3].parent == nodes[0].id);
  // A and B lie on one screen row, B and C on one column: each pair differs along one volume axis.
  auto axes_moved = [](const annotate::Vec3& a, const annotate::Vec3& b) {
    int n = 0;
    for (int i = 0; i < 3; ++i) n += std::abs(a[i] - b[i]) > 1.0;
    return n;
  };
  CHECK(axes_moved(nodes[0].pos, nodes[1].pos) == 1);
  CHECK(axes_moved(nodes[1].pos, nodes[2].pos) == 1);
  // Track: markers at timepoints 0 and 1, linked; the count marker was removed from the list.
  auto tracks = (*store)->tracks();
  REQUIRE(tracks.is_ok());
  REQUIRE(tracks->size() == 1);
  REQUIRE(tracks->front().markers.size() == 2);
  auto p = (*store)->marker(tracks->front().markers[0]);
  auto q = (*store)->marker(tracks->front().markers[1]);
  REQUIRE(p.is_ok());
  REQUIRE(q.is_ok());
  CHECK(p->timepoint == 0);
  CHECK(q->timepoint == 1);
  CHECK(p->cls == "cell");
  CHECK((*store)->markers()->size() == 2);
  // ROI: one box spanning the dragged rectangle, holding the track's marker of timepoint 1 (the shown one).
  auto rois = (*store)->rois();
  REQUIRE(rois.is_ok());
  REQUIRE(rois->size() == 1);
  const annotate::Roi box = rois->front();
  MESSAGE("box " << box.min[0] << "," << box.min[1] << "," << box.min[2] << " - " << box.max[0] << "," << box.max[1]
                 << "," << box.max[2]);
  CHECK(box.contains(q->pos));
  CHECK(box.contains(p->pos));
  CHECK_FALSE(box.contains(nodes[0].pos));  // A at (180, 150) lies left of and above the box
  auto inside = (*store)->query(box, 1);
  REQUIRE(inside.is_ok());
  CHECK(inside->markers.size() == 1);

  // The window draws them: skeleton edges green between the nodes' pixels, the track's step magenta,
  // the box's edges cyan; none of those colours were there before.
  const ImageRgba8 before = png(shot("before")), traced = png(shot("traced")), tracked = png(shot("tracked")),
                   roi = png(shot("roi"));
  // An anti-aliased 2-pixel line has one row (or column) of exact colour: 11 pixels of it cross an 11 x 11 box.
  const auto green = [](const ImageRgba8& img, double x, double y) { return colour_near(img, x, y, 5, 0, 255, 0); };
  MESSAGE("green near the middle of A-B: before " << green(before, 220, 150) << ", traced " << green(traced, 220, 150));
  // (Compared with the same box before: the data may hold a few such pixels itself.)
  for (const auto& [x, y] : {std::pair{(ax + bx) / 2, (ay + by) / 2}, std::pair{(bx + cx) / 2, (by + cy) / 2},
                             std::pair{(ax + dx) / 2, (ay + dy) / 2}})
    CHECK_MESSAGE(green(traced, x, y) >= green(before, x, y) + 9, x << "," << y);
  const auto magenta = [](const ImageRgba8& img, double x, double y) { return colour_near(img, x, y, 5, 255, 0, 255); };
  MESSAGE("magenta near the track's step: before " << magenta(before, 250, 180) << ", tracked " << magenta(tracked, 250, 180));
  CHECK(magenta(tracked, (px + qx) / 2, (py + qy) / 2) >= magenta(before, (px + qx) / 2, (py + qy) / 2) + 9);
  CHECK(colour_near(tracked, qx, qy, 4, 255, 255, 0) >= 20);  // the track's marker at the shown timepoint: a yellow disc
  const auto cyan = [](const ImageRgba8& img, double x, double y) { return colour_near(img, x, y, 5, 0, 255, 255); };
  for (const auto& [x, y] : {std::pair{250.0, 160.0}, std::pair{250.0, 230.0}, std::pair{170.0, 195.0},
                             std::pair{330.0, 195.0}}) {
    CHECK_MESSAGE(cyan(roi, x, y) >= cyan(before, x, y) + 9, x << "," << y);
  }
  // The marker inside the box at the shown timepoint gets a cyan ring; the one of another timepoint does not.
  CHECK(colour_on_ring(tracked, int(qx), int(qy), 8, 12, 0, 255, 255) == 0);
  CHECK(colour_on_ring(roi, int(qx), int(qy), 8, 12, 0, 255, 255) >= 40);
  CHECK(colour_on_ring(roi, int(px), int(py), 8, 12, 0, 255, 255) == 0);
  // The panels came back over the same view.
  CHECK(differing(roi, png(shot("panel"))) > 1000);
}

TEST_CASE("desktop viewer: a movie exported along 3 keyframes starts at the window's first view and moves") {
  const std::string dir = test::xr_out_dir("desktop_ui_movie");
  auto shot = [&](const std::string& name) { return dir + "/" + name + ".png"; };
  const std::string frames = dir + "/frames";
  nlohmann::json steps = nlohmann::json::array({"wait 2", "ui off", "keyframe", "screenshot " + shot("key1"),
                                                "orbit 40 0", "keyframe", "orbit 30 25", "keyframe",
                                                "screenshot " + shot("key3"), "export-movie " + frames + " 9",
                                                "screenshot " + shot("after")});
  const bool mp4 = !xr::find_ffmpeg().empty();
  if (mp4) steps.push_back("export-movie " + dir + "/tour.mp4 4 10");
  const std::string script = dir + "/movie.json";
  std::ofstream(script) << steps.dump(1);
  const test::ChildResult r = test::run_child("VXR_LOG=info " + viewer(kMri, script, ""));
  INFO(r.output);
  REQUIRE(r.exit_code == 0);
  CHECK(r.output.find("viewer: movie " + frames + ": 9 frames") != std::string::npos);
  std::vector<ImageRgba8> movie;
  for (int i = 0;; ++i) {
    char name[32];
    std::snprintf(name, sizeof name, "/frame-%05d.png", i);
    if (!std::filesystem::exists(frames + name)) break;
    movie.push_back(png(frames + name));
  }
  REQUIRE(movie.size() == 9);
  for (const ImageRgba8& f : movie) {
    CHECK(f.width == kWidth);
    CHECK(f.height == kHeight);
  }
  for (size_t i = 1; i < movie.size(); ++i) CHECK_MESSAGE(differing(movie[i - 1], movie[i]) > 100, "frame " << i);
  // Frame 0 is the first keyframe's view and the last frame the last one's, as the window drew them
  // (the same renderer and settings; the window's panels were off).
  const size_t first = differing(movie.front(), png(shot("key1"))), last = differing(movie.back(), png(shot("key3")));
  MESSAGE("pixels differing: frame 0 vs the window at keyframe 1: " << first << ", last frame vs keyframe 3: " << last);
  CHECK(first == 0);
  CHECK(last == 0);
  // After the export the window is back at the orbit it left.
  CHECK(differing(png(shot("after")), png(shot("key3"))) == 0);
  if (mp4) {
    CHECK(std::filesystem::file_size(dir + "/tour.mp4") > 0);
    for (const auto& e : std::filesystem::directory_iterator(dir))  // the scratch frames are gone
      CHECK(e.path().filename().string().find(".frames.") == std::string::npos);
  }
}

TEST_CASE("desktop viewer: vxr view --card and the panel's restore put the window at the card's camera") {
  const std::string dir = test::xr_out_dir("desktop_ui_card_pose");
  const std::string store_dir = dir + "/store";
  // A card as vxr render saves it (card 1), then the same scene seen after a grab: a camera in world
  // units and a volume transform (card 2).
  REQUIRE(annotate::AnnotationStore::open(store_dir, true).is_ok());  // render --save-card adds to an existing store
  const test::ChildResult saved = test::run_child(std::string(VXR_BINARY) + " render " + kMri + " -o " + dir +
                                                  "/a.png --size 64x48 --save-card " + store_dir);
  REQUIRE_MESSAGE(saved.exit_code == 0, saved.output);
  {
    auto store = annotate::AnnotationStore::open(store_dir, false);
    REQUIRE(store.is_ok());
    auto first = (*store)->card(1, false);
    REQUIRE(first.is_ok());
    auto scene = scene_from_json(first->scene_json);
    REQUIRE(scene.is_ok());
    scene->has_camera = true;
    scene->camera.eye = {120, 80, 300};
    scene->camera.target = {10, -5, 3};
    scene->camera.up = {0, 1, 0};
    scene->camera.fov_y_deg = 35;
    scene->transform.position = {20, -10, 5};
    scene->transform.rotation = {std::cos(0.2), 0, std::sin(0.2), 0};  // 0.4 rad about y
    scene->transform.scale = 1.5;
    annotate::Card card;
    card.title = "posed";
    card.scene_json = scene_to_json(*scene);
    REQUIRE((*store)->add_card(card).is_ok());
  }
  const std::string script = dir + "/card.json";
  std::ofstream(script) << nlohmann::json::array(
                               {"wait 2", "panel-card at start", "orbit 60 20", "restore-card 2", "panel-card restored"})
                               .dump(1);
  const test::ChildResult r = test::run_child(viewer(kMri, script, "--annotations " + store_dir + " --card 2"));
  INFO(r.output);
  REQUIRE(r.exit_code == 0);
  auto store = annotate::AnnotationStore::open(store_dir, false);
  REQUIRE(store.is_ok());
  auto card_scene = [&](annotate::Id id) {
    auto c = (*store)->card(id, false);
    REQUIRE(c.is_ok());
    auto s = scene_from_json(c->scene_json);
    REQUIRE(s.is_ok());
    return *s;
  };
  const Scene original = card_scene(2);
  // The window draws the volume untransformed: the card's camera moved into the volume's frame.
  const CameraState expected = camera_in_volume_frame(original.camera, original.transform);
  for (annotate::Id id : {annotate::Id(3), annotate::Id(4)}) {
    const Scene saved = card_scene(id);
    INFO("card " << id);
    REQUIRE(saved.has_camera);
    for (int i = 0; i < 3; ++i) {
      CHECK(saved.camera.eye[i] == doctest::Approx(expected.eye[i]).epsilon(1e-6));
      CHECK(saved.camera.target[i] == doctest::Approx(expected.target[i]).epsilon(1e-6));
    }
    CHECK(saved.camera.fov_y_deg == doctest::Approx(35));
  }
}

TEST_CASE("desktop viewer: in the side-by-side stereo window a click picks through the eye clicked") {
  const std::string dir = test::xr_out_dir("desktop_ui_stereo");
  auto shot = [&](const std::string& name) { return dir + "/" + name + ".png"; };
  const std::string script = dir + "/stereo.json";
  // Eyes of 240 x 360: the right eye's pixel (150, 200) is window pixel (390, 200).
  std::ofstream(script) << nlohmann::json::array({"wait 2", "ui off", "screenshot " + shot("before"), "tool count",
                                                  "click 390 200", "click 110 140", "screenshot " + shot("clicked")})
                               .dump(1);
  const std::string store_dir = dir + "/store";
  REQUIRE(annotate::AnnotationStore::open(store_dir, true).is_ok());
  const test::ChildResult r = test::run_child(test::own_config(dir) + "xvfb-run -a -s '-screen 0 1280x768x24' " + std::string(VXR_BINARY) +
                                              " view " + kMri + " --desktop --stereo --width 240 --height 360 "
                                              "--ui-script " + script + " --annotations " + store_dir);
  INFO(r.output);
  REQUIRE(r.exit_code == 0);
  auto store = annotate::AnnotationStore::open(store_dir, false);
  REQUIRE(store.is_ok());
  REQUIRE((*store)->markers()->size() == 2);
  // Each marker is drawn in the eye clicked at the pixel clicked (a yellow disc centred there) ...
  const ImageRgba8 before = png(shot("before")), clicked = png(shot("clicked"));
  REQUIRE(clicked.width == 480);
  for (const auto& [x, y] : {std::pair{390.0, 200.0}, std::pair{110.0, 140.0}}) {
    CHECK_MESSAGE(colour_near(before, x, y, 4, 255, 255, 0) == 0, x);
    CHECK_MESSAGE(colour_near(clicked, x, y, 4, 255, 255, 0) >= 40, x);
  }
  // ... and in the other eye too, off by parallax: each eye shows both markers.
  size_t left = 0, right = 0;
  for (uint32_t y = 0; y < clicked.height; ++y)
    for (uint32_t x = 0; x < clicked.width; ++x) {
      const uint8_t* p = clicked.at(x, y);
      if (p[0] == 255 && p[1] == 255 && p[2] == 0) (x < 240 ? left : right)++;
    }
  MESSAGE("yellow pixels: left eye " << left << ", right eye " << right);
  CHECK(left > colour_near(clicked, 110, 140, 10, 255, 255, 0));  // the left eye shows the right eye's marker too
  CHECK(right > colour_near(clicked, 390, 200, 10, 255, 255, 0));
}
