// Out-of-core volume rendering: LOD traversal -> brick pool -> brick ray caster.
//
// One render() is one eye's frame: traverse the octree in double (culling,
// LOD, empty-space skip, front-to-back order, parent fallback), write the
// brick table (brick-local eye, scale, clip box, cut plane, atlas origin),
// upload missing bricks within the frame's byte budget, march, read back.
//
// Pass modes. kSinglePass: one dispatch; each ray loops over the whole brick
// table with a slab test per brick. kMultipass (the paper's, batched): each
// brick becomes work items, one per 8x8 pixel tile its screen rectangle
// touches; items go into waves so that no two items of a wave share a tile,
// and one dispatch per wave continues the rays from an RGBA32F accumulation
// image. Measured with `vxr bench lod` (docs/ARCHITECTURE.md): on lavapipe the
// single pass is ~10x slower (every ray pays for every brick), and one
// dispatch per brick (the paper's literal multipass) pays a dispatch and a
// barrier per brick; waves need about as many dispatches as bricks overlap
// along a ray. kTiled: one dispatch; each 8x8 tile walks its own front-to-back
// list of the bricks its screen rectangle touches. All three give the same
// image. kAuto (the default) picks by device, as measured: multipass on CPU
// devices (lavapipe: 252 ms vs tiled 296, single 2007), tiled on GPUs (H100,
// 256x256 sparse vessels: tiled 2.0 ms, single 1.7, multipass 3.1; all 512
// bricks drawn: tiled 1.9 ms vs multipass 7.9, where waves cost a dispatch
// and a barrier each and the GPU idles between them).
//
// render_monolithic() is the comparison path: one level of the source as a
// single 3D texture, drawn by the same shader as one brick.
//
// Classification and compositing are the dense ray caster's GLSL core
// (shaders_glsl/include/raycast_core.glsl) with the same RaycastParams and
// transfer table; see check_brick_settings for what the brick path draws.
// The timepoint is the frame's (BrickFrameSettings::lod.timepoint); channels
// are the pool's (BrickPoolOptions::channels).
#pragma once

#include <map>
#include <span>
#include <memory>
#include <tuple>
#include <vector>

#include "core/image.h"
#include "core/status.h"
#include "gpu/context.h"
#include "gpu/pipeline.h"
#include "gpu/resources.h"
#include "render/camera.h"
#include "render/lod/brick_pool.h"
#include "render/lod/lod_traversal.h"
#include "render/raycaster.h"
#include "render/transfer_function.h"
#include "shared/raycast_params.h"

namespace vxr {

enum class BrickPassMode { kAuto, kSinglePass, kTiled, kMultipass };

struct BrickRendererOptions {
  BrickPoolOptions pool;
  uint32_t max_bricks = 16384;         // brick-table capacity per frame
  uint32_t max_work_items = 1u << 20;  // multipass (brick, tile) items per frame
};

struct BrickFrameSettings {
  LodSettings lod;
  uint64_t upload_budget_bytes = UINT64_MAX;  // per frame; at least one brick is uploaded
  BrickPassMode mode = BrickPassMode::kAuto;
};

struct BrickFrameStats {
  LodStats lod;
  uint64_t samples = 0;          // texture samples the rays took
  uint64_t bytes_uploaded = 0;
  uint32_t bricks_uploaded = 0;
  uint32_t evicted = 0;
  double hit_rate = 1.0;         // wanted bricks already resident / wanted bricks
  uint32_t dispatches = 0;
  double traverse_ms = 0.0;      // CPU octree traversal
  double render_ms = 0.0;        // ray-cast submission, wall clock
};

// The brick shader classifies and composites with the dense ray caster's
// core (raycast_core.glsl): every optical model (ea, emission, mip, minip,
// average, iso), 1-4 channels (additive or composite), any transfer function,
// gradient opacity, depth colour, samples at segment midpoints. What it cannot
// do (jitter, another sample offset: the brick grid is anchored at segment
// midpoints so bricks continue each other) is refused, kInvalidArgument naming
// the setting. `channels`: how many channels the renderer draws.
Status check_brick_settings(const RenderSettings& s, uint32_t channels = 1);

// Empty-space test for a brick whose payload values (data units, apron
// included) lie in ranges[c] for drawn channel c, given the settings and their
// transfer table: false only when skipping the brick cannot change any pixel.
// Per model:
//  - ea, emission: every enabled channel's table entries the interpolation can
//    reach over its windowed range have zero opacity (gradient opacity only
//    scales opacity down; depth colour changes colour, not opacity).
//  - mip: every enabled channel's range is at or below its window's low end
//    (windowed 0 never raises the running maximum) and every enabled channel's
//    entry 0 is transparent (a ray whose every brick was skipped shows nothing,
//    one that took samples shows the table at its maximum).
//  - minip: the mirror image: every range at or above the window's high end
//    (windowed 1 never lowers the running minimum) and entry 255 transparent.
//  - average: never (a skipped brick would shorten the length averaged over).
//  - iso: never (a crossing just past a skipped brick is refined against the
//    sample before it, which lies in that brick).
bool brick_may_contribute(const RenderSettings& s, const TransferTable& table, std::span<const ChunkStats> ranges);
// One channel: ranges = {[lo, hi]}.
bool brick_may_contribute(const RenderSettings& s, const TransferTable& table, double lo, double hi);

// Whether a ray's state fits the one RGBA32F texel the multipass waves carry
// between dispatches (brick_raycast.comp pack_ray): ea with one channel or
// composite, emission, mip/minip with one channel, average with up to 3, iso.
// The others march tiled (one dispatch, no state between passes).
bool brick_state_fits_texel(const RenderSettings& s, uint32_t channels);

// "visited 123 drawn 45 (fallback 2) empty 30 culled 12 missing 3 samples 1.2M uploaded 0.4 MiB hit 97%"
std::string format_stats(const BrickFrameStats& s);

class BrickRenderer {
 public:
  static Result<std::unique_ptr<BrickRenderer>> create(gpu::Context& ctx, const ChunkSource& source,
                                                       const BrickRendererOptions& options = {});

  // Premultiplied RGBA, top row first. Complete every frame: missing bricks
  // are drawn from their nearest resident ancestor.
  Result<ImageRgba8> render(const Camera& camera, const RenderSettings& settings, const BrickFrameSettings& frame,
                            uint32_t width, uint32_t height, BrickFrameStats* stats = nullptr);

  // Loads `level` of the source at `timepoint` into one 3D texture per drawn
  // channel (refused past the device's 3D image limit) for render_monolithic().
  Status set_monolithic(uint32_t level, uint32_t timepoint = 0);
  Result<ImageRgba8> render_monolithic(const Camera& camera, const RenderSettings& settings, const LodSettings& clip,
                                       uint32_t width, uint32_t height, BrickFrameStats* stats = nullptr);

  BrickPool& pool() { return *pool_; }
  uint32_t channels() const { return pool_->channels(); }
  VolumePlacement placement() const;

 private:
  BrickRenderer(gpu::Context& ctx, const ChunkSource& src) : ctx_(ctx), src_(src) {}
  Status ensure_target(uint32_t width, uint32_t height);
  // Gradients (gradient opacity, iso normals) need an apron of 2 in the
  // atlas: the first frame that needs it rebuilds the pool with one.
  Status ensure_apron(const RenderSettings& s);
  // The frame's timepoint: its top level pinned.
  Status ensure_timepoint(uint32_t timepoint);
  void bind_atlases(VkDescriptorSet set, const std::vector<const gpu::Image*>& atlases);
  std::vector<const gpu::Image*> pool_atlases() const;
  Status upload_transfer(const TransferTable& table);
  // The pipeline specialised for the settings (model: VXR_MODEL_*, channels, features).
  Result<const gpu::ComputePipeline*> pipeline_for(const RenderSettings& s, uint32_t model);
  // Fills the brick record for `key` (`atlas_origin`: interior origin in texels).
  void fill_record(void* record, const ChunkKey& key, const glm::vec3& atlas_origin, const LodView& view,
                   const LodSettings& clip) const;
  Result<double> cast(VkDescriptorSet set, const RenderSettings& s, const shader::RaycastParams& params,
                      uint32_t bricks,
                      const glm::uvec3& atlas_texels, BrickPassMode mode, const std::vector<glm::uvec2>& waves,
                      BrickFrameStats* stats);
  // Multipass work items (brick, 8x8 tile) grouped into waves; returns (first item, count) per wave.
  Result<std::vector<glm::uvec2>> build_waves(const std::vector<ChunkKey>& draw, const LodView& view);
  // Tiled: per 8x8 tile, the front-to-back list of bricks whose screen rectangle touches it.
  Status build_tile_lists(const std::vector<ChunkKey>& draw, const LodView& view);
  LodView view_for(const Camera& camera, uint32_t width, uint32_t height) const;

  gpu::Context& ctx_;
  const ChunkSource& src_;
  BrickRendererOptions opt_;
  std::unique_ptr<BrickPool> pool_;
  gpu::ComputePipeline pipeline_;  // emission-absorption, one channel; its set layout is the sets'
  std::map<uint32_t, gpu::ComputePipeline> pipelines_;  // other variants, keyed as in pipeline_for
  gpu::Handle<VkDescriptorPool> desc_pool_;
  VkDescriptorSet paged_set_ = VK_NULL_HANDLE, mono_set_ = VK_NULL_HANDLE;
  gpu::Handle<VkSampler> linear_;
  gpu::Image transfer_tex_, target_, accum_;
  std::vector<gpu::Image> mono_tex_;  // per drawn channel
  gpu::Buffer table_, counters_, items_, params_;
  std::vector<glm::vec4> tf_uploaded_;
  uint32_t mono_level_ = UINT32_MAX, mono_timepoint_ = 0;
  uint32_t pinned_timepoint_ = 0;
  std::vector<glm::dvec3> ray_dirs_;  // per pixel 1/direction, for build_waves
  std::tuple<glm::dvec3, glm::dvec3, glm::dvec3> rays_for_;
  std::vector<uint32_t> pixel_wave_;
  std::vector<double> value_scales_;  // per drawn channel: data units per texel unit
};

}  // namespace vxr
