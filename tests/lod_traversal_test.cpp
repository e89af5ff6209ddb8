// CPU octree traversal: level choice by angular resolution, culling, empty
// skipping, front-to-back order, parent fallback, frame budget.
#include <doctest/doctest.h>

#include <algorithm>
#include <cmath>
#include <set>

#include "render/camera.h"
#include "render/lod/lod_traversal.h"
#include "volume/procedural_source.h"

using namespace vxr;

namespace {

std::unique_ptr<ProceduralSource> make(uint64_t side) {
  ProceduralOptions o;
  o.dims = {side, side, side};
  auto r = ProceduralSource::create(o);
  REQUIRE(r.is_ok());
  return std::move(r).value();
}

LodView view_of(const ChunkSource& src, const Camera& cam, uint32_t w, uint32_t h) {
  const VolumePlacement pl{{uint32_t(src.info().dims[0]), uint32_t(src.info().dims[1]), uint32_t(src.info().dims[2])},
                           {1, 1, 1}};
  const VoxelSpaceRays r = rays_in_voxel_space(cam, pl, w, h);
  return {r.eye, r.forward, r.right, r.up, w, h};
}

// Visible: some payload voxel above 8 (the tests' stand-in for a transfer function).
LodQueries all_resident(const ChunkSource& src) {
  LodQueries q;
  q.visible = [&src](const ChunkKey& k) {
    auto st = src.stats(k);
    return !st || st->max > 8;
  };
  q.resident = [](const ChunkKey&) { return true; };
  return q;
}

double volume_of(const ChunkSource& src, const std::vector<ChunkKey>& keys) {
  double v = 0;
  for (const ChunkKey& k : keys) {
    const BrickBox b = chunk_box(src, k);
    v += (b.hi.x - b.lo.x) * (b.hi.y - b.lo.y) * (b.hi.z - b.lo.z);
  }
  return v;
}

// Ray-box entry/exit, double.
bool hit(const BrickBox& b, const glm::dvec3& o, const glm::dvec3& d, double& t0, double& t1) {
  t0 = 0, t1 = 1e300;
  for (int a = 0; a < 3; ++a) {
    if (d[a] == 0) {
      if (o[a] < b.lo[a] || o[a] > b.hi[a]) return false;
      continue;
    }
    double ta = (b.lo[a] - o[a]) / d[a], tb = (b.hi[a] - o[a]) / d[a];
    if (ta > tb) std::swap(ta, tb);
    t0 = std::max(t0, ta), t1 = std::min(t1, tb);
  }
  return t1 > t0;
}

}  // namespace

TEST_CASE("lod: the level follows the distance, and a 65536^3 volume from afar draws as few bricks as 256^3") {
  auto small = make(256), big = make(65536);
  LodSettings s;
  s.skip_empty = false;
  const auto q = all_resident(*small);  // skip_empty is off: visible is never asked
  const Camera cs = orbit_camera({{256, 256, 256}, {1, 1, 1}}, 30, 25, 1.6);
  const Camera cb = orbit_camera({{65536, 65536, 65536}, {1, 1, 1}}, 30, 25, 1.6);
  const LodResult a = traverse_lod(*small, view_of(*small, cs, 128, 128), s, q);
  const LodResult b = traverse_lod(*big, view_of(*big, cb, 128, 128), s, q);
  // 128 pixels over a volume seen at 1.6x its diagonal: ~ 64^3 voxels are enough.
  std::set<uint32_t> la, lb;
  for (const auto& k : a.draw) la.insert(k.level);
  for (const auto& k : b.draw) lb.insert(k.level);
  CHECK(*la.rbegin() <= 3);
  CHECK(*lb.begin() >= 9);  // never level 0..8 of the big one
  CHECK(b.draw.size() <= a.draw.size() * 3 / 2);
  CHECK(b.stats.visited <= a.stats.visited * 2 + 64);
  // The bricks tile the volume: nothing drawn twice, nothing left out.
  CHECK(volume_of(*small, a.draw) == doctest::Approx(256.0 * 256 * 256));
  CHECK(volume_of(*big, b.draw) == doctest::Approx(65536.0 * 65536 * 65536));
  // A positive bias halves the resolution.
  s.lod_bias = 1.0;
  const LodResult c = traverse_lod(*small, view_of(*small, cs, 128, 128), s, q);
  CHECK(c.draw.size() < a.draw.size());
}

TEST_CASE("lod: bricks come out front to back along every ray") {
  auto src = make(4096);
  LodSettings s;
  s.skip_empty = false;
  const Camera cam = orbit_camera({{4096, 4096, 4096}, {1, 1, 1}}, 40, 30, 0.45, 60);
  const LodView v = view_of(*src, cam, 128, 128);
  const LodResult r = traverse_lod(*src, v, s, all_resident(*src));
  std::set<uint32_t> levels;
  for (const auto& k : r.draw) levels.insert(k.level);
  CHECK(levels.size() >= 3);  // a close view mixes levels
  int checked = 0;
  for (int j = 0; j < 16; ++j)
    for (int i = 0; i < 16; ++i) {
      const double nx = (i + 0.5) / 16 * 2 - 1, ny = (j + 0.5) / 16 * 2 - 1;
      const glm::dvec3 d = glm::normalize(v.forward + nx * v.right - ny * v.up);
      double last_exit = 0;
      for (const auto& k : r.draw) {
        double t0, t1;
        if (!hit(chunk_box(*src, k), v.eye, d, t0, t1)) continue;
        CHECK(t0 >= last_exit - 1e-6);
        last_exit = t1;
        ++checked;
      }
    }
  CHECK(checked > 100);
}

TEST_CASE("lod: frustum, cut plane and ROI cull whole bricks, and empty bricks are skipped") {
  auto src = make(256);
  const Camera cam = orbit_camera({{256, 256, 256}, {1, 1, 1}}, 30, 25, 0.5, 30);
  const LodView v = view_of(*src, cam, 128, 128);
  LodSettings s;
  s.skip_empty = false;
  s.force_level = 0;
  const LodResult all = traverse_lod(*src, v, s, all_resident(*src));
  CHECK(all.stats.culled > 0);
  CHECK(all.draw.size() < 512u);
  s.frustum_cull = false;
  const LodResult nocull = traverse_lod(*src, v, s, all_resident(*src));
  CHECK(nocull.draw.size() == 512u);

  s.cut = {true, glm::normalize(glm::dvec3(1, 1, 0)), -256.0};  // keeps x + y >= 256 * sqrt(2)
  const LodResult cut = traverse_lod(*src, v, s, all_resident(*src));
  for (const auto& k : cut.draw) {
    const BrickBox b = chunk_box(*src, k);
    CHECK(b.hi.x + b.hi.y >= 256.0 * std::sqrt(2.0) - 1e-9);
  }
  CHECK(cut.draw.size() < 512u * 3 / 4);

  s.cut.enabled = false;
  s.roi = {true, {64, 64, 64}, {128, 100, 192}};
  const LodResult roi = traverse_lod(*src, v, s, all_resident(*src));
  CHECK(roi.draw.size() == 2u * 2u * 4u);  // x 64..128, y 64..100 -> 2 chunks, z 64..192 -> 4

  s.roi.enabled = false;
  s.skip_empty = true;
  const LodResult skip = traverse_lod(*src, v, s, all_resident(*src));
  CHECK(skip.stats.skipped_empty > 0);
  CHECK(skip.draw.size() + skip.stats.skipped_empty == nocull.draw.size());
  for (const auto& k : skip.draw) CHECK(src->stats(k)->max > 8);
}

TEST_CASE("lod: missing bricks are requested and their resident ancestor drawn, never a hole") {
  auto src = make(512);
  const Camera cam = orbit_camera({{512, 512, 512}, {1, 1, 1}}, 30, 25, 1.0);
  const LodView v = view_of(*src, cam, 256, 256);
  LodSettings s;
  s.skip_empty = false;
  s.frustum_cull = false;
  std::set<std::tuple<uint32_t, uint32_t, uint32_t, uint32_t>> resident;
  const uint32_t top = static_cast<uint32_t>(src->levels().size()) - 1;
  resident.insert({top, 0, 0, 0});
  LodQueries q = all_resident(*src);
  q.resident = [&](const ChunkKey& k) { return resident.count({k.level, k.x, k.y, k.z}) != 0; };
  const LodResult full = traverse_lod(*src, v, s, all_resident(*src));
  int frames = 0;
  for (; frames < 40; ++frames) {
    const LodResult r = traverse_lod(*src, v, s, q);
    for (const auto& k : r.draw) CHECK(q.resident(k));
    CHECK(volume_of(*src, r.draw) == doctest::Approx(512.0 * 512 * 512));  // complete every frame
    if (r.requests.empty()) {
      CHECK(r.draw.size() == full.draw.size());
      CHECK(r.stats.fallback == 0);
      break;
    }
    CHECK(r.stats.fallback > 0);
    CHECK(r.stats.missing == r.requests.size());
    for (size_t i = 0; i < std::min<size_t>(r.requests.size(), 32); ++i)  // a throttled upload
      resident.insert({r.requests[i].level, r.requests[i].x, r.requests[i].y, r.requests[i].z});
  }
  CHECK(frames > 1);
  CHECK(frames < 40);
}

TEST_CASE("lod: frame-budget mode moves the bias until the frame time meets the target") {
  FrameBudget fb;
  fb.target_ms = 10.0;
  double ms = 0;
  for (int i = 0; i < 12; ++i) {
    ms = 40.0 * std::exp2(-fb.bias);  // work halves per +1 bias
    fb.update(ms);
  }
  CHECK(ms == doctest::Approx(10.0).epsilon(0.02));
  CHECK(fb.bias == doctest::Approx(2.0).epsilon(0.02));
  fb.update(1e9);
  CHECK(fb.bias <= fb.max_bias);
}
