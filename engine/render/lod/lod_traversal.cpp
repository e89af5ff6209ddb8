#include "render/lod/lod_traversal.h"

#include <algorithm>
#include <array>
#include <cmath>

namespace vxr {
namespace {

struct Plane {
  glm::dvec3 n;
  double d;  // keeps dot(n, p) + d >= 0
};

// Node = a chunk at a real level, or a block of top-level chunks at a virtual
// level above the pyramid.
struct Node {
  uint32_t level;
  std::array<uint32_t, 3> c;
};

class Traversal {
 public:
  Traversal(const ChunkSource& src, const LodView& view, const LodSettings& s, const LodQueries& q)
      : src_(src), view_(view), s_(s), q_(q) {
    const auto& levels = src.levels();
    top_ = static_cast<uint32_t>(levels.size()) - 1;
    cs_ = src.chunk_size();
    dims0_ = glm::dvec3(src.info().dims[0], src.info().dims[1], src.info().dims[2]);
    // Virtual levels double everything until one node covers the volume.
    ds_.clear();
    counts_.clear();
    for (const auto& li : levels) {
      ds_.push_back(glm::dvec3(li.downsample[0], li.downsample[1], li.downsample[2]));
      counts_.push_back(li.chunk_counts);
    }
    while (counts_.back()[0] > 1 || counts_.back()[1] > 1 || counts_.back()[2] > 1) {
      auto c = counts_.back();
      for (auto& v : c) v = (v + 1) / 2;
      counts_.push_back(c);
      ds_.push_back(ds_.back() * 2.0);
    }
    // Pixel angle: the image's vertical extent at unit distance over its rows.
    const double fwd_len = glm::length(view.forward);
    pixel_angle_ = 2.0 * glm::length(view.up) / fwd_len / double(view.height);
    bias_scale_ = std::exp2(s.lod_bias);
    force_ = s.force_level < 0 ? -1 : std::min<int>(s.force_level, int(top_));
    if (s.frustum_cull) build_frustum();
  }

  LodResult run() {
    visit({static_cast<uint32_t>(counts_.size()) - 1, {0, 0, 0}});
    return std::move(out_);
  }

 private:
  bool real(const Node& n) const { return n.level <= top_; }
  ChunkKey key(const Node& n) const { return {n.level, n.c[0], n.c[1], n.c[2], 0, s_.timepoint}; }

  BrickBox box(const Node& n) const {
    BrickBox b;
    // Virtual nodes span 2^k top-level chunks; their size comes from the top level's.
    const glm::dvec3 edge = double(cs_) * ds_[n.level];
    for (int a = 0; a < 3; ++a) {
      b.lo[a] = std::min(double(n.c[a]) * edge[a], dims0_[a]);
      b.hi[a] = std::min(double(n.c[a] + 1) * edge[a], dims0_[a]);
    }
    return b;
  }

  void build_frustum() {
    const glm::dvec3 f = view_.forward, r = view_.right, u = view_.up;
    const std::array<glm::dvec3, 4> corner{f - r - u, f + r - u, f + r + u, f - r + u};
    for (int i = 0; i < 4; ++i) {
      glm::dvec3 n = glm::cross(corner[i], corner[(i + 1) % 4]);
      if (glm::dot(n, f) < 0) n = -n;
      frustum_.push_back({n, -glm::dot(n, view_.eye)});
    }
    frustum_.push_back({f, -glm::dot(f, view_.eye)});  // in front of the eye
  }

  static bool outside(const Plane& p, const BrickBox& b) {
    // The box corner farthest along the normal: if even it is behind, all are.
    const glm::dvec3 v(p.n.x >= 0 ? b.hi.x : b.lo.x, p.n.y >= 0 ? b.hi.y : b.lo.y, p.n.z >= 0 ? b.hi.z : b.lo.z);
    return glm::dot(p.n, v) + p.d < 0;
  }

  bool culled(const BrickBox& b) const {
    for (const Plane& p : frustum_)
      if (outside(p, b)) return true;
    if (s_.cut.enabled && outside({s_.cut.normal, s_.cut.offset}, b)) return true;
    if (s_.roi.enabled)
      for (int a = 0; a < 3; ++a)
        if (b.hi[a] <= s_.roi.lo[a] || b.lo[a] >= s_.roi.hi[a]) return true;
    return false;
  }

  // The paper's criterion: angle of one voxel at the nearest point of the box.
  bool wants_finer(const Node& n, const BrickBox& b) const {
    if (n.level == 0) return false;
    if (!real(n)) return true;
    if (force_ >= 0) return int(n.level) > force_;
    const glm::dvec3 nearest = glm::clamp(view_.eye, b.lo, b.hi);
    const double dist = glm::length(nearest - view_.eye);
    const double voxel = std::max({ds_[n.level].x, ds_[n.level].y, ds_[n.level].z});
    if (dist <= 0.0) return true;
    return voxel / dist > pixel_angle_ * bias_scale_;
  }

  bool empty(const Node& n) {
    if (!s_.skip_empty || !real(n)) return false;
    return !q_.visible(key(n));
  }

  std::vector<Node> children(const Node& n) const {
    const uint32_t cl = n.level - 1;
    std::array<uint32_t, 3> r;
    for (int a = 0; a < 3; ++a) r[a] = static_cast<uint32_t>(std::lround(ds_[n.level][a] / ds_[cl][a]));
    // Octant order: the child on the eye's side of each split first.
    uint32_t near_mask = 0;
    for (int a = 0; a < 3; ++a) {
      const double split = double(n.c[a] * r[a] + 1) * double(cs_) * ds_[cl][a];
      if (r[a] == 2 && view_.eye[a] >= split) near_mask |= 1u << a;
    }
    std::vector<Node> out;
    for (uint32_t i = 0; i < 8; ++i) {
      const uint32_t o = i ^ near_mask;
      Node c{cl, {0, 0, 0}};
      bool ok = true;
      for (int a = 0; a < 3; ++a) {
        const uint32_t bit = (o >> a) & 1u;
        if (bit && r[a] == 1) ok = false;
        c.c[a] = n.c[a] * r[a] + bit;
        if (c.c[a] >= counts_[cl][a]) ok = false;
      }
      if (ok) out.push_back(c);
    }
    return out;
  }

  void draw(const Node& n, bool fallback) {
    const ChunkKey k = key(n);
    if (!q_.resident(k)) {  // only the top level can get here; callers pin it
      ++out_.stats.missing;
      out_.requests.push_back(k);
      return;
    }
    out_.draw.push_back(k);
    ++out_.stats.drawn;
    if (fallback) ++out_.stats.fallback;
  }

  void visit(const Node& n) {
    ++out_.stats.visited;
    const BrickBox b = box(n);
    if (b.hi.x <= b.lo.x || b.hi.y <= b.lo.y || b.hi.z <= b.lo.z) return;
    if (culled(b)) {
      ++out_.stats.culled;
      return;
    }
    if (!wants_finer(n, b)) {
      if (empty(n)) {
        ++out_.stats.skipped_empty;
        return;
      }
      draw(n, false);
      return;
    }
    const std::vector<Node> kids = children(n);
    bool ready = true;
    if (real(n)) {
      for (const Node& c : kids) {
        const BrickBox cb = box(c);
        if (culled(cb) || q_.resident(key(c))) continue;
        if (!wants_finer(c, cb) && empty(c)) continue;
        ++out_.stats.missing;
        out_.requests.push_back(key(c));
        ready = false;
      }
    }
    if (!ready) {
      draw(n, true);
      return;
    }
    for (const Node& c : kids) visit(c);
  }

  const ChunkSource& src_;
  const LodView& view_;
  const LodSettings& s_;
  const LodQueries& q_;
  uint32_t top_ = 0, cs_ = 0;
  glm::dvec3 dims0_{0};
  std::vector<glm::dvec3> ds_;
  std::vector<std::array<uint32_t, 3>> counts_;
  double pixel_angle_ = 0.0, bias_scale_ = 1.0;
  int force_ = -1;
  std::vector<Plane> frustum_;
  LodResult out_;
};

}  // namespace

BrickBox chunk_box(const ChunkSource& src, const ChunkKey& key) {
  const auto& li = src.levels()[key.level];
  const std::array<uint32_t, 3> c{key.x, key.y, key.z};
  BrickBox b;
  for (int a = 0; a < 3; ++a) {
    const double edge = double(src.chunk_size()) * li.downsample[a];
    const double dim = double(src.info().dims[a]);
    b.lo[a] = std::min(double(c[a]) * edge, dim);
    b.hi[a] = std::min(double(c[a] + 1) * edge, dim);
  }
  return b;
}

LodResult traverse_lod(const ChunkSource& src, const LodView& view, const LodSettings& settings,
                       const LodQueries& queries) {
  return Traversal(src, view, settings, queries).run();
}

double FrameBudget::update(double frame_ms) {
  if (frame_ms > 0.0 && target_ms > 0.0) bias += gain * std::log2(frame_ms / target_ms);
  bias = std::clamp(bias, min_bias, max_bias);
  return bias;
}

}  // namespace vxr
