// CPU octree traversal that picks the bricks one eye draws this frame.
//
// The octree is the ChunkSource pyramid: chunk (l, x, y, z) has the chunks of
// level l-1 under it as children (2 per axis, 1 along an axis the pyramid did
// not halve). Above the source's top level, virtual nodes (never drawn) close
// the tree into one root. Everything is double, in level-0 voxel coordinates.
//
// Per node (syGlass, "Octree Representation"): cull against the frustum, the
// cut plane and the ROI; decide whether its level suffices by comparing the
// angle one of its voxels spans at the nearest point of its box with the angle
// of one pixel (times 2^bias); if it suffices, draw it unless its min/max maps
// to zero opacity under the transfer function (the caller's rule per model); if not, and every child that
// would be needed is resident, recurse into the children in front-to-back
// (octant) order, else request the missing children and draw this node
// meanwhile (never a hole). The list comes out sorted front to back.
#pragma once

#include <functional>
#include <glm/glm.hpp>
#include <vector>

#include "volume/chunk_source.h"

namespace vxr {

// A plane that clips the volume: points with dot(normal, p) + offset >= 0 are
// kept (p in level-0 voxel coordinates).
struct CutPlane {
  bool enabled = false;
  glm::dvec3 normal{0, 0, 1};
  double offset = 0.0;
};

// A box that clips the volume: only [lo, hi] (level-0 voxel coordinates) is kept.
struct RoiBox {
  bool enabled = false;
  glm::dvec3 lo{0, 0, 0}, hi{0, 0, 0};
};

// One eye, in level-0 voxel coordinates (as rays_in_voxel_space gives it).
struct LodView {
  glm::dvec3 eye{0, 0, 0};
  glm::dvec3 forward{0, 0, -1};  // through the image centre
  glm::dvec3 right{1, 0, 0};     // scaled by tan(fov/2) * aspect
  glm::dvec3 up{0, 1, 0};        // scaled by tan(fov/2)
  uint32_t width = 1, height = 1;
};

struct LodSettings {
  // log2 of the voxel-to-pixel angle ratio accepted: 0 = one voxel per pixel,
  // +1 = voxels twice as large (coarser, faster), -1 = finer.
  double lod_bias = 0.0;
  bool skip_empty = true;  // drop bricks whose min/max maps to zero opacity
  bool frustum_cull = true;
  int force_level = -1;    // >= 0: draw exactly this level (clamped to the pyramid)
  CutPlane cut;
  RoiBox roi;
  uint32_t timepoint = 0;  // the keys' timepoint (their channel is 0: a brick names every channel)
};

struct LodStats {
  uint64_t visited = 0;        // nodes looked at
  uint64_t drawn = 0;          // bricks in the draw list
  uint64_t fallback = 0;       // of those, ancestors drawn because children are missing
  uint64_t skipped_empty = 0;  // bricks not drawn: zero opacity under the transfer function
  uint64_t culled = 0;         // nodes outside the frustum, cut away or outside the ROI
  uint64_t missing = 0;        // wanted bricks not resident (requested)
};

struct LodResult {
  std::vector<ChunkKey> draw;      // front to back
  std::vector<ChunkKey> requests;  // nearest first
  LodStats stats;
};

struct LodQueries {
  // False when skipping the brick cannot change any pixel (it is then neither
  // drawn nor requested). The caller reads the stats of each channel it draws.
  std::function<bool(const ChunkKey&)> visible;
  // True when the brick is on the GPU and may be drawn this frame.
  std::function<bool(const ChunkKey&)> resident;
};

// The box a chunk covers, level-0 voxel coordinates, clipped to the volume.
struct BrickBox {
  glm::dvec3 lo, hi;
};
BrickBox chunk_box(const ChunkSource& src, const ChunkKey& key);

LodResult traverse_lod(const ChunkSource& src, const LodView& view, const LodSettings& settings,
                       const LodQueries& queries);

// Frame-budget mode: nudges the LOD bias so the frame time approaches the
// target. Work scales about as 2^-bias, so log2(ms / target) is the full
// correction; `gain` damps it.
struct FrameBudget {
  double target_ms = 11.1;
  double gain = 0.5;
  double min_bias = -1.0, max_bias = 6.0;
  double bias = 0.0;
  double update(double frame_ms);
};

}  // namespace vxr
