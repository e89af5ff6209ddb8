// A ChunkSource that synthesises a vessel-like volume on demand, so scale can
// be measured without disk: any size up to 2^17 voxels a side, deterministic
// for a seed, sparse (a target fraction of occupied space), u8.
//
// The field lives in normalised coordinates (level-0 voxel / largest side), so
// the same picture appears at every size and at every level: a 65536^3 volume
// seen from afar draws the same coarse levels as a 256^3 one.
//
// Vessels are capsule segments with a Gaussian cross-section (sigma = radius);
// the value is the maximum over segments, plus optional hashed background noise
// in [0, noise_max]. Level l is the Gaussian-filtered field: sigma_l^2 =
// sigma^2 + voxel_l^2 / 12 with the amplitude scaled by sigma^2 / sigma_l^2
// (the cross-section's mass is kept), which is what repeated 2x averaging
// converges to; so the levels agree with each other up to filtering.
//
// stats() never generates voxels: it bounds the Gaussian from the distance of
// the chunk's payload box (interior AND apron) to each nearby segment. A chunk
// farther than the cut-off from every segment is exactly noise-only
// (min 0, max noise_max; 0/0 without noise); elsewhere the bounds contain the
// true range. Covering the apron matters: a ray sampling a brick's border
// filters apron voxels, so a brick is only empty if its apron is too.
#pragma once

#include <array>
#include <cstdint>
#include <memory>
#include <mutex>
#include <unordered_map>
#include <vector>

#include "volume/chunk_source.h"

namespace vxr {

struct ProceduralOptions {
  std::array<uint64_t, 3> dims{256, 256, 256};
  uint32_t chunk_size = 32;
  uint32_t apron = 1;
  uint64_t seed = 1;
  // Target fraction of an 8^3 grid of cells over the volume that the vessels
  // reach (the level-0 chunks of a 256^3 volume with 32^3 chunks).
  double occupancy = 0.10;
  // Background noise, u8 units, uniform in [0, noise_max]. A transfer function
  // whose window starts at or above it sees the background as empty.
  uint32_t noise_max = 0;
  // Largest vessel sigma as a fraction of the largest side.
  double radius = 0.010;
};

class ProceduralSource final : public ChunkSource {
 public:
  // Fails (kInvalidArgument) for a zero or > 2^17 side, chunk_size not in
  // [8, 256], apron > 4 or occupancy outside (0, 1].
  static Result<std::unique_ptr<ProceduralSource>> create(const ProceduralOptions& options);

  const VolumeInfo& info() const override { return info_; }
  const std::vector<LevelInfo>& levels() const override { return levels_; }
  uint32_t chunk_size() const override { return opt_.chunk_size; }
  uint32_t apron() const override { return opt_.apron; }
  Result<ChunkStats> stats(const ChunkKey& key) const override;
  Result<std::shared_ptr<const Chunk>> read(const ChunkKey& key) const override;

  // One voxel of a level (clamped to the level's dims, like the apron rule).
  uint8_t voxel(uint32_t level, int64_t x, int64_t y, int64_t z) const;
  // Fraction of the 8^3 occupancy cells the vessels reach.
  double measured_occupancy() const { return occupancy_; }
  size_t segment_count() const { return segs_.size(); }

 private:
  struct Segment {
    std::array<double, 3> a, b;  // normalised coordinates
    double sigma;                // level-0-free sigma (normalised)
    double amp;                  // peak value, 0..1
  };
  struct Box {
    std::array<double, 3> lo, hi;
  };
  explicit ProceduralSource(const ProceduralOptions& o) : opt_(o) {}
  void build_levels();
  void grow_vessels();
  void build_grid();
  // Segments whose AABB, grown by `pad`, meets `box`.
  void candidates(const Box& box, double pad, std::vector<uint32_t>& out) const;
  // Sigma and amplitude of a segment at a level.
  void level_profile(const Segment& s, uint32_t level, double& sigma, double& amp) const;
  double cutoff(double sigma, double amp) const;  // distance past which round(255*g) == 0
  Box payload_box(const ChunkKey& key) const;     // voxel centres of the payload, normalised

  ProceduralOptions opt_;
  VolumeInfo info_;
  std::vector<LevelInfo> levels_;
  double inv_max_side_ = 1.0;
  std::vector<Segment> segs_;
  double max_sigma_ = 0.0;
  static constexpr int kGrid = 32;
  std::vector<std::vector<uint32_t>> grid_;  // kGrid^3 cells of segment ids (by AABB)
  std::array<double, 3> extent_{1, 1, 1};    // normalised size of the volume
  double occupancy_ = 0.0;
  // stats() answered before: the LOD traversal asks for every visited chunk
  // each frame, and each answer bounds every nearby segment (a 256^3 view at
  // 512x512: most of the main thread's time a frame). Bounded: cleared when full.
  static constexpr size_t kStatsCacheEntries = size_t(1) << 16;
  mutable std::mutex stats_mu_;
  mutable std::unordered_map<ChunkKey, ChunkStats, ChunkKeyHash> stats_cache_;
};

}  // namespace vxr
