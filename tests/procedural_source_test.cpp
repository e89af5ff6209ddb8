// The procedural vessel volume: deterministic, sparse, cheap and correct
// chunk statistics at any size, levels consistent with each other.
#include <doctest/doctest.h>

#include <chrono>
#include <cmath>

#include "volume/procedural_source.h"

using namespace vxr;

namespace {
std::unique_ptr<ProceduralSource> make(const ProceduralOptions& o) {
  auto r = ProceduralSource::create(o);
  REQUIRE(r.is_ok());
  return std::move(r).value();
}
}  // namespace

TEST_CASE("procedural: same seed gives the same voxels, another seed does not") {
  ProceduralOptions o;
  o.dims = {128, 128, 128};
  auto a = make(o), b = make(o);
  o.seed = 2;
  auto c = make(o);
  bool any_diff = false;
  for (uint32_t z = 0; z < 4; ++z)
    for (uint32_t x = 0; x < 4; ++x) {
      const ChunkKey k{0, x, 1, z};
      auto ca = a->read(k), cb = b->read(k), cc = c->read(k);
      REQUIRE(ca.is_ok());
      REQUIRE(cb.is_ok());
      REQUIRE(cc.is_ok());
      CHECK((*ca)->data == (*cb)->data);
      any_diff = any_diff || (*ca)->data != (*cc)->data;
    }
  CHECK(any_diff);
}

TEST_CASE("procedural: levels halve down to one chunk, edge 34 with apron 1") {
  ProceduralOptions o;
  o.dims = {300, 200, 100};
  auto s = make(o);
  REQUIRE(s->levels().size() == 5);  // 300 -> 150 -> 75 -> 38 -> 19
  CHECK(s->levels()[0].chunk_counts == std::array<uint32_t, 3>{10, 7, 4});
  CHECK(s->levels()[4].dims == std::array<uint64_t, 3>{19, 13, 7});
  CHECK(s->levels()[2].downsample == std::array<uint32_t, 3>{4, 4, 4});
  auto c = s->read({1, 4, 3, 1});
  REQUIRE(c.is_ok());
  CHECK((*c)->edge == 34);
  CHECK((*c)->data.size() == 34u * 34u * 34u);
  CHECK(s->read({1, 5, 0, 0}).status().code() == ErrorCode::kNotFound);
  CHECK(s->stats({9, 0, 0, 0}).status().code() == ErrorCode::kNotFound);
}

TEST_CASE("procedural: chunk stats bound every payload voxel, and empty chunks are exactly noise") {
  ProceduralOptions o;
  o.dims = {128, 96, 128};
  o.noise_max = 5;
  auto s = make(o);
  size_t empty = 0, total = 0, checked_tight = 0;
  for (uint32_t l = 0; l < s->levels().size(); ++l) {
    const auto& li = s->levels()[l];
    for (uint32_t z = 0; z < li.chunk_counts[2]; ++z)
      for (uint32_t y = 0; y < li.chunk_counts[1]; ++y)
        for (uint32_t x = 0; x < li.chunk_counts[0]; ++x) {
          auto st = s->stats({l, x, y, z});
          auto c = s->read({l, x, y, z});
          REQUIRE(st.is_ok());
          REQUIRE(c.is_ok());
          uint8_t lo = 255, hi = 0;
          for (uint8_t v : (*c)->data) lo = std::min(lo, v), hi = std::max(hi, v);
          CHECK(double(lo) >= st->min);
          CHECK(double(hi) <= st->max);
          ++total;
          if (st->max <= 5.0) ++empty;
          if (hi > 5 && st->max - hi <= 8) ++checked_tight;
        }
  }
  CHECK(empty > 0);
  CHECK(empty < total);
  CHECK(checked_tight > 0);  // the bound is not merely "0..255"
}

TEST_CASE("procedural: about 10% of the volume is occupied") {
  ProceduralOptions o;
  o.dims = {256, 256, 256};
  auto s = make(o);
  CHECK(s->measured_occupancy() >= 0.10);
  CHECK(s->measured_occupancy() < 0.13);
  size_t occupied = 0;
  const auto& li = s->levels()[0];
  for (uint32_t z = 0; z < li.chunk_counts[2]; ++z)
    for (uint32_t y = 0; y < li.chunk_counts[1]; ++y)
      for (uint32_t x = 0; x < li.chunk_counts[0]; ++x) occupied += s->stats({0, x, y, z})->max > 0 ? 1 : 0;
  const double frac = double(occupied) / (8.0 * 8 * 8);
  MESSAGE("level-0 chunks occupied: " << frac);
  CHECK(frac > 0.05);
  CHECK(frac < 0.25);
}

TEST_CASE("procedural: a 65536^3 volume has cheap stats and voxels that match the 256^3 one at its level 8") {
  ProceduralOptions small, big;
  small.dims = {256, 256, 256};
  big.dims = {65536, 65536, 65536};
  auto s = make(small), b = make(big);
  REQUIRE(b->levels().size() == 12);
  const auto t0 = std::chrono::steady_clock::now();
  const auto& li = b->levels()[6];  // 32^3 chunks
  size_t n = 0;
  for (uint32_t z = 0; z < li.chunk_counts[2]; z += 2)
    for (uint32_t y = 0; y < li.chunk_counts[1]; y += 2)
      for (uint32_t x = 0; x < li.chunk_counts[0]; x += 2) n += b->stats({6, x, y, z}).is_ok();
  const double ms = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
  CHECK(n == 16u * 16u * 16u);
  CHECK(ms < 3000.0);
  // Same field in normalised coordinates: level 8 of the big volume is 256^3,
  // filtered from a finer grid, so it differs from the small level 0 only
  // by the width of the level-0 filter.
  int maxdiff = 0;
  for (int i = 0; i < 256; i += 7) {
    const int d = std::abs(int(s->voxel(0, i, 128, 100)) - int(b->voxel(8, i, 128, 100)));
    maxdiff = std::max(maxdiff, d);
  }
  CHECK(maxdiff <= 24);
}

TEST_CASE("procedural: level 1 is close to the 2x2x2 average of level 0") {
  ProceduralOptions o;
  o.dims = {128, 128, 128};
  auto s = make(o);
  double sum_abs = 0, sum_val = 0;
  int n = 0;
  for (int z = 0; z < 64; z += 3)
    for (int y = 0; y < 64; y += 3)
      for (int x = 0; x < 64; x += 3) {
        double avg = 0;
        for (int k = 0; k < 8; ++k) avg += s->voxel(0, 2 * x + (k & 1), 2 * y + ((k >> 1) & 1), 2 * z + (k >> 2));
        avg /= 8;
        if (avg < 10) continue;  // compare where there is signal
        const double v = s->voxel(1, x, y, z);
        sum_abs += std::abs(v - avg);
        sum_val += avg;
        ++n;
      }
  REQUIRE(n > 20);
  MESSAGE("mean |level1 - avg(level0)| = " << sum_abs / n << " of mean " << sum_val / n);
  CHECK(sum_abs < 0.15 * sum_val);  // small next to the signal
}

TEST_CASE("procedural: bad sizes are refused with the setting named") {
  ProceduralOptions o;
  o.dims = {256, 0, 256};
  auto r = ProceduralSource::create(o);
  CHECK(r.status().code() == ErrorCode::kInvalidArgument);
  o.dims = {1u << 18, 16, 16};
  CHECK(ProceduralSource::create(o).status().message().find("131072") != std::string::npos);
  o.dims = {64, 64, 64};
  o.occupancy = 0;
  CHECK(ProceduralSource::create(o).status().message().find("occupancy") != std::string::npos);
}
