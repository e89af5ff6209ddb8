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
#pragma once

#include <map>
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
#include "render/volume_renderer.h"
#include "shared/raycast_params.h"
#include "volume/chunk_cache.h"

namespace vxr {

struct BrickRendererOptions {
  BrickPoolOptions pool;
  uint32_t max_bricks = 16384;         // brick-table capacity per frame (all views together)
  uint32_t max_work_items = 1u << 20;  // multipass / tile-list entries per frame (all views together)
  uint32_t max_views = 32;             // record_view calls per frame (eyes x lens-warp tiles)
  // Streaming (vxr view): missing bricks are requested from this cache,
  // whose loader threads read and decode them; begin_frame copies in those
  // that have arrived. A frame never waits for I/O: until a brick arrives its
  // resident ancestor is drawn. Null: render() reads missing bricks itself
  // after the frame (vxr render, tests). Must outlive the renderer.
  ChunkCache* stream_from = nullptr;
  // Small volumes: when every chunk of every level (channel 0, timepoint 0)
  // fits in half the pool, upload and pin them all at create(), so every
  // frame draws at full detail from the first (and deterministically).
  bool preload_if_fits = false;
};

// The brick shader classifies and composites with the dense ray caster's
// core (raycast_core.glsl): one channel, emission-absorption, emission or
// MIP, any transfer function (window, gamma, colormap or colour points,
// opacity points), samples at segment midpoints. What it cannot do (other
// models, more channels, gradient opacity, depth colour, jitter, another
// sample offset) is refused, kInvalidArgument naming the setting, rather than
// silently ignored.
Status check_brick_settings(const RenderSettings& s);

// Empty-space test for a brick whose payload values (data units, apron
// included) lie in [lo, hi], given the settings and their transfer table:
// false only when skipping the brick cannot change any pixel. EA and
// emission: every table entry the interpolation can reach over the windowed
// range has zero opacity (gradient opacity would only scale it down). MIP:
// the whole range is at or below the window's low end (windowed value 0 never
// raises the running maximum) and the table's entry 0 has zero opacity (else
// a ray whose every brick was skipped would lose the colour of value 0).
bool brick_may_contribute(const RenderSettings& s, const TransferTable& table, double lo, double hi);

// "visited 123 drawn 45 (fallback 2) empty 30 culled 12 missing 3 samples 1.2M uploaded 0.4 MiB hit 97%"
std::string format_stats(const BrickFrameStats& s);

class BrickRenderer final : public VolumeRenderer {
 public:
  static Result<std::unique_ptr<BrickRenderer>> create(gpu::Context& ctx, const ChunkSource& source,
                                                       const BrickRendererOptions& options = {});

  // VolumeRenderer. Per view: one slice of the frame's brick table, work
  // list and parameter ring, and one descriptor set (max_views per frame).
  Status begin_frame(VkCommandBuffer cmd, const BrickFrameSettings& frame) override;
  Status record_view(VkCommandBuffer cmd, const Camera& camera, const RenderSettings& settings,
                     const BrickFrameSettings& frame, const RenderTarget& target,
                     BrickFrameStats* stats = nullptr) override;
  VolumePlacement placement() const override;

  // One frame of one view recorded, submitted, waited for and read back
  // (tests, PNG output): premultiplied RGBA, top row first. Complete every
  // frame: missing bricks are drawn from their nearest resident ancestor;
  // without a stream cache they are read after the frame, within the budget.
  Result<ImageRgba8> render(const Camera& camera, const RenderSettings& settings, const BrickFrameSettings& frame,
                            uint32_t width, uint32_t height, BrickFrameStats* stats = nullptr);

  // Loads `level` of the source into one 3D texture (refused past the
  // device's 3D image limit) for render_monolithic().
  Status set_monolithic(uint32_t level);
  Result<ImageRgba8> render_monolithic(const Camera& camera, const RenderSettings& settings, const LodSettings& clip,
                                       uint32_t width, uint32_t height, BrickFrameStats* stats = nullptr);

  BrickPool& pool() { return *pool_; }
  // Bricks requested from the stream cache and not yet copied in.
  size_t pending_bricks() const { return pending_.size(); }

 private:
  BrickRenderer(gpu::Context& ctx, const ChunkSource& src) : ctx_(ctx), src_(src) {}
  Status ensure_target(uint32_t width, uint32_t height);
  // The accumulation image holds at least width x height (rays' state between
  // passes, and final float pixels on their way to a blit).
  Status ensure_accum(uint32_t width, uint32_t height);
  // Records the transfer table's upload when it changed (once per frame at most).
  Status record_transfer(VkCommandBuffer cmd, const TransferTable& table);
  // The pipeline specialised for the settings' optical model.
  Result<const gpu::ComputePipeline*> pipeline_for(const RenderSettings& s);
  // Fills the brick record for `key` (`atlas_origin`: interior origin in texels).
  void fill_record(void* record, const ChunkKey& key, const glm::vec3& atlas_origin, const LodView& view,
                   const LodSettings& clip) const;
  // Records one view's dispatches with `set` and writes the result into `target`.
  Status record_cast(VkCommandBuffer cmd, VkDescriptorSet set, const RenderSettings& s, uint32_t width,
                     uint32_t height, uint32_t bricks, const glm::uvec3& atlas_texels, BrickPassMode mode,
                     const std::vector<glm::uvec2>& waves, const RenderTarget& target, uint32_t* dispatches);
  // Multipass work items (brick, 8x8 tile) grouped into waves, written at
  // `dst` (capacity entries); returns (first item, count) per wave.
  Result<std::vector<glm::uvec2>> build_waves(const std::vector<ChunkKey>& draw, const LodView& view,
                                              glm::uvec4* dst, size_t capacity, size_t* used);
  // Tiled: per 8x8 tile, the front-to-back list of bricks whose screen rectangle touches it.
  Status build_tile_lists(const std::vector<ChunkKey>& draw, const LodView& view, glm::uvec4* dst, size_t capacity,
                          size_t* used);
  LodView view_for(const Camera& camera, uint32_t width, uint32_t height) const;

  gpu::Context& ctx_;
  const ChunkSource& src_;
  BrickRendererOptions opt_;
  std::unique_ptr<BrickPool> pool_;
  gpu::ComputePipeline pipeline_;  // emission-absorption; its set layout is the sets'
  std::map<uint32_t, gpu::ComputePipeline> pipelines_;  // other variants: model | gamma << 4 | naive << 5
  gpu::Handle<VkDescriptorPool> desc_pool_;
  VkDescriptorSet mono_set_ = VK_NULL_HANDLE;
  std::vector<VkDescriptorSet> view_sets_;  // one per view of a frame
  gpu::Handle<VkSampler> linear_;
  gpu::Image transfer_tex_, target_, accum_, mono_tex_;
  std::vector<gpu::Image> retired_;  // replaced while a frame may still use them; freed at begin_frame
  gpu::Buffer table_, counters_, items_, params_, tf_staging_;
  VkDeviceSize params_stride_ = 0;
  // This frame: views recorded, and the table / work-list entries they took.
  uint32_t views_ = 0;
  size_t table_used_ = 0, items_used_ = 0;
  bool tf_recorded_ = false;
  std::vector<glm::vec4> tf_uploaded_;
  std::vector<ChunkKey> pending_;    // streaming: requested, not yet copied in
  std::vector<ChunkKey> requests_;   // render(): the frame's requests, read after it
  uint64_t frame_number_ = 0;
  UploadStats last_upload_;          // streaming: what this frame's begin_frame copied in
  uint32_t mono_level_ = UINT32_MAX;
  std::vector<glm::dvec3> ray_dirs_;  // per pixel 1/direction, for build_waves
  std::tuple<glm::dvec3, glm::dvec3, glm::dvec3> rays_for_;
  std::vector<uint32_t> pixel_wave_;
  double value_scale_ = 255.0;
};

}  // namespace vxr
