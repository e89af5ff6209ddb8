// GPU brick pool: 3D texture atlases of bricks (chunk payloads with their
// apron), one atlas per channel with the same slot layout, and the map from
// ChunkKey (channel 0; the key names the brick, every channel comes with it)
// to atlas slot.
//
// Texel formats, the same for every source, so every path samples the same
// values (the CPU reference normalises the same way): u8 R8_UNORM, u16 R16_UNORM, every other dtype (i8, i16, u32, i32,
// f32) R32_SFLOAT in data units, converted while filling the staging ring.
//
// Apron: a slot holds the chunk with `apron` voxels around it. Gradients
// (gradient opacity, isosurface normals) read +-1 voxel around a sample, so
// trilinear filtering there reaches 2 voxels past the brick: the renderer asks
// for apron 2. Where the source stores less (containers imported with the
// default apron 1, procedural sources), the missing layers are filled from
// the neighbouring chunks of the same level (the container's own clamp rule
// at the volume border), so the slot equals what an apron-2 source would give.
// That reads up to 26 neighbours per brick, so the pool does it only when
// asked: a source that stores apron >= 2 costs nothing extra.
//
// Everything Vulkan is allocated once at create(): the atlases, a staging
// ring for uploads. Per frame the caller touches the bricks it draws (so they
// are not evicted), then upload() reads requested bricks from the
// ChunkSource, nearest first, within a byte budget, evicting the least
// recently used brick not drawn this frame. The source's top level (of the
// timepoint drawn) is pinned so the traversal always has a resident ancestor.
//
// Streaming (vxr view): record_upload() takes chunks from a cache instead of
// the source and records the copies into the frame's command buffer; a brick
// is staged only when every chunk its slot is made of (slot_chunks) is there.
//
// Between uploads the atlases are in SHADER_READ_ONLY_OPTIMAL; an upload
// moves them to TRANSFER_DST_OPTIMAL and back around its copies.
//
// Direct writes: on a device whose memory is the host's (lavapipe, integrated
// GPUs) the atlases are linear images mapped for their life, kept in GENERAL,
// and a brick is written straight into its slot: no staging ring, no copy
// command, no wait. The bytes in the atlas are the same either way.
//
// Texel views (a CPU device, direct writes, u8 and u16 texels): each
// atlas's memory is also a storage texel buffer of 16-bit elements
// (gpu::create_image_texels, kAtlasTexelElement), and the ray caster filters
// those by hand instead of calling the sampler, which on lavapipe costs
// several times a trilinear filter written in the shader
// (docs/skipping-perf.md, tenth round). The automatic slot grid then keeps
// each atlas within one view (maxTexelBufferElements elements). An atlas
// read that way holds one 32-bit word per texel (write_texel_words): a u8
// texel with its +x, +y and +xy neighbours (four times as wide), so a
// trilinear sample is two loads; a u16 texel with its +x neighbour (twice
// as wide), four loads (eleventh and twenty-second rounds).
#pragma once

#include <functional>
#include <glm/glm.hpp>
#include <list>
#include <memory>
#include <unordered_map>
#include <vector>

#include "core/status.h"
#include "gpu/context.h"
#include "gpu/resources.h"
#include "volume/chunk_source.h"

namespace vxr {

struct BrickPoolOptions {
  // Slots per atlas axis; the atlas is slots * (chunk_size + 2 * apron) texels
  // per axis, checked against maxImageDimension3D and the memory heap.
  // {0, 0, 0}: automatic, the largest grid up to 16 x 16 x 8 whose atlases
  // (every channel, the dtype's texel size) fit in auto_atlas_bytes.
  glm::uvec3 slots{0, 0, 0};
  uint64_t auto_atlas_bytes = 1ull << 30;
  uint64_t staging_bytes = 16ull << 20;  // the upload ring; bounds one frame's uploads
  // Voxels around each brick in its slot: 0 = the source's; more than the
  // source stores is filled from neighbouring chunks (see above). At most 4.
  uint32_t apron = 0;
  // Source channels to load, in the order the renderer numbers them (at most
  // 4); empty = the source's first min(channels, 4).
  std::vector<uint32_t> channels;
  // Write bricks straight into host-mapped atlases where the device allows it
  // (gpu::host_mapped_image_supported); false: always through the staging ring.
  bool direct_writes = true;
  // With direct writes on a CPU device, a word view of each atlas for the
  // ray caster's own trilinear filter (see above); false: none, the rays use
  // the sampler (tests compare the two).
  bool texel_views = true;
};


// The texel views' element: one 32-bit word per atlas texel, which lavapipe
// loads for 8 rays with one gather instruction; a 16-bit element is loaded
// lane by lane (MRI MIP at step 0.5: 34.7-36.8 ms against 43.7-47.2 with u8
// pairs, docs/skipping-perf.md, twenty-second round).
constexpr VkFormat kAtlasTexelElement = VK_FORMAT_R32_UINT;

// Texels read by hand are stored as words: a u8 texel's word holds, from
// its low byte, texels (x, y), (x + 1, y), (x, y + 1) and (x + 1, y + 1) of
// its slot; a u16 texel's, from its low half, (x, y) and (x + 1, y). Past a
// slot's last texel of an axis the texel itself stands in. The image keeps
// its format at texel_word_width times the width, and is never sampled.
// 0: the format is not read by hand.
inline uint32_t texel_word_width(VkFormat texel_format) {
  return texel_format == VK_FORMAT_R8_UNORM ? 4u : texel_format == VK_FORMAT_R16_UNORM ? 2u : 0u;
}
// `n` texels of a row and of the next row (the row itself for a slot's
// last) -> n words (texel_word_width(texel_format) texels each).
void write_texel_words(VkFormat texel_format, const uint8_t* row, const uint8_t* next_row, uint32_t n, uint8_t* out);

// Largest set of atlases create() makes: lavapipe has one 2 GiB heap; leave room for the rest.
constexpr uint64_t kMaxAtlasBytes = (1ull << 31) - (64ull << 20);

// `wanted` slots per axis lowered until every side fits max_dim texels and the
// atlases fit max_bytes (texel_bytes: all channels of one stored texel; a
// slot's x side is edge * wide_x of them: texel words). kOutOfRange when not
// even one brick fits.
Result<glm::uvec3> fit_slots(glm::uvec3 wanted, uint32_t edge, uint32_t texel_bytes, uint32_t max_dim,
                             uint64_t max_bytes, uint32_t wide_x = 1);

// The atlas texel format for a dtype (see above) and data units per texel
// unit: 255 (u8, UNORM), 65535 (u16, UNORM), 1 (float texels).
VkFormat brick_texel_format(DType dtype);
double brick_value_scale(DType dtype);
// `n` native voxels -> atlas texels of brick_texel_format(dtype).
void convert_to_texels(DType dtype, const uint8_t* in, size_t n, uint8_t* out);

// Empty-space cells inside a brick: cells_per_axis^3 cells of cell_size
// voxels, half a voxel off the voxel grid (cell k of an axis covers local
// [k * s - 0.5, (k + 1) * s - 0.5): shared/brick_params.h), so one more per
// axis than the chunk holds cells. For each cell the pool keeps the min and
// max texel value (atlas texel units, per channel) a trilinear sample inside
// the cell can take: over voxels k*s-1 .. (k+1)*s-1, widened towards the ring
// of voxels around them by the most a sample up to VXR_CELL_BAND outside the
// cell mixes in (3 * band of its weight). The ranges do not depend on the
// transfer function; the ray caster classifies them per frame and jumps over
// cells that cannot change a pixel (brick_raycast.comp). Filled at upload,
// from the staged texels.
struct BrickCells {
  uint32_t cells_per_axis = 1;
  uint32_t cell_size = 8;  // voxels
  uint32_t count() const { return cells_per_axis * cells_per_axis * cells_per_axis; }
};
// About `cell_voxels` voxels per cell, at most 33 cells per axis. The pool
// uses the finest of 2, 4 and 8 whose ranges (every slot it hands out, every
// channel) fit kMaxCellRangeBytes: it hands out no more slots than the
// source has bricks, so a small volume gets 2. Measured with `vxr bench
// peer`: the MRI's rays skip 3.3x the samples with 2-voxel cells, 2.4x with
// 4, 1.7x with 8.
BrickCells brick_cells_for(uint32_t chunk_size, uint32_t cell_voxels = 4);
// The most the cell ranges of a pool may take (a storage buffer; lavapipe's range limit is 128 MiB).
constexpr uint64_t kMaxCellRangeBytes = 64ull << 20;
// The ranges of one channel of a slot (`texels`: edge^3 in `format`, edge =
// chunk_size + 2 * apron, apron >= 1) into out[count()] as (min, max), also
// widened by a few ulps so that a filtered value, however the device rounds
// its weights, lies inside its cell's range.
void compute_cell_ranges(VkFormat format, const uint8_t* texels, uint32_t chunk_size, uint32_t apron,
                         const BrickCells& cells, glm::vec2* out);

struct UploadStats {
  uint32_t bricks = 0;
  uint64_t bytes = 0;
  uint32_t evicted = 0;
  uint32_t deferred = 0;  // requests left for later frames (budget, ring or pool full)
};

class BrickPool {
 public:
  static Result<std::unique_ptr<BrickPool>> create(gpu::Context& ctx, const ChunkSource& source,
                                                   const BrickPoolOptions& options);

  // Starts a frame: bricks touched from now on are protected from eviction.
  void begin_frame() { ++frame_; }
  // Keys name bricks: their channel is ignored (a brick carries every channel).
  bool resident(ChunkKey key) const {
    key.channel = 0;
    return map_.count(key) != 0;
  }
  // Marks a resident brick as used this frame; returns its interior origin in atlas texels.
  glm::uvec3 touch(ChunkKey key);

  // Loads and uploads the top level of `timepoint` and pins it; pins of other
  // timepoints (and pin() calls) are released (they become ordinary LRU bricks).
  Status pin_top_level(uint32_t timepoint = 0);
  // Loads, uploads and pins `keys` (at most half the slots) in addition to
  // what is pinned, outside a frame's recording (it waits for its copies).
  Status pin(const std::vector<ChunkKey>& keys);
  // Uploads requested bricks in order until `budget_bytes` (at least one brick
  // per call) or the ring is used up. Waits for the copies.
  Result<UploadStats> upload(const std::vector<ChunkKey>& requests, uint64_t budget_bytes);

  // Streaming form of upload(): chunks come from `fetch` (nullptr: not loaded
  // yet; the brick is skipped and counted as deferred) and the copies are
  // recorded into `cmd`, ahead of the frame's rays. The staging ring is
  // reused: the command buffer of the previous call must have completed.
  using Fetch = std::function<std::shared_ptr<const Chunk>(const ChunkKey&)>;
  Result<UploadStats> record_upload(VkCommandBuffer cmd, const std::vector<ChunkKey>& requests, uint64_t budget_bytes,
                                    const Fetch& fetch);
  // The chunks (source keys: every drawn channel and, when the slot's apron is
  // wider than the source's, the neighbours it is filled from) that the slot
  // of `brick` is made of: what a streaming caller must have loaded.
  void slot_chunks(ChunkKey brick, std::vector<ChunkKey>& out) const;

  // One atlas per drawn channel (channels() of them); source_channel(i) is what atlas i holds.
  // One channel of `key` (key.channel is the source's) as slot texels: edge^3
  // in the atlas format, edge = chunk_size + 2 * apron(). What upload() copies.
  Status fill_slot(const ChunkKey& key, uint8_t* out) const;
  uint32_t slot_edge() const { return edge_; }
  uint32_t texel_bytes() const { return texel_bytes_; }
  // The atlases hold texel words (write_texel_words; only with texel views).
  bool texel_words() const { return words_; }

  const gpu::Image& atlas(uint32_t channel = 0) const { return atlases_[channel]; }
  // The layout the atlases are sampled in (GENERAL with direct writes).
  VkImageLayout atlas_layout() const {
    return direct_ ? VK_IMAGE_LAYOUT_GENERAL : VK_IMAGE_LAYOUT_SHADER_READ_ONLY_OPTIMAL;
  }
  bool writes_direct() const { return direct_; }
  // Atlas c's texel view, or null (no texel views: the rays sample the atlas).
  const gpu::ImageTexels* atlas_texels_view(uint32_t channel = 0) const {
    return channel < texel_views_.size() ? &texel_views_[channel] : nullptr;
  }
  uint32_t channels() const { return static_cast<uint32_t>(atlases_.size()); }
  uint32_t source_channel(uint32_t i) const { return channel_map_[i]; }
  uint32_t apron() const { return apron_; }
  glm::uvec3 slot_grid() const { return slots_; }
  uint32_t capacity() const { return uint32_t(slots_.x) * slots_.y * slots_.z; }
  uint32_t used() const { return static_cast<uint32_t>(map_.size()); }
  uint64_t brick_bytes() const { return brick_bytes_; }  // one brick, every channel
  // Per slot and drawn channel, the cell ranges (BrickCells): vec2 at
  // ((slot * channels() + c) * cells().count() + cell). Host-visible storage
  // buffer (cached where the device offers it: the renderer reads it for its
  // march boxes), written when a brick is staged.
  const BrickCells& cells() const { return cells_; }
  const gpu::Buffer& cell_ranges() const { return cell_ranges_; }
  // The slot a resident brick occupies (its index in cell_ranges()).
  uint32_t slot_of(ChunkKey key) const {
    key.channel = 0;
    return map_.at(key);
  }

 private:
  struct Slot {
    ChunkKey key;
    uint64_t last_used = 0;
    bool pinned = false;
    bool used = false;
  };
  BrickPool(gpu::Context& ctx, const ChunkSource& src) : ctx_(ctx), src_(src) {}
  Result<uint32_t> free_slot(UploadStats& stats);
  // A chunk by key; a null chunk: not loaded yet.
  using ReadChunk = std::function<Result<std::shared_ptr<const Chunk>>(const ChunkKey&)>;
  // A chunk from `fetch`, checked against the source's chunk shape; null: not loaded yet.
  Result<std::shared_ptr<const Chunk>> checked_chunk(const ChunkKey& key, const ReadChunk& fetch) const;
  // One channel's slot texels: the chunk's own bytes when they already are the
  // slot (same apron, u8/u16: `keep` holds the chunk), else filled into `out`.
  // nullptr when a chunk is not loaded yet.
  Result<const uint8_t*> slot_texels_from(const ChunkKey& key, uint8_t* out, const ReadChunk& fetch,
                                          std::shared_ptr<const Chunk>& keep) const;
  // fill_slot with chunks from `fetch`; false when one of them is not loaded yet.
  Result<bool> fill_slot_from(const ChunkKey& key, uint8_t* out, const ReadChunk& fetch) const;
  // Fills requested bricks (every channel) into the staging ring and assigns
  // their slots; the regions (per atlas) still have to be copied (record_copies).
  Result<UploadStats> stage(const std::vector<ChunkKey>& requests, uint64_t budget_bytes, const ReadChunk& fetch,
                            std::vector<std::vector<VkBufferImageCopy>>& regions);
  void record_copies(VkCommandBuffer cmd, const std::vector<std::vector<VkBufferImageCopy>>& regions);
  // Direct writes: one channel's slot texels (edge^3, packed) into its slot of atlas c.
  // A brick channel whose texels are a chunk's bytes, written after stage()'s loop.
  struct DeferredWrite {
    uint32_t slot, channel;
    const uint8_t* texels;
    std::shared_ptr<const Chunk> keep;
  };
  // compute_cell_ranges for the slot's channel, and (direct writes) its texels into the atlas.
  void write_brick_channel(uint32_t slot, uint32_t c, const uint8_t* texels);
  void write_in_parallel(const std::vector<DeferredWrite>& writes);
  void write_slot(uint32_t c, uint32_t slot, const uint8_t* texels);
  glm::uvec3 slot_origin(uint32_t slot) const;

  gpu::Context& ctx_;
  const ChunkSource& src_;
  glm::uvec3 slots_{0};
  uint32_t edge_ = 0, apron_ = 0;
  uint32_t texel_bytes_ = 1;
  bool words_ = false;
  uint64_t channel_bytes_ = 0;  // one brick, one channel
  uint64_t brick_bytes_ = 0;
  std::vector<gpu::Image> atlases_;
  std::vector<gpu::ImageTexels> texel_views_;  // one per atlas, or none
  std::vector<uint32_t> channel_map_;
  gpu::Buffer staging_;       // staged writes only
  bool direct_ = false;       // direct writes (see above)
  std::vector<uint8_t> scratch_;  // direct writes: one brick, every channel, packed
  BrickCells cells_;
  gpu::Buffer cell_ranges_;
  std::vector<Slot> slot_;
  std::vector<uint32_t> free_;
  std::unordered_map<ChunkKey, uint32_t, ChunkKeyHash> map_;  // keys with channel 0
  uint64_t frame_ = 1;
};

}  // namespace vxr
