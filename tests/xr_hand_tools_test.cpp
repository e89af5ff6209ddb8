// The analysis tools driven by the hands (xr/hand_tools.h): the right
// trigger acts at the controller tip with hysteresis, the tip maps into voxels
// through any volume transform, the menu cycles tools, the left trigger
// removes; then end to end, headless (`vxr view --annotations` with a pose
// script) and through the OpenXR test runtime.
#include <doctest/doctest.h>

#include <cmath>
#include <cstring>
#include <filesystem>

#include "annotate/annotation_store.h"
#include "assets/assets.h"
#include "cli_runner.h"
#include "core/image.h"
#include "gpu_fixture.h"
#include "volume/dense_chunk_source.h"
#include "xr/hand_tools.h"
#include "xr/interaction.h"
#include "xr/openxr/openxr_target.h"
#include "xr/view_session.h"
#include "xr_test_util.h"

using namespace vxr;
using namespace vxr::xr;
using annotate::Tool;
namespace fs = std::filesystem;

namespace {

std::shared_ptr<annotate::AnnotationStore> fresh_store(const fs::path& p) {
  fs::remove_all(p);
  fs::create_directories(p.parent_path());
  auto s = annotate::AnnotationStore::open(p.string(), true);
  REQUIRE_MESSAGE(s.is_ok(), s.status().to_string());
  return std::shared_ptr<annotate::AnnotationStore>(std::move(s).value());
}

const VolumePlacement kPlacement{{64, 32, 16}, {0.5, 1.0, 2.0}};

// The volume 1 mm per unit, centred 0.5 m in front, axes as the reference's.
xr::VolumeTransform plain() {
  xr::VolumeTransform t;
  t.position = {0.0, 1.5, -0.5};
  t.scale = 0.001;
  return t;
}

// Right hand pointing along -z with its tip (5 cm along the ray) at `tip`.
InputState right_at(const glm::dvec3& tip, double trigger) {
  InputState s;
  s.hands[kLeft].tracked = s.hands[kRight].tracked = true;
  s.hands[kLeft].aim.position = {-0.3, 1.0, -0.2};  // well away from the volume
  s.hands[kRight].aim.position = tip + glm::dvec3(0, 0, 0.05);
  s.hands[kRight].trigger = trigger;
  return s;
}

// Volume-frame point (physical units, centred) -> voxel coordinates of kPlacement, by hand.
glm::dvec3 voxel_of(const glm::dvec3& w) {
  return {w.x / 0.5 + 32.0, w.y / 1.0 + 16.0, w.z / 2.0 + 8.0};
}

}  // namespace

TEST_CASE("hand tools: the right trigger presses above 0.6 and releases below 0.4, one marker per press") {
  auto store = fresh_store(fs::path(VXR_TEST_OUT_DIR) / "hand_tools" / "hysteresis");
  ViewerTools tools(*store);
  HandTools hands(tools, kPlacement);
  const xr::VolumeTransform t = plain();
  const glm::dvec3 tip{0.002, 1.503, -0.501};  // volume point (2, 3, -1) mm
  const double triggers[] = {0.0, 0.5, 0.59, 0.6, 0.5, 0.41, 0.9, 0.4, 0.55, 0.59, 0.61, 0.45, 0.3};
  const bool places[] = {false, false, false, true, false, false, false, false, false, false, true, false, false};
  for (size_t i = 0; i < std::size(triggers); ++i) {
    CAPTURE(triggers[i]);
    const HandToolFrame f = hands.update(right_at(tip, triggers[i]), t, 0);
    CHECK(f.stored == places[i]);
    CHECK(f.error.empty());
    if (f.stored) CHECK(f.hand == kRight);
  }
  auto markers = store->markers();
  REQUIRE(markers.is_ok());
  REQUIRE(markers->size() == 2);
  for (const annotate::Marker& m : *markers) {
    CHECK(m.cls == "cell");
    const glm::dvec3 v = voxel_of({2.0, 3.0, -1.0});
    CHECK(m.pos[0] == doctest::Approx(v.x).epsilon(1e-9));
    CHECK(m.pos[1] == doctest::Approx(v.y).epsilon(1e-9));
    CHECK(m.pos[2] == doctest::Approx(v.z).epsilon(1e-9));
  }
  CHECK(hands.report().find("tool count (cell): 2 counted") != std::string::npos);
}

TEST_CASE("hand tools: the tip maps to voxels through a scaled, turned, moved volume and a turned controller") {
  auto store = fresh_store(fs::path(VXR_TEST_OUT_DIR) / "hand_tools" / "mapping");
  ViewerTools tools(*store);
  HandToolSettings settings;
  settings.count_class = "nucleus";
  HandTools hands(tools, kPlacement, settings);
  xr::VolumeTransform t;
  t.position = {0.2, 1.4, -0.6};
  t.orientation = glm::angleAxis(0.7, glm::normalize(glm::dvec3(1, 2, 3)));
  t.scale = 0.004;
  const glm::dvec3 voxel{10.25, 20.5, 3.75};
  // Its reference position: centred physical units, scaled, turned, moved.
  const glm::dvec3 physical = (voxel - glm::dvec3(32, 16, 8)) * glm::dvec3(0.5, 1.0, 2.0);
  const glm::dvec3 reference = t.orientation * (0.004 * physical) + t.position;
  InputState in = right_at({0, 0, 0}, 0.0);
  // A controller turned 40 degrees about an oblique axis: the tip is 5 cm along ITS -z.
  in.hands[kRight].aim.orientation = glm::angleAxis(0.698, glm::normalize(glm::dvec3(-1, 1, 0.5)));
  in.hands[kRight].aim.position = reference - in.hands[kRight].aim.orientation * glm::dvec3(0, 0, -0.05);
  const glm::dvec3 got = hands.tip_voxel(in.hands[kRight], t);
  CHECK(glm::length(got - voxel) < 1e-9);
  hands.update(in, t, 3);
  in.hands[kRight].trigger = 1.0;
  REQUIRE(hands.update(in, t, 3).stored);
  auto markers = store->markers();
  REQUIRE(markers.is_ok());
  REQUIRE(markers->size() == 1);
  CHECK(glm::length(glm::dvec3((*markers)[0].pos[0], (*markers)[0].pos[1], (*markers)[0].pos[2]) - voxel) < 1e-9);
  CHECK((*markers)[0].timepoint == 3);
  CHECK((*markers)[0].cls == "nucleus");
}

TEST_CASE("hand tools: the menu button cycles count, measure, trace, track, roi, cut, once per press") {
  auto store = fresh_store(fs::path(VXR_TEST_OUT_DIR) / "hand_tools" / "menu");
  ViewerTools tools(*store);
  HandToolSettings settings;
  settings.tool = Tool::kTrace;
  HandTools hands(tools, kPlacement, settings);
  CHECK(hands.tool() == Tool::kTrace);
  CHECK(tools.palette().tool() == Tool::kTrace);
  InputState in = right_at({0.0, 1.5, -0.5}, 0.0);
  struct Step {
    Tool tool;
    bool cut;  // the cut plane (xr/cut_plane_tool.h) holds the triggers; tool() stays roi
  };
  const Step expected[] = {{Tool::kTrack, false}, {Tool::kRoi, false},   {Tool::kRoi, true},   {Tool::kCount, false},
                           {Tool::kMeasure, false}, {Tool::kTrace, false}, {Tool::kTrack, false}};
  for (const Step& want : expected) {
    in.hands[kRight].menu = true;
    CHECK(hands.update(in, plain(), 0).tool_changed);
    CHECK(hands.tool() == want.tool);
    CHECK(hands.cutting() == want.cut);
    CHECK(!hands.update(in, plain(), 0).tool_changed);  // held: no repeat
    CHECK(hands.tool() == want.tool);
    in.hands[kRight].menu = false;
    CHECK(!hands.update(in, plain(), 0).tool_changed);
  }
  in.hands[kLeft].menu = true;  // either hand's menu button
  CHECK(hands.update(in, plain(), 0).tool_changed);
  CHECK(hands.tool() == Tool::kRoi);
  CHECK(tools.palette().tool() == Tool::kRoi);
  CHECK(hands.report().rfind("tool roi", 0) == 0);
}

TEST_CASE("hand tools: the left trigger removes the marker nearest its tip, nothing near is refused") {
  auto store = fresh_store(fs::path(VXR_TEST_OUT_DIR) / "hand_tools" / "remove");
  ViewerTools tools(*store);
  HandTools hands(tools, kPlacement);
  const xr::VolumeTransform t = plain();
  for (const glm::dvec3& tip : {glm::dvec3(0.0, 1.5, -0.5), glm::dvec3(0.008, 1.5, -0.5)}) {
    hands.update(right_at(tip, 0.0), t, 0);
    REQUIRE(hands.update(right_at(tip, 1.0), t, 0).stored);
  }
  InputState in = right_at({0.0, 1.5, -0.5}, 0.0);
  in.hands[kLeft].aim.position = glm::dvec3(0.007, 1.5, -0.5) + glm::dvec3(0, 0, 0.05);  // 1 mm (2 voxels) from the second
  hands.update(in, t, 0);
  in.hands[kLeft].trigger = 0.8;
  const HandToolFrame removed = hands.update(in, t, 0);
  CHECK(removed.stored);
  CHECK(removed.hand == kLeft);
  CHECK(removed.error.empty());
  auto markers = store->markers();
  REQUIRE(markers.is_ok());
  REQUIRE(markers->size() == 1);
  CHECK((*markers)[0].pos[0] == doctest::Approx(32.0));  // the first one stays
  // Again, with nothing within the pick radius: refused, the store as it was.
  in.hands[kLeft].trigger = 0.0;
  hands.update(in, t, 0);
  in.hands[kLeft].trigger = 0.8;
  const HandToolFrame refused = hands.update(in, t, 0);
  CHECK(!refused.stored);
  CHECK(refused.error.find("no marker within") != std::string::npos);
  CHECK(store->markers()->size() == 1);
}

TEST_CASE("hand tools: measuring previews while held and stores the length on release, lost tracking drops it") {
  auto store = fresh_store(fs::path(VXR_TEST_OUT_DIR) / "hand_tools" / "measure");
  REQUIRE(store->set_voxel_space({{0.5, 1.0, 2.0}, "mm"}).is_ok());
  ViewerTools tools(*store);
  HandToolSettings settings;
  settings.tool = Tool::kMeasure;
  HandTools hands(tools, kPlacement, settings);
  const xr::VolumeTransform t = plain();
  const glm::dvec3 a{0.0, 1.5, -0.5}, b{0.003, 1.504, -0.5};  // 3 mm, 4 mm apart: 5 mm
  CHECK(!hands.update(right_at(a, 1.0), t, 0).stored);
  hands.update(right_at(0.5 * (a + b), 1.0), t, 0);
  REQUIRE(tools.palette().live().measuring.has_value());
  CHECK(tools.palette().live().measuring_length == doctest::Approx(2.5));
  AnnotationScene live;
  hands.add_live(right_at(0.5 * (a + b), 1.0), t, live);
  CHECK(live.cones.size() == 1);     // the segment being drawn
  CHECK(live.spheres.size() == 2);   // its fixed end and the tip cursor
  hands.update(right_at(b, 1.0), t, 0);
  const HandToolFrame done = hands.update(right_at(b, 0.3), t, 0);
  CHECK(done.stored);
  auto ms = store->measurements();
  REQUIRE(ms.is_ok());
  REQUIRE(ms->size() == 1);
  CHECK(store->length((*ms)[0]) == doctest::Approx(5.0).epsilon(1e-9));
  CHECK(hands.report().find("measurement 1: 5 mm") != std::string::npos);
  auto scene = hands.stored_scene(0);  // the measure tool shows what it stored
  REQUIRE(scene.is_ok());
  CHECK(scene->cones.size() == 1);

  // Tracking lost mid-drag: nothing stored, the drawing dropped.
  hands.update(right_at(a, 1.0), t, 0);
  InputState lost = right_at(b, 1.0);
  lost.hands[kRight].tracked = false;
  CHECK(!hands.update(lost, t, 0).stored);
  CHECK(!tools.palette().live().measuring.has_value());
  CHECK(!hands.update(right_at(b, 0.0), t, 0).stored);
  CHECK(store->measurements()->size() == 1);
}

TEST_CASE("hand tools: tracing chains a node per press, roi drags a box while held, drawn live, stored on release") {
  auto store = fresh_store(fs::path(VXR_TEST_OUT_DIR) / "hand_tools" / "trace_roi");
  ViewerTools tools(*store);
  HandToolSettings settings;
  settings.tool = Tool::kTrace;
  HandTools hands(tools, kPlacement, settings);
  const xr::VolumeTransform t = plain();
  const glm::dvec3 a{0.0, 1.5, -0.5}, b{0.004, 1.502, -0.498};
  for (const glm::dvec3& tip : {a, b}) {
    hands.update(right_at(tip, 0.0), t, 0);
    REQUIRE(hands.update(right_at(tip, 1.0), t, 0).stored);
  }
  auto skeletons = store->skeletons();
  REQUIRE(skeletons.is_ok());
  REQUIRE(skeletons->size() == 1);
  auto sk = store->skeleton((*skeletons)[0].id);
  REQUIRE(sk.is_ok());
  REQUIRE(sk->nodes().size() == 2);
  const annotate::SkeletonNode& first = sk->nodes().begin()->second;
  const annotate::SkeletonNode& second = std::next(sk->nodes().begin())->second;
  CHECK(first.parent == annotate::kNoParent);
  CHECK(second.parent == first.id);
  CHECK(second.pos[0] == doctest::Approx(32.0 + 8.0));  // 4 mm at 0.5 mm per voxel
  auto drawn = hands.stored_scene(0);
  REQUIRE(drawn.is_ok());
  CHECK(drawn->spheres.size() == 2);  // the nodes, as vxr render draws them
  CHECK(drawn->cones.size() == 1);    // and the edge between them

  InputState menu = right_at(b, 0.0);
  menu.hands[kRight].menu = true;
  hands.update(menu, t, 0);  // trace -> track
  hands.update(right_at(b, 0.0), t, 0);
  hands.update(menu, t, 0);  // track -> roi
  REQUIRE(hands.tool() == Tool::kRoi);
  hands.update(right_at(a, 0.0), t, 0);
  CHECK(!hands.update(right_at(a, 1.0), t, 0).stored);
  CHECK(!hands.update(right_at(b, 1.0), t, 0).stored);
  AnnotationScene live;
  hands.add_live(right_at(b, 1.0), t, live);
  CHECK(live.cones.size() == 12);  // the box's edges while it is dragged
  CHECK(hands.update(right_at(b, 0.0), t, 0).stored);
  auto rois = store->rois();
  REQUIRE(rois.is_ok());
  REQUIRE(rois->size() == 1);
  CHECK((*rois)[0].min[0] == doctest::Approx(32.0));
  CHECK((*rois)[0].max[0] == doctest::Approx(40.0));
  CHECK((*rois)[0].max[1] == doctest::Approx(18.0));
  CHECK((*rois)[0].max[2] == doctest::Approx(9.0));
}

TEST_CASE("hand tools: A picks the nearest traced node and the next node branches from it, B finishes the chain") {
  auto store = fresh_store(fs::path(VXR_TEST_OUT_DIR) / "hand_tools" / "pick_finish");
  ViewerTools tools(*store);
  HandToolSettings settings;
  settings.tool = Tool::kTrace;
  HandTools hands(tools, kPlacement, settings);
  const xr::VolumeTransform t = plain();
  // A chain a -> b -> c, 4 mm (8 voxels) apart along x.
  const glm::dvec3 a{0.0, 1.5, -0.5}, b{0.004, 1.5, -0.5}, c{0.008, 1.5, -0.5}, d{0.001, 1.504, -0.5},
      e{-0.006, 1.497, -0.5};
  auto press = [&](const glm::dvec3& tip) {
    hands.update(right_at(tip, 0.0), t, 0);
    return hands.update(right_at(tip, 1.0), t, 0);
  };
  auto button = [&](const glm::dvec3& tip, bool HandInput::*which) {
    InputState in = right_at(tip, 0.0);
    hands.update(in, t, 0);
    in.hands[kRight].*which = true;
    const HandToolFrame first = hands.update(in, t, 0);
    CHECK(!hands.update(in, t, 0).picked);  // held: no repeat
    return first;
  };
  for (const glm::dvec3& tip : {a, b, c}) REQUIRE(press(tip).stored);
  // A 1 mm (2 voxels) from a: a becomes the node the next one hangs below.
  const HandToolFrame picked = button(a + glm::dvec3(0.001, 0, 0), &HandInput::primary);
  CHECK(picked.picked);
  CHECK(!picked.stored);
  CHECK(picked.error.empty());
  CHECK(tools.palette().live().current_node == 1);
  CHECK(hands.report().find("last: tracing from node 1") != std::string::npos);
  // The node the branch will start from is drawn live (a ball bigger than the tip's cursor, at node 1 = a).
  auto current_node_balls = [&] {
    AnnotationScene live;
    hands.add_live(right_at({0.03, 1.5, -0.5}, 0.0), t, live);  // the tip outside the box: no cursor
    return live.spheres;
  };
  REQUIRE(current_node_balls().size() == 1);
  CHECK(glm::length(current_node_balls()[0].centre) < 1e-9);  // a is the volume's centre
  REQUIRE(press(d).stored);  // node 4, a branch below node 1
  REQUIRE(current_node_balls().size() == 1);  // now node 4
  CHECK(current_node_balls()[0].centre.y == doctest::Approx(4.0));
  // B: the chain is finished; the next press starts a new root.
  const HandToolFrame finished = button(d, &HandInput::secondary);
  CHECK(finished.picked);
  CHECK(tools.palette().live().current_node == annotate::kNoParent);
  CHECK(current_node_balls().empty());
  REQUIRE(press(e).stored);  // node 5, a root
  // A with no node within the pick radius is refused in one line; nothing changes.
  const HandToolFrame far = button({0.03, 1.5, -0.5}, &HandInput::primary);
  CHECK(!far.picked);
  CHECK(far.error.find("no traced node within") != std::string::npos);

  auto skeletons = store->skeletons();
  REQUIRE(skeletons.is_ok());
  REQUIRE(skeletons->size() == 1);
  auto sk = store->skeleton((*skeletons)[0].id);
  REQUIRE(sk.is_ok());
  REQUIRE(sk->nodes().size() == 5);
  const int64_t parents[] = {annotate::kNoParent, 1, 2, 1, annotate::kNoParent};
  for (int64_t id = 1; id <= 5; ++id) {
    CAPTURE(id);
    REQUIRE(sk->find(id) != nullptr);
    CHECK(sk->find(id)->parent == parents[id - 1]);
  }
  // The left hand's buttons do nothing (pick and finish belong to the tool hand).
  InputState left = right_at(a, 0.0);
  left.hands[kLeft].primary = left.hands[kLeft].secondary = true;
  CHECK(!hands.update(left, t, 0).picked);
}

TEST_CASE("hand tools: the trigger never grabs, the volume moves only on squeeze") {
  xr::VolumeTransform t = plain();
  GrabInteraction grab;
  InputState in = right_at({0.0, 1.5, -0.5}, 1.0);
  grab.update(in, t, 0.01);
  in.hands[kRight].aim.position += glm::dvec3(0.1, 0.1, 0.1);
  in.hands[kRight].grip.position += glm::dvec3(0.1, 0.1, 0.1);
  const auto started = grab.update(in, t, 0.01);
  CHECK(!started[kRight]);
  CHECK(!grab.grabbing(kRight));
  CHECK(t.position == plain().position);
  in.hands[kRight].grab = 1.0;  // squeeze: now it grabs
  CHECK(grab.update(in, t, 0.01)[kRight]);
}

// ---- end to end ----

namespace {

std::string q(const fs::path& p) { return test::shell_quote(p.string()); }

struct SampleFrame {
  VolumePlacement placement;
  double scale = 0.0;  // metres per volume unit of the default transform
};

SampleFrame sample_frame() {
  auto v = assets::sample_volume();
  REQUIRE(v.is_ok());
  SampleFrame f;
  f.placement = {v->dims, v->voxel_size};
  f.scale = 0.35 / glm::length(f.placement.extent());
  return f;
}

// The default transform by hand: centre (0, 1.6, -0.5), volume +z up, -y towards the viewer.
glm::dvec3 expected_voxel(const SampleFrame& f, const glm::dvec3& reference) {
  const glm::dvec3 d = reference - glm::dvec3(0.0, 1.6, -0.5);
  const glm::dvec3 w = glm::dvec3(d.x, -d.z, d.y) / f.scale;
  glm::dvec3 v;
  for (int i = 0; i < 3; ++i) v[i] = w[i] / f.placement.voxel_size[i] + 0.5 * f.placement.dims[i];
  return v;
}

std::string vec_json(const glm::dvec3& v) {
  char buf[128];
  std::snprintf(buf, sizeof buf, "[%.17g, %.17g, %.17g]", v.x, v.y, v.z);
  return buf;
}

const glm::dvec3 kP1{-0.03, 1.62, -0.47}, kP2{0.04, 1.57, -0.53};
const glm::dvec3 kTipOffset{0.0, 0.0, 0.05};  // the aim origin behind the tip (controllers point along -z)

// Count: press at P1, release, move to P2, press, release, take the hand out of the box.
std::string count_script(uint64_t base) {
  auto f = [&](uint64_t n) { return std::to_string(base + n); };
  return R"({"view": {"width": 160, "height": 160},
  "keys": [
    {"frame": 0, "head": {"position": [0, 1.6, -0.2], "orientation": [0, 0, 0, 1]},
     "right": {"aim": {"position": )" + vec_json(kP1 + kTipOffset) + R"(}, "trigger": 0}},
    {"frame": )" + f(2) + R"(, "right": {"trigger": 1}},
    {"frame": )" + f(4) + R"(, "right": {"trigger": 0}},
    {"frame": )" + f(6) + R"(, "right": {"aim": {"position": )" + vec_json(kP2 + kTipOffset) + R"(}}},
    {"frame": )" + f(8) + R"(, "right": {"trigger": 0.7}},
    {"frame": )" + f(10) + R"(, "right": {"trigger": 0.2}},
    {"frame": )" + f(12) + R"(, "right": {"aim": {"position": [0.15, 1.1, -0.3]}}}
  ]})";
}

std::vector<size_t> changed_pixels(const ImageRgba8& a, const ImageRgba8& b) {
  REQUIRE(a.width == b.width);
  REQUIRE(a.height == b.height);
  std::vector<size_t> out;
  for (size_t i = 0; i < size_t(a.width) * a.height; ++i)
    if (std::memcmp(&a.pixels[i * 4], &b.pixels[i * 4], 4) != 0) out.push_back(i);
  return out;
}

// Where `p` shows in the left eye of the count script's head (ipd 64 mm, +-40 degrees).
glm::dvec2 left_eye_pixel(const glm::dvec3& p, uint32_t size) {
  const glm::dvec3 eye{-0.032, 1.6, -0.2};
  const glm::dvec3 d = p - eye;
  const double t = std::tan(0.6981317), z = -d.z;
  return {0.5 * (d.x / (z * t) + 1.0) * size, 0.5 * (1.0 - d.y / (z * t)) * size};
}

}  // namespace

TEST_CASE("hand tools end to end: a headless pose script counts two markers where the right trigger pressed") {
  const fs::path dir = test::scratch_dir("hand_tools", "headless_count");
  const fs::path store = dir / "store";
  fresh_store(store);  // made, then closed: vxr view holds it
  std::ofstream(dir / "count.json") << count_script(0);
  const std::string common = "view --sample --headless --script " + q(dir / "count.json");
  test::CliRun with = test::run_vxr(common + " --annotations " + q(store) + " --png-dir " + q(dir / "with"), dir, 180);
  INFO("stdout: " << with.out << "\nstderr: " << with.err);
  REQUIRE(with.rc == 0);
  CHECK(with.out.find("vxr view: tool count (cell): 1 counted; last: marker 1 (cell)") != std::string::npos);
  CHECK(with.out.find("vxr view: tool count (cell): 2 counted; last: marker 2 (cell)") != std::string::npos);
  const SampleFrame frame = sample_frame();
  {
    auto opened = annotate::AnnotationStore::open(store.string(), false);
    REQUIRE(opened.is_ok());
    auto markers = (*opened)->markers();
    REQUIRE(markers.is_ok());
    REQUIRE(markers->size() == 2);
    const glm::dvec3 want[] = {expected_voxel(frame, kP1), expected_voxel(frame, kP2)};
    for (size_t i = 0; i < 2; ++i) {
      const annotate::Marker& m = (*markers)[i];
      const glm::dvec3 got(m.pos[0], m.pos[1], m.pos[2]);
      CAPTURE(i);
      CHECK(glm::length(got - want[i]) < 1e-3);  // well within a voxel
      CHECK(m.cls == "cell");
    }
  }

  // Without the store the eye differs only around the two markers.
  test::CliRun without = test::run_vxr(common + " --png-dir " + q(dir / "without"), dir, 180);
  REQUIRE(without.rc == 0);
  auto a = read_png((dir / "with" / "last_left.png").string());
  auto b = read_png((dir / "without" / "last_left.png").string());
  REQUIRE(a.is_ok());
  REQUIRE(b.is_ok());
  const std::vector<size_t> changed = changed_pixels(*a, *b);
  const glm::dvec2 at[] = {left_eye_pixel(kP1, 160), left_eye_pixel(kP2, 160)};
  size_t near[2] = {0, 0}, elsewhere = 0;
  for (size_t i : changed) {
    const glm::dvec2 px(double(i % 160) + 0.5, double(i / 160) + 0.5);
    bool counted = false;
    for (int k = 0; k < 2; ++k)
      if (glm::length(px - at[k]) < 6.0) {
        ++near[k];
        counted = true;
      }
    if (!counted) ++elsewhere;
  }
  INFO("changed " << changed.size() << ", near P1 " << near[0] << ", near P2 " << near[1] << ", elsewhere "
                  << elsewhere);
  CHECK(near[0] > 0);
  CHECK(near[1] > 0);
  CHECK(elsewhere == 0);
}

TEST_CASE("hand tools end to end: a headless measure run stores the measurement of the expected metric length") {
  const fs::path dir = test::scratch_dir("hand_tools", "headless_measure");
  const fs::path store = dir / "store";
  const SampleFrame frame = sample_frame();
  {
    auto s = fresh_store(store);
    const auto& vs = frame.placement.voxel_size;
    REQUIRE(s->set_voxel_space({{vs[0], vs[1], vs[2]}, "mm"}).is_ok());
  }
  // Press at P1, drag to P2 while held, release there.
  std::ofstream(dir / "measure.json") << R"({"view": {"width": 32, "height": 32},
  "keys": [
    {"frame": 0, "right": {"aim": {"position": )" + vec_json(kP1 + kTipOffset) + R"(}, "trigger": 0}},
    {"frame": 2, "right": {"trigger": 1}},
    {"frame": 8, "right": {"aim": {"position": )" + vec_json(kP2 + kTipOffset) + R"(}}},
    {"frame": 10, "right": {"trigger": 0}}
  ]})";
  test::CliRun r = test::run_vxr("view --sample --headless --tool measure --script " + q(dir / "measure.json") +
                                     " --annotations " + q(store),
                                 dir, 180);
  INFO("stdout: " << r.out << "\nstderr: " << r.err);
  REQUIRE(r.rc == 0);
  auto opened = annotate::AnnotationStore::open(store.string(), false);
  REQUIRE(opened.is_ok());
  auto ms = (*opened)->measurements();
  REQUIRE(ms.is_ok());
  REQUIRE(ms->size() == 1);
  // Metric length: the hands' distance in metres over metres per volume unit (mm here).
  const double expected = glm::length(kP2 - kP1) / frame.scale;
  CHECK((*opened)->length((*ms)[0]) == doctest::Approx(expected).epsilon(1e-6));
  char line[96];
  std::snprintf(line, sizeof line, "last: measurement 1: %.6g mm", expected);
  CHECK(r.out.find(line) != std::string::npos);

  // --tool/--class need a store; a wrong tool name is a usage error.
  test::CliRun bad = test::run_vxr("view --sample --headless --frames 1 --tool measure", dir, 60);
  CHECK(bad.rc == 2);
  CHECK(bad.err.find("--tool/--class: the tools edit an annotation store") != std::string::npos);
  bad = test::run_vxr("view --sample --headless --frames 1 --tool lasso --annotations " + q(store), dir, 60);
  CHECK(bad.rc == 2);
  CHECK(bad.err.find("lasso") != std::string::npos);
}

TEST_CASE("hand tools through the OpenXR test runtime: trigger presses place markers and pulse the haptics") {
  test::GpuTestScope scope;
  const std::string dir = test::xr_out_dir("hand_tools");
  // Later frames than headless: input is live once the session is FOCUSED.
  test::use_test_runtime(dir, count_script(10));
  auto v = assets::sample_volume();
  REQUIRE(v.is_ok());
  const VolumePlacement placement{v->dims, v->voxel_size};
  auto store = fresh_store(fs::path(dir) / "store");
  ViewOptions o;
  o.frames = 26;
  o.tool_store = store;
  std::vector<std::string> lines;
  o.on_tool_report = [&](const std::string& line) { lines.push_back(line); };
  auto source = DenseChunkSource::create({*v});
  REQUIRE(source.is_ok());
  const TargetFactory openxr = []() -> Result<std::unique_ptr<FrameTarget>> {
    auto t = OpenXrTarget::create({});
    if (!t) return t.status();
    return std::unique_ptr<FrameTarget>(std::move(t).value());
  };
  auto stats = run_view(openxr, *source, o, default_volume_transform(placement));
  REQUIRE_MESSAGE(stats.is_ok(), stats.status().to_string());
  CHECK(stats->pipelines_after_first_frame == 0);
  auto markers = store->markers();
  REQUIRE(markers.is_ok());
  REQUIRE(markers->size() == 2);
  const SampleFrame frame{placement, 0.35 / glm::length(placement.extent())};
  const glm::dvec3 want[] = {expected_voxel(frame, kP1), expected_voxel(frame, kP2)};
  for (size_t i = 0; i < 2; ++i) {
    const glm::dvec3 got((*markers)[i].pos[0], (*markers)[i].pos[1], (*markers)[i].pos[2]);
    CAPTURE(i);
    CHECK(glm::length(got - want[i]) < 1.0);  // OpenXR poses are float: within a voxel
  }
  REQUIRE(lines.size() == 2);
  CHECK(lines[1].find("2 counted") != std::string::npos);
  const nlohmann::json report = test::runtime_report(dir);
  REQUIRE(report.size() == 1);
  CHECK(report[0]["haptic_pulses"].get<int>() == 2);
  CHECK_MESSAGE(test::core_validation_messages(dir).empty(), test::core_validation_messages(dir));
}

// ---- tracing: a chain, a pick, a branch, a finish ----

namespace {

// Tips in the reference space, inside the sample at its default transform.
const glm::dvec3 kTrace[] = {{-0.03, 1.62, -0.47}, {0.0, 1.60, -0.50}, {0.04, 1.57, -0.53},
                             {-0.05, 1.65, -0.45}, {0.02, 1.66, -0.48}};
// Node n (1-based) hangs below kTraceParent[n - 1] (0: a root).
const int64_t kTraceParent[] = {0, 1, 2, 1, 0};

// Traces kTrace[0..2] as a chain, picks node 1 with `pick` (the script's name
// for the control the profile binds to pick), traces kTrace[3] (a branch below
// node 1), finishes with `finish`, traces kTrace[4] (a new root).
std::string trace_script(uint64_t base, const std::string& pick, const std::string& finish, int size,
                         const std::string& extra = "") {
  std::string keys;
  uint64_t frame = base;
  auto key = [&](const std::string& right) {
    keys += std::string(keys.empty() ? "" : ",\n") + R"({"frame": )" + std::to_string(frame) + R"(, "right": {)" +
            right + "}}";
    frame += 2;
  };
  auto aim = [&](const glm::dvec3& tip) { key(R"("aim": {"position": )" + vec_json(tip + kTipOffset) + "}"); };
  auto node = [&](const glm::dvec3& tip) {
    aim(tip);
    key(R"("trigger": 1)");
    key(R"("trigger": 0)");
  };
  for (int i = 0; i < 3; ++i) node(kTrace[i]);
  aim(kTrace[0]);
  key("\"" + pick + "\": true");
  key("\"" + pick + "\": false");
  node(kTrace[3]);
  key("\"" + finish + "\": true");
  key("\"" + finish + "\": false");
  node(kTrace[4]);
  return R"({"view": {"width": )" + std::to_string(size) + R"(, "height": )" + std::to_string(size) + "}" + extra +
         R"(, "keys": [)" + keys + "]}";
}

uint64_t trace_script_end(uint64_t base) { return base + 2 * 20; }  // 20 keys, 2 frames apart

// The store holds one skeleton of the five traced nodes, each where its tip
// was, hanging below the node kTraceParent says.
void check_traced(annotate::AnnotationStore& store, double tolerance_voxels) {
  auto skeletons = store.skeletons();
  REQUIRE(skeletons.is_ok());
  REQUIRE(skeletons->size() == 1);
  auto sk = store.skeleton((*skeletons)[0].id);
  REQUIRE(sk.is_ok());
  REQUIRE(sk->nodes().size() == 5);
  const SampleFrame frame = sample_frame();
  for (int64_t id = 1; id <= 5; ++id) {
    CAPTURE(id);
    const annotate::SkeletonNode* n = sk->find(id);
    REQUIRE(n != nullptr);
    CHECK(n->parent == (kTraceParent[id - 1] == 0 ? annotate::kNoParent : kTraceParent[id - 1]));
    const glm::dvec3 got(n->pos[0], n->pos[1], n->pos[2]);
    CHECK(glm::length(got - expected_voxel(frame, kTrace[id - 1])) < tolerance_voxels);
  }
}

}  // namespace

TEST_CASE("hand tools end to end: a headless pose script traces a chain, picks node 1 with A, branches, finishes with B") {
  const fs::path dir = test::scratch_dir("hand_tools", "headless_trace");
  const fs::path store = dir / "store";
  fresh_store(store);
  std::ofstream(dir / "trace.json") << trace_script(0, "a", "b", 32);
  test::CliRun r = test::run_vxr("view --sample --headless --tool trace --script " + q(dir / "trace.json") +
                                     " --annotations " + q(store),
                                 dir, 180);
  INFO("stdout: " << r.out << "\nstderr: " << r.err);
  REQUIRE(r.rc == 0);
  CHECK(r.out.find("vxr view: tool trace; last: tracing from node 1") != std::string::npos);
  CHECK(r.out.find("last: node 4 of skeleton 1 below node 1") != std::string::npos);
  CHECK(r.out.find("last: the next node starts a new branch root") != std::string::npos);
  CHECK(r.out.find("last: node 5 of skeleton 1 (a root)") != std::string::npos);
  auto opened = annotate::AnnotationStore::open(store.string(), false);
  REQUIRE(opened.is_ok());
  check_traced(**opened, 1e-3);
}

TEST_CASE("hand tools through the OpenXR test runtime: pick and finish reach the tracing tool on every profile with buttons") {
  test::GpuTestScope scope;
  auto v = assets::sample_volume();
  REQUIRE(v.is_ok());
  const VolumePlacement placement{v->dims, v->voxel_size};
  auto source = DenseChunkSource::create({*v});
  REQUIRE(source.is_ok());
  // The script's name for the physical control each profile binds to pick and to finish (actions.cpp).
  struct Case {
    const char* profile;
    const char* pick;
    const char* finish;
  };
  const Case cases[] = {{"oculus/touch_controller", "a", "b"},
                        {"valve/index_controller", "a", "b"},
                        {"htc/vive_controller", "thumbstick_click", "menu"},
                        {"microsoft/motion_controller", "trackpad_click", "menu"}};
  for (const Case& c : cases) {
    INFO(c.profile);
    const std::string dir = test::xr_out_dir(std::string("trace_") + (std::strchr(c.profile, '/') + 1));
    test::use_test_runtime(dir, trace_script(10, c.pick, c.finish, 16,
                                             std::string(R"(, "profile": "/interaction_profiles/)") + c.profile + "\""));
    auto store = fresh_store(fs::path(dir) / "store");
    ViewOptions o;
    o.frames = trace_script_end(10) + 2;
    o.tool_store = store;
    o.hand_tools.tool = Tool::kTrace;
    std::vector<std::string> lines;
    o.on_tool_report = [&](const std::string& line) { lines.push_back(line); };
    const TargetFactory openxr = []() -> Result<std::unique_ptr<FrameTarget>> {
      auto t = OpenXrTarget::create({});
      if (!t) return t.status();
      return std::unique_ptr<FrameTarget>(std::move(t).value());
    };
    auto stats = run_view(openxr, *source, o, default_volume_transform(placement));
    REQUIRE_MESSAGE(stats.is_ok(), stats.status().to_string());
    check_traced(*store, 1.0);  // OpenXR poses are float: within a voxel
    // Five nodes, a pick and a finish: each a line and a haptic click.
    REQUIRE(lines.size() == 7);
    CHECK(lines[3].find("tracing from node 1") != std::string::npos);
    CHECK(lines[5].find("the next node starts a new branch root") != std::string::npos);
    const nlohmann::json report = test::runtime_report(dir);
    REQUIRE(report.size() == 1);
    CHECK(report[0]["haptic_pulses"].get<int>() == 7);
    CHECK_MESSAGE(test::core_validation_messages(dir).empty(), test::core_validation_messages(dir));
  }
}
