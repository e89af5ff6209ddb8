// The analysis tools as device-independent logic (engine/annotate/tools.h)
// and their JSON event scripts (tool_script.h): every edit lands in the store,
// the live state follows the cursor, and a refused edit changes nothing.
#include <doctest/doctest.h>

#include <cmath>
#include <filesystem>

#include "annotate/annotation_store.h"
#include "annotate/tool_script.h"
#include "annotate/tools.h"

using namespace vxr;
using namespace vxr::annotate;
namespace fs = std::filesystem;

namespace {

std::unique_ptr<AnnotationStore> fresh_store(const std::string& name) {
  const fs::path p = fs::path(VXR_TEST_OUT_DIR) / "annotate_tools" / name;
  fs::remove_all(p);
  fs::create_directories(p.parent_path());
  auto s = AnnotationStore::open(p.string(), true);
  REQUIRE_MESSAGE(s.is_ok(), s.status().to_string());
  return std::move(*s);
}

ToolEvent ev(ToolAction a, Vec3 p, uint32_t t = 0) { return ToolEvent{a, p, t}; }

}  // namespace

TEST_CASE("tools: counting adds a marker of the current class per press, removes the nearest, counts live") {
  auto store = fresh_store("count");
  ToolPalette tools(*store, 2.0);
  tools.set_class("nucleus", {1, 0, 0, 1});
  REQUIRE(tools.apply(ev(ToolAction::kPress, {10, 10, 10})));
  REQUIRE(tools.apply(ev(ToolAction::kPress, {20, 10, 10})));
  tools.set_class("mitosis", {0, 1, 0, 1});
  REQUIRE(tools.apply(ev(ToolAction::kPress, {30, 10, 10})));
  CHECK(tools.live().counts == std::map<std::string, size_t>{{"mitosis", 1}, {"nucleus", 2}});
  // Too far from any marker: refused, nothing removed.
  const Status far = tools.apply(ev(ToolAction::kRemove, {15, 10, 10}));
  CHECK(far.code() == ErrorCode::kNotFound);
  CHECK(store->markers()->size() == 3);
  REQUIRE(tools.apply(ev(ToolAction::kRemove, {19, 11, 10})));
  auto left = store->markers();
  REQUIRE(left->size() == 2);
  CHECK(left->at(0).pos == Vec3{10, 10, 10});
  CHECK(left->at(1).cls == "mitosis");
  CHECK(tools.live().counts == std::map<std::string, size_t>{{"mitosis", 1}, {"nucleus", 1}});
  // Another timepoint counts separately.
  REQUIRE(tools.apply(ev(ToolAction::kPress, {10, 10, 10}, 4)));
  CHECK(tools.live().counts == std::map<std::string, size_t>{{"mitosis", 1}});
}

TEST_CASE("tools: measuring follows the cursor and stores a metric length with anisotropic voxels") {
  auto store = fresh_store("measure");
  REQUIRE(store->set_voxel_space(VoxelSpace{{0.5, 0.5, 2.0}, "um"}));
  ToolPalette tools(*store);
  tools.select_tool(Tool::kMeasure);
  REQUIRE(tools.apply(ev(ToolAction::kPress, {0, 0, 0})));
  REQUIRE(tools.apply(ev(ToolAction::kMove, {2, 0, 0})));
  CHECK(tools.live().measuring_length == doctest::Approx(1.0).epsilon(1e-15));
  REQUIRE(tools.apply(ev(ToolAction::kRelease, {3, 4, 1})));
  CHECK(!tools.live().measuring);
  auto ms = store->measurements();
  REQUIRE(ms->size() == 1);
  CHECK(store->length(ms->front()) == doctest::Approx(std::sqrt(1.5 * 1.5 + 2.0 * 2.0 + 2.0 * 2.0)).epsilon(1e-15));
  // A click without a drag stores nothing.
  REQUIRE(tools.apply(ev(ToolAction::kPress, {5, 5, 5})));
  REQUIRE(tools.apply(ev(ToolAction::kRelease, {5, 5, 5})));
  CHECK(store->measurements()->size() == 1);
  // Remove picks by distance to the segment, not to its ends.
  REQUIRE(tools.apply(ev(ToolAction::kRemove, {1.5, 2.5, 0.5})));
  CHECK(store->measurements()->empty());
}

TEST_CASE("tools: tracing chains nodes, branches from a picked node, removes back to the parent") {
  auto store = fresh_store("trace");
  ToolPalette tools(*store, 1.0);
  tools.select_tool(Tool::kTrace);
  tools.set_node_radius(2.5);
  for (double x : {0.0, 10.0, 20.0}) REQUIRE(tools.apply(ev(ToolAction::kPress, {x, 0, 0})));
  const Id sk = tools.live().skeleton;
  REQUIRE(sk != 0);
  REQUIRE(tools.apply(ev(ToolAction::kPick, {10.5, 0, 0})));  // node 2
  CHECK(tools.live().current_node == 2);
  REQUIRE(tools.apply(ev(ToolAction::kPress, {10, 10, 0})));  // branch: node 4 below 2
  REQUIRE(tools.apply(ev(ToolAction::kPress, {10, 20, 0})));  // node 5 below 4
  REQUIRE(tools.apply(ev(ToolAction::kRemove, {0, 0, 0})));   // removes node 5, back to 4
  CHECK(tools.live().current_node == 4);
  REQUIRE(tools.apply(ev(ToolAction::kFinish, {0, 0, 0})));
  REQUIRE(tools.apply(ev(ToolAction::kPress, {50, 50, 50})));  // a new root
  auto s = store->skeleton(sk);
  REQUIRE(s.is_ok());
  CHECK(s->size() == 5);
  CHECK(s->find(1)->parent == kNoParent);
  CHECK(s->find(2)->parent == 1);
  CHECK(s->find(3)->parent == 2);
  CHECK(s->find(4)->parent == 2);
  // The removed node's id is free again: the new root took it.
  REQUIRE(s->find(5) != nullptr);
  CHECK(s->find(5)->parent == kNoParent);
  CHECK(s->find(5)->pos == Vec3{50, 50, 50});
  CHECK(s->roots().size() == 2);
  CHECK(s->find(4)->radius == 2.5);
  CHECK(tools.apply(ev(ToolAction::kPick, {100, 0, 0})).code() == ErrorCode::kNotFound);
}

TEST_CASE("tools: tracking links one marker per timepoint, a second at the same timepoint is refused cleanly") {
  auto store = fresh_store("track");
  ToolPalette tools(*store);
  tools.select_tool(Tool::kTrack);
  for (uint32_t t = 0; t < 3; ++t) REQUIRE(tools.apply(ev(ToolAction::kPress, {10.0 + t, 5, 5}, t)));
  const Id track = tools.live().track;
  const Status twice = tools.apply(ev(ToolAction::kPress, {13, 5, 5}, 2));
  CHECK(!twice.is_ok());
  CHECK(store->markers()->size() == 3);  // the refused marker was taken back
  CHECK(store->track(track)->markers.size() == 3);
  REQUIRE(tools.apply(ev(ToolAction::kFinish, {0, 0, 0})));
  REQUIRE(tools.apply(ev(ToolAction::kPress, {40, 5, 5}, 2)));  // a second track
  CHECK(tools.live().track != track);
  CHECK(store->tracks()->size() == 2);
}

TEST_CASE("tools: an ROI box is dragged corner to corner and counts the markers inside it") {
  auto store = fresh_store("roi");
  ToolPalette tools(*store);
  for (double x : {1.0, 5.0, 9.0}) REQUIRE(tools.apply(ev(ToolAction::kPress, {x, 5, 5})));
  tools.select_tool(Tool::kRoi);
  REQUIRE(tools.apply(ev(ToolAction::kPress, {6, 0, 0})));
  REQUIRE(tools.apply(ev(ToolAction::kMove, {0, 10, 10})));
  CHECK(tools.live().roi_markers == 2);
  REQUIRE(tools.apply(ev(ToolAction::kRelease, {0, 10, 10})));
  auto rois = store->rois();
  REQUIRE(rois->size() == 1);
  CHECK(rois->front().min == Vec3{0, 0, 0});
  CHECK(rois->front().max == Vec3{6, 10, 10});
  REQUIRE(tools.apply(ev(ToolAction::kRemove, {3, 3, 3})));
  CHECK(store->rois()->empty());
}

TEST_CASE("tool scripts: a script drives every tool, bad scripts name the event and the key") {
  auto store = fresh_store("script");
  ToolPalette tools(*store);
  auto steps = parse_tool_script(R"({"events": [
      {"tool": "count", "class": "cell", "color": [0, 1, 1, 1]}, {"press": [1, 2, 3]}, {"press": [4, 5, 6]},
      {"tool": "measure"}, {"press": [0, 0, 0]}, {"move": [1, 0, 0]}, {"release": [3, 4, 0]},
      {"tool": "trace", "radius": 2}, {"press": [0, 0, 0]}, {"press": [0, 5, 0]},
      {"tool": "track", "timepoint": 1, "press": [7, 7, 7]}, {"timepoint": 2, "press": [8, 7, 7]}]})",
                                 "s.json");
  REQUIRE_MESSAGE(steps.is_ok(), steps.status().to_string());
  size_t callbacks = 0;
  REQUIRE(run_tool_script(tools, *steps, [&](const ToolStep&, const ToolLiveState&) { ++callbacks; }));
  CHECK(callbacks == 9);
  CHECK(store->counts()->at("cell") == 4);  // two counted, two tracked (markers of the current class)
  REQUIRE(store->measurements()->size() == 1);
  CHECK(store->length(store->measurements()->front()) == doctest::Approx(5.0));
  CHECK(store->skeleton(tools.live().skeleton)->size() == 2);
  CHECK(store->track(tools.live().track)->markers.size() == 2);

  auto bad = parse_tool_script(R"({"events": [{"tool": "count"}, {"prss": [1, 2, 3]}]})", "s.json");
  CHECK(bad.status().message() == "s.json: event 1: unknown key \"prss\" (tool, class, color, timepoint, radius, "
                                  "press, move, release, pick, remove, finish)");
  CHECK(parse_tool_script(R"({"events": [{"press": [1, 2]}]})", "s.json").status().message() ==
        "s.json: event 0: \"press\" needs the cursor [x, y, z] in voxels");
  CHECK(parse_tool_script(R"({"events": [{"press": [1, 2, 3], "move": [1, 2, 3]}]})", "s.json").status().message() ==
        "s.json: event 0: holds two actions; give one per event");
  CHECK(parse_tool_script(R"({"events": [{"tool": "lasso"}]})", "s.json").status().message().find("\"tool\" must be") !=
        std::string::npos);
  CHECK(!parse_tool_script("[1]", "s.json").is_ok());
  // A refused edit stops the script and names the event; earlier edits stay.
  auto refused = parse_tool_script(R"({"events": [{"tool": "count", "press": [1, 1, 1]}, {"remove": [90, 90, 90]}]})",
                                   "s.json");
  REQUIRE(refused.is_ok());
  ToolPalette again(*store);
  const Status st = run_tool_script(again, *refused);
  CHECK(st.message().rfind("event 1 (count): no marker within 5 voxels", 0) == 0);
  CHECK(store->counts()->at("default") == 1);
}
