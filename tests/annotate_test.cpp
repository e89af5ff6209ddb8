// engine/annotate: the LevelDB annotation store, skeleton edits, SWC
// reading/writing against real files, CSV export, and durability under
// kill -9.
#include <doctest/doctest.h>
#include <leveldb/db.h>
#include <poll.h>
#include <signal.h>
#include <spawn.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <map>
#include <random>
#include <set>
#include <sstream>
#include <thread>

#include "annotate/annotation_store.h"
#include "annotate/csv_export.h"
#include "annotate/file_io.h"
#include "annotate/obj.h"
#include "annotate/swc.h"
#include "scene/render_settings.h"

using namespace vxr;
using namespace vxr::annotate;
namespace fs = std::filesystem;

extern char** environ;

namespace {

const std::string kTestdata = VXR_TESTDATA_DIR;

// A fresh, empty folder for one test's store.
std::string fresh_dir(const std::string& name) {
  const fs::path p = fs::path(VXR_TEST_OUT_DIR) / "annotate" / name;
  fs::remove_all(p);
  fs::create_directories(p.parent_path());
  return p.string();
}

std::unique_ptr<AnnotationStore> open_new(const std::string& name) {
  auto s = AnnotationStore::open(fresh_dir(name), true);
  REQUIRE_MESSAGE(s.is_ok(), s.status().message());
  return std::move(s).value();
}

// 1-based line of the data line whose first column is `id` (first match).
int line_of(const std::string& path, int64_t id) {
  std::ifstream in(path);
  std::string line;
  for (int n = 1; std::getline(in, line); ++n) {
    std::istringstream ss(line);
    std::string first;
    if ((ss >> first) && first[0] != '#' && first == std::to_string(id)) return n;
  }
  return -1;
}

std::set<SwcWarningKind> kinds(const SwcFile& f) {
  std::set<SwcWarningKind> out;
  for (const SwcWarning& w : f.warnings) out.insert(w.kind);
  return out;
}

double dist(const Vec3& a, const Vec3& b) {
  return std::hypot(a[0] - b[0], a[1] - b[1], a[2] - b[2]);
}

// Same tree: `b` is `a` renumbered by `map` (a id -> b id), same coordinates within tol.
void check_same_tree(const Skeleton& a, const Skeleton& b, const std::map<int64_t, int64_t>& map, double tol) {
  REQUIRE(a.size() == b.size());
  REQUIRE(map.size() == a.size());
  for (const auto& [id, n] : a.nodes()) {
    const SkeletonNode* m = b.find(map.at(id));
    REQUIRE(m != nullptr);
    CHECK(m->type == n.type);
    CHECK(dist(m->pos, n.pos) <= tol);
    CHECK(std::fabs(m->radius - n.radius) <= tol);
    CHECK(m->parent == (n.parent == kNoParent ? kNoParent : map.at(n.parent)));
  }
}

}  // namespace

// ---------------------------------------------------------------- SWC files

TEST_CASE("swc: every real file in testdata/swc round-trips through writer and reader (same tree, 1e-6)") {
  int files = 0;
  for (const auto& entry : fs::directory_iterator(kTestdata + "/swc")) {
    const std::string path = entry.path().string();
    CAPTURE(path);
    auto file = read_swc(path);
    REQUIRE_MESSAGE(file.is_ok(), file.status().message());
    // These are valid files: the reader has nothing to report.
    for (const SwcWarning& w : file->warnings) FAIL_CHECK(w.message);
    const Skeleton a = skeleton_from_swc(*file);
    REQUIRE(a.validate().is_ok());
    std::map<int64_t, int64_t> renumbered;
    const std::string text = skeleton_to_swc(a, "round trip of " + path, &renumbered);
    auto back = parse_swc(text, "written");
    REQUIRE_MESSAGE(back.is_ok(), back.status().message());
    CHECK(back->warnings.empty());
    // Parent-first: every parent line precedes its child, ids are 1..N in order.
    for (size_t i = 0; i < back->samples.size(); ++i) {
      CHECK(back->samples[i].id == static_cast<int64_t>(i + 1));
      CHECK(back->samples[i].parent < back->samples[i].id);
    }
    check_same_tree(a, skeleton_from_swc(*back), renumbered, 1e-6);
    ++files;
  }
  CHECK(files == 5);
}

TEST_CASE("swc: the reader tolerates CRLF, tabs, inline comments, '.1' and '0.' numbers, sparse unsorted ids") {
  const std::string text =
      "# header\r\n"
      "\t10\t1\t0.\t.5\t-1.25\t2.0\t-1\t# soma, tab separated\r\n"
      "30 3 1 2 3 .1 20   \r\n"  // child before its parent (unsorted)
      "20 3 1e1 0 0 0.3 10\n"
      "\n"
      "   # indented comment\n";
  auto f = parse_swc(text, "t.swc");
  REQUIRE_MESSAGE(f.is_ok(), f.status().message());
  CHECK(f->warnings.empty());
  REQUIRE(f->samples.size() == 3);
  CHECK(f->samples[0].pos == Vec3{0, 0.5, -1.25});
  CHECK(f->samples[1].radius == doctest::Approx(0.1));
  CHECK(f->samples[1].parent == 20);
  CHECK(f->samples[2].pos[0] == 10.0);
  const Skeleton sk = skeleton_from_swc(*f);
  CHECK(sk.parent_first_order() == std::vector<int64_t>{10, 20, 30});
}

TEST_CASE("swc: broken lines are one error naming file and line, never a crash") {
  auto cols = parse_swc("1 1 0 0 0 1 -1\n2 3 0 0\n", "a.swc");
  CHECK(cols.status().message() == "a.swc:2: expected 7 columns (id type x y z radius parent), found 4");
  auto nan = parse_swc("1 1 0 zero 0 1 -1\n", "b.swc");
  CHECK(nan.status().message() == "b.swc:1: y 'zero' is not a number");
  auto frac = parse_swc("1.5 1 0 0 0 1 -1\n", "c.swc");
  CHECK(frac.status().message().rfind("c.swc:1: ", 0) == 0);
  auto loop = parse_swc("1 1 0 0 0 1 -1\n2 3 0 0 0 1 3\n3 3 0 0 0 1 2\n", "d.swc");
  CHECK(loop.status().code() == ErrorCode::kInvalidArgument);
  CHECK(loop.status().message().find("own ancestor") != std::string::npos);
  CHECK(loop.status().message().rfind("d.swc:", 0) == 0);
  auto self = parse_swc("1 1 0 0 0 1 1\n", "e.swc");
  CHECK(self.status().message() == "e.swc:1: sample 1 is its own parent");
  auto empty = parse_swc("# only a comment\r\n\n", "f.swc");
  CHECK(empty.status().message() == "f.swc: no samples (lines of id type x y z radius parent); is this an SWC file?");
  auto binary = parse_swc("\x89PNG\x01 1 2 3 4 5 6\n", "g.swc");
  CHECK(binary.status().message() == "g.swc:1: id '?PNG?' is not a number");
  auto missing = read_swc("/nonexistent/x.swc");
  CHECK(missing.status().message() == "/nonexistent/x.swc: no such file");
}

TEST_CASE("swc: each malformed real file gives its specific warning at the right line, or a line-naming error") {
  const std::string dir = kTestdata + "/swc-malformed/";
  SUBCASE("Neuron_missing_ids: samples 8 and 9 name the absent parent 7 and become roots") {
    auto f = read_swc(dir + "Neuron_missing_ids.swc");
    REQUIRE(f.is_ok());
    CHECK(kinds(*f) == std::set{SwcWarningKind::kMissingParent, SwcWarningKind::kSeveralRoots});
    CHECK(f->lines_with(SwcWarningKind::kMissingParent) ==
          std::vector<int>{line_of(dir + "Neuron_missing_ids.swc", 8), line_of(dir + "Neuron_missing_ids.swc", 9)});
    CHECK(f->warnings.front().message.find("sample 8 names parent 7, which is not in the file") != std::string::npos);
    CHECK(skeleton_from_swc(*f).roots().size() == 3);
  }
  SUBCASE("Neuron_missing_parents: the children of deleted samples 5, 216, 427, 638 are reported") {
    const std::string path = dir + "Neuron_missing_parents.swc";
    auto f = read_swc(path);
    REQUIRE(f.is_ok());
    CHECK(kinds(*f) == std::set{SwcWarningKind::kMissingParent, SwcWarningKind::kSeveralRoots});
    std::set<std::string> parents;
    for (const SwcWarning& w : f->warnings) {
      if (w.kind != SwcWarningKind::kMissingParent) continue;
      const size_t at = w.message.find("names parent ");
      REQUIRE(at != std::string::npos);
      parents.insert(w.message.substr(at + 13, w.message.find(',', at) - at - 13));
      CHECK(w.message.rfind(path + ":" + std::to_string(w.line) + ": sample ", 0) == 0);
    }
    CHECK(parents == std::set<std::string>{"5", "216", "427", "638"});
    CHECK(skeleton_from_swc(*f).validate().is_ok());
  }
  SUBCASE("repeated_id: sample 4 twice is an error naming line 6 and the first definition") {
    auto f = read_swc(dir + "repeated_id.swc");
    CHECK(f.status().message() ==
          dir + "repeated_id.swc:6: sample id 4 is repeated (first defined on line 5); make ids unique");
  }
  SUBCASE("multiple_somata: a second root on sample 10's line") {
    auto f = read_swc(dir + "multiple_somata.swc");
    REQUIRE(f.is_ok());
    CHECK(kinds(*f) == std::set{SwcWarningKind::kSeveralRoots});
    CHECK(f->lines_with(SwcWarningKind::kSeveralRoots) == std::vector<int>{line_of(dir + "multiple_somata.swc", 10)});
    CHECK(f->warnings[0].message.find("2 roots") != std::string::npos);
  }
  SUBCASE("soma_zero_radius: soma sample 1 has radius 0") {
    auto f = read_swc(dir + "soma_zero_radius.swc");
    REQUIRE(f.is_ok());
    CHECK(kinds(*f) == std::set{SwcWarningKind::kZeroRadiusSoma});
    CHECK(f->lines_with(SwcWarningKind::kZeroRadiusSoma) == std::vector<int>{line_of(dir + "soma_zero_radius.swc", 1)});
  }
  SUBCASE("undefined_type: samples 6..9 have type 0") {
    const std::string path = dir + "undefined_type.swc";
    auto f = read_swc(path);
    REQUIRE(f.is_ok());
    CHECK(kinds(*f) == std::set{SwcWarningKind::kUndefinedType});
    CHECK(f->lines_with(SwcWarningKind::kUndefinedType) ==
          std::vector<int>{line_of(path, 6), line_of(path, 7), line_of(path, 8), line_of(path, 9)});
  }
  SUBCASE("Neuron_disconnected_components: several trees, reported once with the root count") {
    auto f = read_swc(dir + "Neuron_disconnected_components.swc");
    REQUIRE(f.is_ok());
    CHECK(kinds(*f) == std::set{SwcWarningKind::kSeveralRoots});
    REQUIRE(f->warnings.size() == 1);
    const size_t roots = skeleton_from_swc(*f).roots().size();
    CHECK(roots > 1);
    CHECK(f->warnings[0].message.find(std::to_string(roots) + " roots") != std::string::npos);
  }
  SUBCASE("z_jump: sample 11 jumps 89 in z and its radius 26x") {
    const std::string path = dir + "z_jump.swc";
    auto f = read_swc(path);
    REQUIRE(f.is_ok());
    CHECK(kinds(*f) == std::set{SwcWarningKind::kLongSegment, SwcWarningKind::kRadiusJump});
    CHECK(f->lines_with(SwcWarningKind::kLongSegment) == std::vector<int>{line_of(path, 11)});
    CHECK(f->lines_with(SwcWarningKind::kRadiusJump) == std::vector<int>{line_of(path, 11)});
  }
  SUBCASE("sample_disordered: 0-based ids are reported and shifted; the tree is intact") {
    const std::string path = dir + "sample_disordered.swc";
    auto f = read_swc(path);
    REQUIRE(f.is_ok());
    CHECK(kinds(*f) == std::set{SwcWarningKind::kNonPositiveId});
    CHECK(f->lines_with(SwcWarningKind::kNonPositiveId) == std::vector<int>{line_of(path, 0)});
    const Skeleton sk = skeleton_from_swc(*f);
    CHECK(sk.validate().is_ok());
    CHECK(sk.size() == 53);
    CHECK(sk.roots() == std::vector<int64_t>{1});
    CHECK(sk.find(28)->parent == 1);  // sample 27's parent 0, shifted by one
  }
}

TEST_CASE("swc: every file in testdata/swc-malformed loads with warnings or fails naming a line") {
  int files = 0;
  for (const auto& entry : fs::directory_iterator(kTestdata + "/swc-malformed")) {
    const std::string path = entry.path().string();
    CAPTURE(path);
    auto f = read_swc(path);
    if (f.is_ok()) {
      CHECK_FALSE(f->warnings.empty());
      for (const SwcWarning& w : f->warnings)
        CHECK(w.message.rfind(path + ":" + std::to_string(w.line) + ": ", 0) == 0);
      CHECK(skeleton_from_swc(*f).validate().is_ok());
    } else {
      CHECK(f.status().message().rfind(path + ":", 0) == 0);
    }
    ++files;
  }
  CHECK(files == 9);
}

// ---------------------------------------------------------------- skeleton edits

namespace {
// root 1 -> 2 -> 3, 2 -> 4, 1 -> 5
Skeleton small_tree() {
  Skeleton sk(0, "t");
  for (auto [id, parent] : std::vector<std::pair<int64_t, int64_t>>{{1, -1}, {2, 1}, {3, 2}, {4, 2}, {5, 1}}) {
    SkeletonNode n;
    n.id = id;
    n.parent = parent;
    n.pos = {double(id), 0, 0};
    n.radius = 1;
    REQUIRE(sk.add_node(n).is_ok());
  }
  return sk;
}
}  // namespace

TEST_CASE("skeleton: add refuses a missing parent or a repeated id, and move changes only the position") {
  Skeleton sk = small_tree();
  SkeletonNode orphan;
  orphan.parent = 42;
  CHECK(sk.add_node(orphan).status().code() == ErrorCode::kNotFound);
  SkeletonNode dup;
  dup.id = 3;
  CHECK(sk.add_node(dup).status().code() == ErrorCode::kInvalidArgument);
  auto added = sk.add_node({0, {9, 9, 9}, 0.5, 3, 4});
  REQUIRE(added.is_ok());
  CHECK(*added == 6);
  REQUIRE(sk.move_node(6, {1, 2, 3}).is_ok());
  CHECK(sk.find(6)->pos == Vec3{1, 2, 3});
  CHECK(sk.find(6)->parent == 4);
  CHECK(sk.validate().is_ok());
}

TEST_CASE("skeleton: deleting a node hands its children to its parent, and deleting a root makes them roots") {
  Skeleton sk = small_tree();
  REQUIRE(sk.delete_node(2).is_ok());
  CHECK(sk.find(3)->parent == 1);
  CHECK(sk.find(4)->parent == 1);
  CHECK(sk.validate().is_ok());
  REQUIRE(sk.delete_node(1).is_ok());
  CHECK(sk.roots() == std::vector<int64_t>{3, 4, 5});
  CHECK(sk.validate().is_ok());
  Skeleton t = small_tree();
  REQUIRE(t.delete_subtree(2).is_ok());
  CHECK(t.size() == 2);
  CHECK(t.validate().is_ok());
  CHECK(t.delete_node(99).code() == ErrorCode::kNotFound);
}

TEST_CASE("skeleton: reparent moves a subtree and refuses to create a cycle") {
  Skeleton sk = small_tree();
  REQUIRE(sk.reparent(2, 5).is_ok());
  CHECK(sk.find(2)->parent == 5);
  CHECK(sk.subtree(5) == std::vector<int64_t>{5, 2, 3, 4});
  const Status cyc = sk.reparent(5, 3);  // 3 is below 5 now
  CHECK(cyc.code() == ErrorCode::kInvalidArgument);
  CHECK(cyc.message().find("cycle") != std::string::npos);
  CHECK(sk.find(5)->parent == 1);  // unchanged
  CHECK(sk.reparent(4, 4).code() == ErrorCode::kInvalidArgument);
  REQUIRE(sk.reparent(2, kNoParent).is_ok());
  CHECK(sk.roots() == std::vector<int64_t>{1, 2});
  CHECK(sk.validate().is_ok());
}

TEST_CASE("skeleton: split detaches a subtree as a new tree, and merge re-roots and attaches with fresh ids") {
  Skeleton sk = small_tree();
  auto part = sk.split(2);
  REQUIRE(part.is_ok());
  CHECK(part->roots() == std::vector<int64_t>{2});
  CHECK(part->size() == 3);
  CHECK(sk.size() == 2);
  CHECK(sk.validate().is_ok());
  CHECK(part->validate().is_ok());
  // Merge the part back, hung from node 5 by its leaf 3: 3 becomes the part's root.
  auto map = sk.merge(*part, 3, 5);
  REQUIRE(map.is_ok());
  CHECK(part->size() == 0);
  CHECK(sk.size() == 5);
  CHECK(sk.validate().is_ok());
  const int64_t n3 = map->at(3), n2 = map->at(2), n4 = map->at(4);
  CHECK(n3 > 5);
  CHECK(sk.find(n3)->parent == 5);
  CHECK(sk.find(n2)->parent == n3);  // reversed along the old root path
  CHECK(sk.find(n4)->parent == n2);
  CHECK(sk.find(n3)->pos == Vec3{3, 0, 0});
  Skeleton other = small_tree();
  CHECK(sk.merge(other, 99, 1).status().code() == ErrorCode::kNotFound);
  CHECK(sk.merge(sk, 1, 1).status().code() == ErrorCode::kInvalidArgument);
}

TEST_CASE("store: skeleton edits are persisted, keep a valid tree, and a refused edit writes nothing") {
  const std::string dir = fresh_dir("skeleton_edits");
  Id a = 0, b = 0;
  {
    auto s = AnnotationStore::open(dir, true);
    REQUIRE(s.is_ok());
    auto id = (*s)->add_skeleton(small_tree());
    REQUIRE(id.is_ok());
    a = *id;
    REQUIRE((*s)->move_node(a, 3, {7, 7, 7}).is_ok());
    REQUIRE((*s)->reparent_node(a, 4, 5).is_ok());
    CHECK((*s)->reparent_node(a, 1, 3).code() == ErrorCode::kInvalidArgument);
    REQUIRE((*s)->delete_node(a, 2).is_ok());
    auto added = (*s)->add_node(a, {0, {1, 1, 1}, 2, 4, 3});
    REQUIRE(added.is_ok());
    auto split = (*s)->split_skeleton(a, 5);
    REQUIRE(split.is_ok());
    b = *split;
    auto merged = (*s)->merge_skeletons(a, *added, b, 4);  // 5 -> 4 becomes 4 -> 5 under the new node
    REQUIRE(merged.is_ok());
    CHECK(merged->size() == 2);
  }
  auto s = AnnotationStore::open(dir, false);
  REQUIRE(s.is_ok());
  CHECK((*s)->skeleton(b).status().code() == ErrorCode::kNotFound);
  auto sk = (*s)->skeleton(a);
  REQUIRE(sk.is_ok());
  CHECK(sk->validate().is_ok());
  // 1 root; 3 (moved, now child of 1); 6 under 3; then old 4 under 6 and old 5 under old 4.
  CHECK(sk->size() == 5);
  CHECK(sk->roots() == std::vector<int64_t>{1});
  CHECK(sk->find(3)->pos == Vec3{7, 7, 7});
  CHECK(sk->find(3)->parent == 1);
  CHECK(sk->find(6)->parent == 3);
  CHECK(sk->find(7)->parent == 6);
  CHECK(sk->find(7)->pos == Vec3{4, 0, 0});
  CHECK(sk->find(8)->parent == 7);
  CHECK(sk->find(8)->pos == Vec3{5, 0, 0});
  auto list = (*s)->skeletons();
  REQUIRE(list.is_ok());
  CHECK(list->size() == 1);
}

TEST_CASE("store: SWC imported with anisotropic voxels and exported again is the same tree within 1e-6") {
  auto s = open_new("swc_store_roundtrip");
  REQUIRE(s->set_voxel_space({{0.3, 0.3, 2.0}, "um"}).is_ok());
  auto file = read_swc(kTestdata + "/swc/Neuron.swc");
  REQUIRE(file.is_ok());
  Skeleton um = skeleton_from_swc(*file);
  Skeleton vox = um;
  for (const auto& [id, n] : um.nodes()) {
    SkeletonNode v = n;
    v.pos = s->voxel_space().from_physical(n.pos);
    vox.insert_unchecked(v);
  }
  auto id = s->add_skeleton(vox);
  REQUIRE(id.is_ok());
  auto back = s->skeleton(*id);
  REQUIRE(back.is_ok());
  Skeleton out = *back;
  for (const auto& [nid, n] : back->nodes()) {
    SkeletonNode p = n;
    p.pos = s->voxel_space().to_physical(n.pos);
    out.insert_unchecked(p);
  }
  std::map<int64_t, int64_t> renumbered;
  auto again = parse_swc(skeleton_to_swc(out, "", &renumbered), "x");
  REQUIRE(again.is_ok());
  check_same_tree(um, skeleton_from_swc(*again), renumbered, 1e-6);
}

// ---------------------------------------------------------------- markers, measurements, tracks, ROIs

TEST_CASE("store: measurement length uses the anisotropic voxel size and unit") {
  auto s = open_new("measure");
  REQUIRE(s->set_voxel_space({{0.5, 0.5, 2.0}, "um"}).is_ok());
  auto id = s->add_measurement({0, "axon gap", {0, 0, 0}, {3, 4, 1}, 0});
  REQUIRE(id.is_ok());
  auto m = s->measurement(*id);
  REQUIRE(m.is_ok());
  // (3*0.5, 4*0.5, 1*2) = (1.5, 2, 2) um
  CHECK(s->length(*m) == doctest::Approx(std::sqrt(10.25)).epsilon(1e-12));
  const std::string csv = measurements_csv({*m}, s->voxel_space());
  CHECK(csv == "id,label,timepoint,ax,ay,az,bx,by,bz,length_um\n1,axon gap,0,0,0,0,3,4,1,3.2015621187164243\n");
  CHECK(s->set_voxel_space({{1, 1, 0}, "um"}).code() == ErrorCode::kInvalidArgument);
  CHECK(s->set_voxel_space({{1, 1, 1}, "furlong"}).code() == ErrorCode::kInvalidArgument);
}

TEST_CASE("store: markers count per class and timepoint, and CSV quotes awkward class names") {
  auto s = open_new("markers");
  for (int i = 0; i < 7; ++i) {
    Marker m;
    m.cls = i < 4 ? "neuron" : "glia, \"reactive\"";
    m.pos = {double(i), 0, 0};
    m.timepoint = i % 2;
    REQUIRE(s->add_marker(m).is_ok());
  }
  auto all = s->counts();
  REQUIRE(all.is_ok());
  CHECK(*all == std::map<std::string, size_t>{{"glia, \"reactive\"", 3}, {"neuron", 4}});
  auto t1 = s->counts(1);
  REQUIRE(t1.is_ok());
  CHECK(*t1 == std::map<std::string, size_t>{{"glia, \"reactive\"", 1}, {"neuron", 2}});
  auto ms = s->markers();
  REQUIRE(ms.is_ok());
  CHECK(counts_csv(*ms) == "class,count\n\"glia, \"\"reactive\"\"\",3\nneuron,4\n");
  const std::string pts = markers_csv(*ms, s->voxel_space());
  CHECK(pts.rfind("id,class,r,g,b,a,x,y,z,timepoint,x_um,y_um,z_um\n1,neuron,1,1,0,1,0,0,0,0,0,0,0\n", 0) == 0);
  REQUIRE(s->delete_marker(1).is_ok());
  CHECK(s->marker(1).status().code() == ErrorCode::kNotFound);
  Marker bad;
  bad.pos = {NAN, 0, 0};
  CHECK(s->add_marker(bad).status().code() == ErrorCode::kInvalidArgument);
}

TEST_CASE("store: a track holds one marker per timepoint in time order, and loses deleted markers") {
  auto s = open_new("tracks");
  std::vector<Id> ids;
  for (uint32_t t : {2u, 0u, 1u, 1u}) {
    Marker m;
    m.pos = {double(t), double(t), 0};
    m.timepoint = t;
    ids.push_back(*s->add_marker(m));
  }
  auto tr = s->add_track("cell A", {ids[0], ids[1], ids[2]});
  REQUIRE(tr.is_ok());
  CHECK(s->track(*tr)->markers == std::vector<Id>{ids[1], ids[2], ids[0]});  // t = 0, 1, 2
  const Status clash = s->add_to_track(*tr, ids[3]);
  CHECK(clash.code() == ErrorCode::kInvalidArgument);
  CHECK(clash.message().find("one marker per timepoint") != std::string::npos);
  CHECK(s->add_track("x", {999}).status().code() == ErrorCode::kNotFound);
  auto markers = s->markers();
  auto tracks = s->tracks();
  const std::string csv = tracks_csv(*tracks, *markers, s->voxel_space());
  CHECK(csv ==
        "track,name,step,marker,timepoint,x,y,z,step_length_um\n"
        "1,cell A,0,2,0,0,0,0,\n"
        "1,cell A,1,3,1,1,1,0,1.4142135623730951\n"
        "1,cell A,2,1,2,2,2,0,1.4142135623730951\n");
  REQUIRE(s->delete_marker(ids[2]).is_ok());
  CHECK(s->track(*tr)->markers == std::vector<Id>{ids[1], ids[0]});
}

TEST_CASE("store: an ROI query returns exactly the annotations inside the box") {
  auto s = open_new("roi");
  Marker in, out, in_t1;
  in.pos = {5, 5, 5};
  out.pos = {11, 5, 5};
  in_t1.pos = {1, 1, 1};
  in_t1.timepoint = 1;
  const Id m_in = *s->add_marker(in), m_out = *s->add_marker(out), m_t1 = *s->add_marker(in_t1);
  const Id meas_in = *s->add_measurement({0, "in", {0, 0, 0}, {10, 10, 10}, 0});  // on the faces: inside
  REQUIRE(s->add_measurement({0, "half", {5, 5, 5}, {20, 5, 5}, 0}).is_ok());
  Skeleton sk(0, "s");
  REQUIRE(sk.add_node({1, {2, 2, 2}, 1, 1, kNoParent}).is_ok());
  REQUIRE(sk.add_node({2, {30, 2, 2}, 1, 3, 1}).is_ok());
  const Id skid = *s->add_skeleton(sk);
  const Id tr_in = *s->add_track("in", {m_in, m_t1});
  REQUIRE(s->add_track("out", {m_out}).is_ok());
  auto roi = s->add_roi({0, "box", {0, 0, 0}, {10, 10, 10}});
  REQUIRE(roi.is_ok());
  auto box = s->roi(*roi);
  REQUIRE(box.is_ok());
  auto q = s->query(*box);
  REQUIRE(q.is_ok());
  REQUIRE(q->markers.size() == 2);
  CHECK(q->markers[0].id == m_in);
  CHECK(q->markers[1].id == m_t1);
  REQUIRE(q->measurements.size() == 1);
  CHECK(q->measurements[0].id == meas_in);
  REQUIRE(q->nodes.size() == 1);
  CHECK(q->nodes[0].first == skid);
  CHECK(q->nodes[0].second.id == 1);
  REQUIRE(q->tracks.size() == 1);
  CHECK(q->tracks[0].id == tr_in);
  auto q0 = s->query(*box, 0u);
  REQUIRE(q0.is_ok());
  CHECK(q0->markers.size() == 1);
  CHECK(s->add_roi({0, "inside out", {1, 0, 0}, {0, 1, 1}}).status().code() == ErrorCode::kInvalidArgument);
}

// ---------------------------------------------------------------- cards

TEST_CASE("store: a card keeps its scene, note, snapshot and memo byte for byte, and search matches every word") {
  const std::string dir = fresh_dir("cards");
  Scene scene;
  scene.volume = "head.vxc";
  scene.has_camera = true;
  scene.camera.eye = {1, 2, 3};
  scene.render.model = OpticalModel::kMip;
  Card c;
  c.title = "Dendrite spine cluster";
  c.note = "Dense spines near the Soma; check at t=3.";
  c.scene_json = scene_to_json(scene);
  c.snapshot_png = {0x89, 'P', 'N', 'G', '\r', '\n', 0x1a, '\n', 1, 2, 3};
  const std::string wav("RIFF\x24\0\0\0WAVEfmt ", 16);
  c.audio_wav.assign(wav.begin(), wav.end());
  Id id = 0;
  {
    auto s = AnnotationStore::open(dir, true);
    REQUIRE(s.is_ok());
    auto added = (*s)->add_card(c);
    REQUIRE_MESSAGE(added.is_ok(), added.status().message());
    id = *added;
    Card other;
    other.note = "nothing to see";
    REQUIRE((*s)->add_card(other).is_ok());
    Card bad = c;
    bad.scene_json = "{\"render\": {\"model\": \"xray\"}}";
    CHECK((*s)->add_card(bad).status().message().find("xray") != std::string::npos);
    bad = c;
    bad.snapshot_png = {1, 2, 3};
    CHECK((*s)->add_card(bad).status().message() == "card snapshot is not a PNG file");
  }
  auto s = AnnotationStore::open(dir, false);
  REQUIRE(s.is_ok());
  auto back = (*s)->card(id);
  REQUIRE(back.is_ok());
  CHECK(back->note == c.note);
  CHECK(back->snapshot_png == c.snapshot_png);
  CHECK(back->audio_wav == c.audio_wav);
  CHECK(back->created_unix > 0);
  auto restored = scene_from_json(back->scene_json);
  REQUIRE(restored.is_ok());
  CHECK(*restored == scene);
  auto hits = (*s)->search_cards("soma SPINES");
  REQUIRE(hits.is_ok());
  REQUIRE(hits->size() == 1);
  CHECK((*hits)[0].id == id);
  CHECK((*hits)[0].snapshot_png.empty());  // search does not read media
  CHECK((*s)->search_cards("soma axon")->empty());
  CHECK((*s)->search_cards("")->size() == 2);
  REQUIRE((*s)->delete_card(id).is_ok());
  CHECK((*s)->card(id).status().code() == ErrorCode::kNotFound);
}

// ---------------------------------------------------------------- opening, schema

TEST_CASE("store: opening refuses a missing store, a second opener, a newer schema and a foreign LevelDB") {
  const std::string missing = fresh_dir("missing");
  auto none = AnnotationStore::open(missing, false);
  CHECK(none.status().code() == ErrorCode::kNotFound);
  CHECK(none.status().message() ==
        missing + ": no annotation store here (create one with `vxr annotate init " + missing + "`)");

  const std::string dir = fresh_dir("schema");
  {
    auto s = AnnotationStore::open(dir, true);
    REQUIRE(s.is_ok());
    auto second = AnnotationStore::open(dir, false);
    CHECK(second.status().code() == ErrorCode::kIo);
    CHECK(second.status().message().find("open in another process") != std::string::npos);
  }
  {  // What a future vxr would write.
    leveldb::DB* db = nullptr;
    REQUIRE(leveldb::DB::Open(leveldb::Options(), dir, &db).ok());
    REQUIRE(db->Put(leveldb::WriteOptions(), "meta/schema_version", "2").ok());
    delete db;
  }
  auto newer = AnnotationStore::open(dir, false);
  CHECK(newer.status().code() == ErrorCode::kUnsupported);
  CHECK(newer.status().message() ==
        dir + ": annotation store schema version 2 is newer than this vxr reads (version 1); open it with a newer vxr");

  const std::string foreign = fresh_dir("foreign");
  {
    leveldb::DB* db = nullptr;
    leveldb::Options o;
    o.create_if_missing = true;
    REQUIRE(leveldb::DB::Open(o, foreign, &db).ok());
    REQUIRE(db->Put(leveldb::WriteOptions(), "something", "else").ok());
    delete db;
  }
  auto f = AnnotationStore::open(foreign, true);
  CHECK(f.status().code() == ErrorCode::kCorrupt);
  CHECK(f.status().message().find("is not a vxr annotation store") != std::string::npos);
}

TEST_CASE("store: a damaged write-ahead log is reported as corrupt, never skipped") {
  const std::string dir = fresh_dir("damaged");
  {
    auto s = AnnotationStore::open(dir, true);
    REQUIRE(s.is_ok());
    for (int i = 0; i < 20; ++i) {
      Marker m;
      m.pos = {double(i), 0, 0};
      REQUIRE((*s)->add_marker(m).is_ok());
    }
  }
  fs::path log;
  for (const auto& e : fs::directory_iterator(dir))
    if (e.path().extension() == ".log" && fs::file_size(e.path()) > 200) log = e.path();
  REQUIRE_FALSE(log.empty());
  {
    std::fstream f(log, std::ios::in | std::ios::out | std::ios::binary);
    f.seekp(static_cast<std::streamoff>(fs::file_size(log) / 2));
    f.write("XXXXXXXX", 8);
  }
  auto s = AnnotationStore::open(dir, false);
  CHECK(s.status().code() == ErrorCode::kCorrupt);
  CHECK(s.status().message().rfind(dir + ": annotation store is damaged (Corruption: ", 0) == 0);
}

// ---------------------------------------------------------------- kill -9

TEST_CASE("store: killed with SIGKILL at 60 random moments, every acknowledged write is there and the store opens") {
  const std::string dir = fresh_dir("kill9");
  std::mt19937 rng(20261124);
  struct Ack {
    char kind;
    Id a;
    int64_t b;
    long seq;
  };
  std::vector<Ack> acked;
  long next_seq = 0;
  int kills_mid_write = 0;
  for (int round = 0; round < 60; ++round) {
    CAPTURE(round);
    int fds[2];
    REQUIRE(::pipe(fds) == 0);
    posix_spawn_file_actions_t fa;
    posix_spawn_file_actions_init(&fa);
    posix_spawn_file_actions_adddup2(&fa, fds[1], 1);
    posix_spawn_file_actions_addclose(&fa, fds[0]);
    const std::string seq_arg = std::to_string(next_seq);
    char* argv[] = {const_cast<char*>(VXR_ANNOTATE_KILL_WRITER), const_cast<char*>(dir.c_str()),
                    const_cast<char*>(seq_arg.c_str()), nullptr};
    pid_t pid = 0;
    REQUIRE(posix_spawn(&pid, VXR_ANNOTATE_KILL_WRITER, &fa, nullptr, argv, environ) == 0);
    posix_spawn_file_actions_destroy(&fa);
    ::close(fds[1]);
    // The moment: after a random number (0..7) of acknowledged writes plus a
    // random fraction of a write's time, so kills land at every stage of a
    // write; every tenth round right away, while the store is being opened.
    std::string out;
    char buf[4096];
    const auto lines_in = [&] { return std::count(out.begin(), out.end(), '\n'); };
    if (round % 10 == 0) {
      std::this_thread::sleep_for(std::chrono::microseconds(rng() % 3000));
    } else {
      const long want = long(rng() % 8);
      const auto give_up = std::chrono::steady_clock::now() + std::chrono::seconds(20);
      while (lines_in() < want && std::chrono::steady_clock::now() < give_up) {
        pollfd p{fds[0], POLLIN, 0};
        if (::poll(&p, 1, 100) <= 0) continue;
        const ssize_t n = ::read(fds[0], buf, sizeof buf);
        if (n <= 0) break;
        out.append(buf, size_t(n));
      }
      std::this_thread::sleep_for(std::chrono::microseconds(rng() % 8000));
    }
    ::kill(pid, SIGKILL);
    int status = 0;
    REQUIRE(::waitpid(pid, &status, 0) == pid);
    CHECK_MESSAGE(WIFSIGNALED(status), "the writer exited by itself (status " << status << "): it failed a write");
    for (ssize_t n; (n = ::read(fds[0], buf, sizeof buf)) > 0;) out.append(buf, size_t(n));
    ::close(fds[0]);
    std::istringstream lines(out);
    int this_round = 0;
    for (std::string line; std::getline(lines, line);) {
      std::istringstream ls(line);
      Ack a{};
      ls >> a.kind >> a.a;
      if (a.kind == 'n') ls >> a.b;
      ls >> a.seq;
      REQUIRE_MESSAGE(!ls.fail(), "bad ack line '" << line << "'");
      acked.push_back(a);
      next_seq = a.seq + 1;
      ++this_round;
    }
    if (this_round > 0) ++kills_mid_write;

    auto s = AnnotationStore::open(dir, false);
    if (acked.empty() && !s.is_ok()) continue;  // killed before the store existed
    REQUIRE_MESSAGE(s.is_ok(), s.status().message());
    for (const Ack& a : acked) {
      const double d = double(a.seq);
      if (a.kind == 'm') {
        auto m = (*s)->marker(a.a);
        REQUIRE_MESSAGE(m.is_ok(), "acknowledged marker " << a.a << " lost: " << m.status().message());
        CHECK(m->pos == Vec3{d, 2 * d, 3 * d});
        CHECK(m->cls == std::string("c").append(std::to_string(a.seq % 4)));
      } else if (a.kind == 'n') {
        auto sk = (*s)->skeleton(a.a);
        REQUIRE_MESSAGE(sk.is_ok(), sk.status().message());
        const SkeletonNode* n = sk->find(a.b);
        REQUIRE_MESSAGE(n != nullptr, "acknowledged node " << a.b << " lost");
        CHECK(n->pos == Vec3{d, 0, 1});
      } else {
        auto c = (*s)->card(a.a);
        REQUIRE_MESSAGE(c.is_ok(), "acknowledged card " << a.a << " lost: " << c.status().message());
        CHECK(c->note == "card " + std::to_string(a.seq));
        CHECK(c->snapshot_png.size() == size_t(a.seq) + 9);
      }
    }
    // Nothing half-written either: every card present has its snapshot, every skeleton is a valid tree.
    auto cards = (*s)->cards();
    REQUIRE(cards.is_ok());
    for (const Card& c : *cards) {
      auto full = (*s)->card(c.id);
      CHECK_MESSAGE(full.is_ok(), full.status().message());
    }
    auto sks = (*s)->skeletons();
    REQUIRE(sks.is_ok());
    for (const SkeletonInfo& k : *sks) CHECK((*s)->skeleton(k.id).is_ok());
  }
  MESSAGE(acked.size() << " acknowledged writes over 60 kills, " << kills_mid_write
                       << " kills after at least one write");
  CHECK(kills_mid_write >= 40);
}

TEST_CASE("store: meshes keep the OBJ hierarchy and geometry, delete cascades, damaged geometry is reported") {
  const std::string dir = fresh_dir("meshes");
  auto store = AnnotationStore::open(dir, true);
  REQUIRE(store.is_ok());
  auto obj = parse_obj("o tissue\nv 0 0 0\nv 1 0 0\nv 0 1 0\nv 0 0 1\ng cell_a\nf 1 2 3\ng cell_b\nf 1 2 4\nf 1 3 4\n",
                       "t.obj", "");
  REQUIRE(obj.is_ok());
  auto ids = (*store)->add_meshes(obj->mesh, 0.5);
  REQUIRE_MESSAGE(ids.is_ok(), ids.status().to_string());
  REQUIRE(ids->size() == 3);
  auto all = (*store)->meshes();
  REQUIRE(all.is_ok());
  REQUIRE(all->size() == 3);
  CHECK((*all)[0].name == "tissue");
  CHECK((*all)[0].parent == 0);
  CHECK((*all)[1].parent == (*ids)[0]);
  CHECK((*all)[2].parent == (*ids)[0]);
  CHECK((*all)[2].triangles == 2);
  CHECK((*all)[2].vertices == 4);
  CHECK((*all)[2].color[3] == 0.5);
  // Geometry comes back exactly (doubles), renumbered per part.
  auto b = (*store)->mesh_geometry((*ids)[2]);
  REQUIRE(b.is_ok());
  REQUIRE(b->triangles.size() == 2);
  for (size_t t = 0; t < 2; ++t)
    for (int k = 0; k < 3; ++k)
      CHECK(b->positions[b->triangles[t][k]] == obj->mesh.positions[obj->mesh.triangles[1 + t][k]]);
  // The real OBJ file round-trips too.
  auto ico = read_obj(kTestdata + "/obj/ico4.obj");
  REQUIRE(ico.is_ok());
  auto ico_ids = (*store)->add_meshes(ico->mesh);
  REQUIRE(ico_ids.is_ok());
  auto back = (*store)->mesh_geometry(ico_ids->front());
  REQUIRE(back.is_ok());
  CHECK(back->positions.size() == ico->mesh.positions.size());
  REQUIRE(back->triangles.size() == ico->mesh.triangles.size());
  bool same = true;
  for (size_t t = 0; t < back->triangles.size(); ++t)
    for (int k = 0; k < 3; ++k)
      same = same && back->positions[back->triangles[t][k]] == ico->mesh.positions[ico->mesh.triangles[t][k]];
  CHECK(same);
  // Deleting the tissue removes its cells in the same batch.
  REQUIRE((*store)->delete_mesh((*ids)[0]));
  CHECK((*store)->meshes()->size() == 1);
  CHECK((*store)->mesh_geometry((*ids)[1]).status().code() == ErrorCode::kNotFound);
  store->reset();
  {  // Damage one geometry value behind the store's back.
    leveldb::DB* db = nullptr;
    REQUIRE(leveldb::DB::Open(leveldb::Options(), dir, &db).ok());
    char key[32];
    std::snprintf(key, sizeof key, "meshdata/%016llx", (unsigned long long)ico_ids->front());
    REQUIRE(db->Put(leveldb::WriteOptions(), key, std::string(20, 'x')).ok());
    delete db;
  }
  auto reopened = AnnotationStore::open(dir, false);
  REQUIRE(reopened.is_ok());
  const Status damaged = (*reopened)->mesh_geometry(ico_ids->front()).status();
  CHECK(damaged.code() == ErrorCode::kCorrupt);
  CHECK(damaged.message().find("meshdata/") != std::string::npos);
}
