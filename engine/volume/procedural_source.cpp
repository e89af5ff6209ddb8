#include "volume/procedural_source.h"

#include <algorithm>
#include <cmath>
#include <string>

namespace vxr {
namespace {

// splitmix64: portable, so the same seed gives the same volume everywhere.
struct Rng {
  uint64_t s;
  uint64_t next() {
    uint64_t z = (s += 0x9e3779b97f4a7c15ull);
    z = (z ^ (z >> 30)) * 0xbf58476d1ce4e5b9ull;
    z = (z ^ (z >> 27)) * 0x94d049bb133111ebull;
    return z ^ (z >> 31);
  }
  double uniform() { return double(next() >> 11) * (1.0 / 9007199254740992.0); }  // [0, 1)
};

uint64_t hash64(uint64_t a, uint64_t b, uint64_t c, uint64_t d, uint64_t e) {
  Rng r{a * 0x9e3779b97f4a7c15ull ^ b};
  r.s ^= r.next() + c;
  r.s ^= r.next() + d;
  r.s ^= r.next() + e;
  return r.next();
}

using V3 = std::array<double, 3>;
double dot(const V3& a, const V3& b) { return a[0] * b[0] + a[1] * b[1] + a[2] * b[2]; }
V3 sub(const V3& a, const V3& b) { return {a[0] - b[0], a[1] - b[1], a[2] - b[2]}; }

double point_segment_dist(const V3& p, const V3& a, const V3& b) {
  const V3 ab = sub(b, a), ap = sub(p, a);
  const double len2 = dot(ab, ab);
  double t = len2 > 0 ? std::clamp(dot(ap, ab) / len2, 0.0, 1.0) : 0.0;
  const V3 q{a[0] + t * ab[0] - p[0], a[1] + t * ab[1] - p[1], a[2] + t * ab[2] - p[2]};
  return std::sqrt(dot(q, q));
}

double point_box_dist(const V3& p, const V3& lo, const V3& hi) {
  double d2 = 0;
  for (int i = 0; i < 3; ++i) {
    const double e = std::max({lo[i] - p[i], 0.0, p[i] - hi[i]});
    d2 += e * e;
  }
  return std::sqrt(d2);
}

// A lower bound on the distance between a box and a segment: the segment is
// sampled every len/16; every point of it is within len/32 of a sample.
double box_segment_dist_lower(const V3& lo, const V3& hi, const V3& a, const V3& b) {
  constexpr int kN = 16;
  const double len = std::sqrt(dot(sub(b, a), sub(b, a)));
  double best = 1e300;
  for (int k = 0; k <= kN; ++k) {
    const double t = double(k) / kN;
    const V3 p{a[0] + t * (b[0] - a[0]), a[1] + t * (b[1] - a[1]), a[2] + t * (b[2] - a[2])};
    best = std::min(best, point_box_dist(p, lo, hi));
  }
  return std::max(0.0, best - len / (2.0 * kN));
}

// Distance to a segment is convex, so its maximum over a box is at a corner.
double box_segment_dist_upper(const V3& lo, const V3& hi, const V3& a, const V3& b) {
  double best = 0;
  for (int c = 0; c < 8; ++c) {
    const V3 p{(c & 1) ? hi[0] : lo[0], (c & 2) ? hi[1] : lo[1], (c & 4) ? hi[2] : lo[2]};
    best = std::max(best, point_segment_dist(p, a, b));
  }
  return best;
}

constexpr uint64_t kMaxSide = 1ull << 17;
constexpr int kOccGrid = 8;

}  // namespace

Result<std::unique_ptr<ProceduralSource>> ProceduralSource::create(const ProceduralOptions& o) {
  for (int i = 0; i < 3; ++i)
    if (o.dims[i] == 0 || o.dims[i] > kMaxSide)
      return invalid_argument("procedural volume: each side must be 1.." + std::to_string(kMaxSide) + " voxels, not " +
                              std::to_string(o.dims[i]));
  if (o.chunk_size < 8 || o.chunk_size > 256)
    return invalid_argument("procedural volume: chunk size must be 8..256, not " + std::to_string(o.chunk_size));
  if (o.apron > 4) return invalid_argument("procedural volume: apron must be 0..4 voxels");
  if (!(o.occupancy > 0.0 && o.occupancy <= 1.0))
    return invalid_argument("procedural volume: occupancy must be in (0, 1]");
  if (o.noise_max > 64) return invalid_argument("procedural volume: noise_max must be 0..64");
  std::unique_ptr<ProceduralSource> s(new ProceduralSource(o));
  s->build_levels();
  s->grow_vessels();
  s->build_grid();
  return s;
}

void ProceduralSource::build_levels() {
  info_.dims = opt_.dims;
  info_.dtype = DType::kU8;
  info_.unit = "px";
  const uint64_t max_side = std::max({opt_.dims[0], opt_.dims[1], opt_.dims[2]});
  inv_max_side_ = 1.0 / double(max_side);
  for (int i = 0; i < 3; ++i) extent_[i] = double(opt_.dims[i]) * inv_max_side_;
  for (uint32_t l = 0;; ++l) {
    LevelInfo li;
    const uint64_t f = 1ull << l;
    for (int i = 0; i < 3; ++i) {
      li.dims[i] = (opt_.dims[i] + f - 1) / f;
      li.chunk_counts[i] = static_cast<uint32_t>((li.dims[i] + opt_.chunk_size - 1) / opt_.chunk_size);
      li.downsample[i] = static_cast<uint32_t>(f);
    }
    levels_.push_back(li);
    if (std::max({li.dims[0], li.dims[1], li.dims[2]}) <= opt_.chunk_size) break;
  }
}

void ProceduralSource::level_profile(const Segment& s, uint32_t level, double& sigma, double& amp) const {
  const double voxel = double(1ull << level) * inv_max_side_;
  const double s2 = s.sigma * s.sigma + voxel * voxel / 12.0;  // a box of one voxel: what 2x averaging telescopes to
  sigma = std::sqrt(s2);
  amp = s.amp * (s.sigma * s.sigma) / s2;
}

double ProceduralSource::cutoff(double sigma, double amp) const {
  // 255 * amp * exp(-d^2 / (2 sigma^2)) < 0.5  <=>  d > sigma * sqrt(2 ln(510 amp))
  const double k = 510.0 * amp;
  return k <= 1.0 ? 0.0 : sigma * std::sqrt(2.0 * std::log(k));
}

void ProceduralSource::grow_vessels() {
  Rng rng{opt_.seed * 0x2545F4914F6CDD1Dull + 12345};
  std::vector<uint8_t> occ(kOccGrid * kOccGrid * kOccGrid, 0);
  size_t occupied = 0;
  const size_t target = static_cast<size_t>(std::ceil(opt_.occupancy * occ.size()));
  V3 cell;
  for (int i = 0; i < 3; ++i) cell[i] = extent_[i] / kOccGrid;

  auto mark = [&](const Segment& s) {
    double sigma, amp;
    level_profile(s, 0, sigma, amp);
    const double cut = cutoff(sigma, amp);
    std::array<int, 3> c0, c1;
    for (int i = 0; i < 3; ++i) {
      const double lo = std::min(s.a[i], s.b[i]) - cut, hi = std::max(s.a[i], s.b[i]) + cut;
      c0[i] = std::clamp(int(std::floor(lo / cell[i])), 0, kOccGrid - 1);
      c1[i] = std::clamp(int(std::floor(hi / cell[i])), 0, kOccGrid - 1);
    }
    for (int z = c0[2]; z <= c1[2]; ++z)
      for (int y = c0[1]; y <= c1[1]; ++y)
        for (int x = c0[0]; x <= c1[0]; ++x) {
          uint8_t& o = occ[(size_t(z) * kOccGrid + y) * kOccGrid + x];
          if (o) continue;
          const V3 lo{x * cell[0], y * cell[1], z * cell[2]};
          const V3 hi{lo[0] + cell[0], lo[1] + cell[1], lo[2] + cell[2]};
          if (box_segment_dist_lower(lo, hi, s.a, s.b) <= cut) {
            o = 1;
            ++occupied;
          }
        }
  };
  auto random_unit = [&] {
    for (;;) {
      V3 v{rng.uniform() * 2 - 1, rng.uniform() * 2 - 1, rng.uniform() * 2 - 1};
      const double n = std::sqrt(dot(v, v));
      if (n > 1e-3 && n <= 1.0) return V3{v[0] / n, v[1] / n, v[2] / n};
    }
  };

  struct Branch {
    V3 pos, dir;
    double sigma;
    int steps;
  };
  const double seg_len = 0.025;
  while (occupied < target && segs_.size() < 200000) {
    std::vector<Branch> stack;
    const V3 root{rng.uniform() * extent_[0], rng.uniform() * extent_[1], rng.uniform() * extent_[2]};
    stack.push_back({root, random_unit(), opt_.radius * (0.6 + 0.4 * rng.uniform()), 0});
    const double amp = 0.75 + 0.25 * rng.uniform();
    while (!stack.empty() && occupied < target) {
      Branch b = stack.back();
      stack.pop_back();
      while (b.steps < 80 && b.sigma > 0.2 * opt_.radius && occupied < target) {
        const V3 j = random_unit();
        V3 d{b.dir[0] + 0.35 * j[0], b.dir[1] + 0.35 * j[1], b.dir[2] + 0.35 * j[2]};
        const double n = std::sqrt(dot(d, d));
        for (double& c : d) c /= n;
        const V3 end{b.pos[0] + seg_len * d[0], b.pos[1] + seg_len * d[1], b.pos[2] + seg_len * d[2]};
        bool inside = true;
        for (int i = 0; i < 3; ++i) inside = inside && end[i] >= 0.0 && end[i] <= extent_[i];
        if (!inside) break;
        Segment s{b.pos, end, b.sigma, amp};
        segs_.push_back(s);
        mark(s);
        max_sigma_ = std::max(max_sigma_, s.sigma);
        b.pos = end;
        b.dir = d;
        b.sigma *= 0.985;
        ++b.steps;
        if (rng.uniform() < 0.10) {
          const V3 k = random_unit();
          V3 cd{d[0] + 0.9 * k[0], d[1] + 0.9 * k[1], d[2] + 0.9 * k[2]};
          const double cn = std::sqrt(dot(cd, cd));
          for (double& c : cd) c /= cn;
          stack.push_back({end, cd, b.sigma * 0.7, 0});
        }
      }
    }
  }
  occupancy_ = double(occupied) / double(occ.size());
}

void ProceduralSource::build_grid() {
  grid_.assign(size_t(kGrid) * kGrid * kGrid, {});
  for (uint32_t id = 0; id < segs_.size(); ++id) {
    const Segment& s = segs_[id];
    std::array<int, 3> c0, c1;
    for (int i = 0; i < 3; ++i) {
      const double cell = extent_[i] / kGrid;
      c0[i] = std::clamp(int(std::floor(std::min(s.a[i], s.b[i]) / cell)), 0, kGrid - 1);
      c1[i] = std::clamp(int(std::floor(std::max(s.a[i], s.b[i]) / cell)), 0, kGrid - 1);
    }
    for (int z = c0[2]; z <= c1[2]; ++z)
      for (int y = c0[1]; y <= c1[1]; ++y)
        for (int x = c0[0]; x <= c1[0]; ++x) grid_[(size_t(z) * kGrid + y) * kGrid + x].push_back(id);
  }
}

void ProceduralSource::candidates(const Box& box, double pad, std::vector<uint32_t>& out) const {
  out.clear();
  std::array<int, 3> c0, c1;
  for (int i = 0; i < 3; ++i) {
    const double cell = extent_[i] / kGrid;
    c0[i] = std::clamp(int(std::floor((box.lo[i] - pad) / cell)), 0, kGrid - 1);
    c1[i] = std::clamp(int(std::floor((box.hi[i] + pad) / cell)), 0, kGrid - 1);
  }
  for (int z = c0[2]; z <= c1[2]; ++z)
    for (int y = c0[1]; y <= c1[1]; ++y)
      for (int x = c0[0]; x <= c1[0]; ++x) {
        const auto& cell = grid_[(size_t(z) * kGrid + y) * kGrid + x];
        out.insert(out.end(), cell.begin(), cell.end());
      }
  std::sort(out.begin(), out.end());
  out.erase(std::unique(out.begin(), out.end()), out.end());
}

ProceduralSource::Box ProceduralSource::payload_box(const ChunkKey& key) const {
  const LevelInfo& li = levels_[key.level];
  const double f = double(1ull << key.level) * inv_max_side_;
  const std::array<uint32_t, 3> c{key.x, key.y, key.z};
  Box b;
  for (int i = 0; i < 3; ++i) {
    const int64_t first = int64_t(c[i]) * opt_.chunk_size - opt_.apron;
    const int64_t last = int64_t(c[i] + 1) * opt_.chunk_size + opt_.apron - 1;
    const int64_t lo = std::clamp<int64_t>(first, 0, int64_t(li.dims[i]) - 1);
    const int64_t hi = std::clamp<int64_t>(last, 0, int64_t(li.dims[i]) - 1);
    b.lo[i] = (double(lo) + 0.5) * f;
    b.hi[i] = (double(hi) + 0.5) * f;
  }
  return b;
}

Result<ChunkStats> ProceduralSource::stats(const ChunkKey& key) const {
  if (key.level >= levels_.size() || key.channel != 0 || key.timepoint != 0)
    return not_found("procedural volume: no chunk at level " + std::to_string(key.level));
  const LevelInfo& li = levels_[key.level];
  if (key.x >= li.chunk_counts[0] || key.y >= li.chunk_counts[1] || key.z >= li.chunk_counts[2])
    return not_found("procedural volume: chunk outside level " + std::to_string(key.level));
  {
    std::lock_guard<std::mutex> lock(stats_mu_);
    if (auto it = stats_cache_.find(key); it != stats_cache_.end()) return it->second;
  }
  const Box box = payload_box(key);
  Segment widest{{0, 0, 0}, {0, 0, 0}, max_sigma_, 1.0};
  double sig, amp;
  level_profile(widest, key.level, sig, amp);
  std::vector<uint32_t> ids;
  candidates(box, cutoff(sig, amp), ids);
  double tmax = 0.0, tmin = 0.0;
  for (uint32_t id : ids) {
    const Segment& s = segs_[id];
    level_profile(s, key.level, sig, amp);
    const double cut = cutoff(sig, amp);
    const double dlo = box_segment_dist_lower(box.lo, box.hi, s.a, s.b);
    if (dlo > cut) continue;
    tmax = std::max(tmax, amp * std::exp(-dlo * dlo / (2 * sig * sig)));
    const double dhi = box_segment_dist_upper(box.lo, box.hi, s.a, s.b);
    if (dhi <= cut) tmin = std::max(tmin, amp * std::exp(-dhi * dhi / (2 * sig * sig)));
  }
  ChunkStats st;
  st.min = std::floor(255.0 * tmin);
  st.max = std::min(255.0, double(opt_.noise_max) + std::ceil(255.0 * tmax));
  if (st.min > st.max) st.min = st.max;
  std::lock_guard<std::mutex> lock(stats_mu_);
  if (stats_cache_.size() >= kStatsCacheEntries) stats_cache_.clear();
  stats_cache_.emplace(key, st);
  return st;
}

uint8_t ProceduralSource::voxel(uint32_t level, int64_t x, int64_t y, int64_t z) const {
  const LevelInfo& li = levels_[std::min<size_t>(level, levels_.size() - 1)];
  const std::array<int64_t, 3> idx{std::clamp<int64_t>(x, 0, li.dims[0] - 1), std::clamp<int64_t>(y, 0, li.dims[1] - 1),
                                   std::clamp<int64_t>(z, 0, li.dims[2] - 1)};
  const double f = double(1ull << level) * inv_max_side_;
  const V3 p{(idx[0] + 0.5) * f, (idx[1] + 0.5) * f, (idx[2] + 0.5) * f};
  Segment widest{{0, 0, 0}, {0, 0, 0}, max_sigma_, 1.0};
  double sig, amp;
  level_profile(widest, level, sig, amp);
  std::vector<uint32_t> ids;
  candidates({p, p}, cutoff(sig, amp), ids);
  double t = 0.0;
  for (uint32_t id : ids) {
    const Segment& s = segs_[id];
    level_profile(s, level, sig, amp);
    const double d = point_segment_dist(p, s.a, s.b);
    if (d > cutoff(sig, amp)) continue;
    t = std::max(t, amp * std::exp(-d * d / (2 * sig * sig)));
  }
  uint32_t v = static_cast<uint32_t>(std::lround(255.0 * t));
  if (opt_.noise_max)
    v += static_cast<uint32_t>(hash64(opt_.seed, level, idx[0], idx[1], idx[2]) % (opt_.noise_max + 1));
  return static_cast<uint8_t>(std::min<uint32_t>(v, 255));
}

Result<std::shared_ptr<const Chunk>> ProceduralSource::read(const ChunkKey& key) const {
  VXR_ASSIGN_OR_RETURN(ChunkStats st, stats(key));
  const LevelInfo& li = levels_[key.level];
  const uint32_t edge = opt_.chunk_size + 2 * opt_.apron;
  auto chunk = std::make_shared<Chunk>();
  chunk->key = key;
  chunk->edge = edge;
  chunk->dtype = DType::kU8;
  chunk->stats = st;
  chunk->data.assign(size_t(edge) * edge * edge, 0);

  // Clamped level indices and normalised centres of the payload, per axis.
  const double f = double(1ull << key.level) * inv_max_side_;
  const std::array<uint32_t, 3> c{key.x, key.y, key.z};
  std::array<std::vector<int64_t>, 3> idx;
  std::array<std::vector<double>, 3> pos;
  for (int a = 0; a < 3; ++a) {
    for (uint32_t i = 0; i < edge; ++i) {
      const int64_t v = std::clamp<int64_t>(int64_t(c[a]) * opt_.chunk_size + i - opt_.apron, 0, li.dims[a] - 1);
      idx[a].push_back(v);
      pos[a].push_back((double(v) + 0.5) * f);
    }
  }
  std::vector<double> tube(chunk->data.size(), 0.0);
  if (st.max > double(opt_.noise_max)) {  // some vessel reaches this chunk
    const Box box = payload_box(key);
    Segment widest{{0, 0, 0}, {0, 0, 0}, max_sigma_, 1.0};
    double sig, amp;
    level_profile(widest, key.level, sig, amp);
    std::vector<uint32_t> ids;
    candidates(box, cutoff(sig, amp), ids);
    for (uint32_t id : ids) {
      const Segment& s = segs_[id];
      level_profile(s, key.level, sig, amp);
      const double cut = cutoff(sig, amp);
      if (box_segment_dist_lower(box.lo, box.hi, s.a, s.b) > cut) continue;
      std::array<uint32_t, 3> r0, r1;
      for (int a = 0; a < 3; ++a) {
        const double lo = std::min(s.a[a], s.b[a]) - cut, hi = std::max(s.a[a], s.b[a]) + cut;
        r0[a] = static_cast<uint32_t>(std::lower_bound(pos[a].begin(), pos[a].end(), lo) - pos[a].begin());
        r1[a] = static_cast<uint32_t>(std::upper_bound(pos[a].begin(), pos[a].end(), hi) - pos[a].begin());
      }
      for (uint32_t z = r0[2]; z < r1[2]; ++z)
        for (uint32_t y = r0[1]; y < r1[1]; ++y)
          for (uint32_t x = r0[0]; x < r1[0]; ++x) {
            const double d = point_segment_dist({pos[0][x], pos[1][y], pos[2][z]}, s.a, s.b);
            if (d > cut) continue;
            double& t = tube[(size_t(z) * edge + y) * edge + x];
            t = std::max(t, amp * std::exp(-d * d / (2 * sig * sig)));
          }
    }
  }
  for (uint32_t z = 0; z < edge; ++z)
    for (uint32_t y = 0; y < edge; ++y)
      for (uint32_t x = 0; x < edge; ++x) {
        const size_t i = (size_t(z) * edge + y) * edge + x;
        uint32_t v = static_cast<uint32_t>(std::lround(255.0 * tube[i]));
        if (opt_.noise_max)
          v += static_cast<uint32_t>(hash64(opt_.seed, key.level, idx[0][x], idx[1][y], idx[2][z]) %
                                     (opt_.noise_max + 1));
        chunk->data[i] = static_cast<uint8_t>(std::min<uint32_t>(v, 255));
      }
  return std::shared_ptr<const Chunk>(std::move(chunk));
}

}  // namespace vxr
