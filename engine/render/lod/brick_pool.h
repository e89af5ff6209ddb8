// GPU brick pool: a fixed 3D texture atlas of bricks (chunk payloads with
// their apron) and the map from ChunkKey to atlas slot.
//
// Everything Vulkan is allocated once at create(): the atlas, a staging ring
// for uploads. Per frame the caller touches the bricks it draws (so they are
// not evicted), then upload() reads requested bricks from the ChunkSource,
// nearest first, within a byte budget, evicting the least recently used brick
// not drawn this frame. The source's top level is pinned so the traversal
// always has a resident ancestor to draw.
//
// Between uploads the atlas is in SHADER_READ_ONLY_OPTIMAL; an upload moves it
// to TRANSFER_DST_OPTIMAL and back around its copies.
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
  // Slots per atlas axis wanted; the atlas is slots * (chunk_size + 2 * apron)
  // texels per axis. create() lowers them to fit maxImageDimension3D and the
  // heap (fit_slots), so containers with wide chunks still draw.
  glm::uvec3 slots{16, 16, 8};
  uint64_t staging_bytes = 16ull << 20;  // the upload ring; bounds one frame's uploads (grown to one brick)
};

// Largest atlas create() makes: lavapipe has one 2 GiB heap; leave room for the rest.
constexpr uint64_t kMaxAtlasBytes = (1ull << 31) - (64ull << 20);

// `wanted` slots per axis lowered until every side fits max_dim texels and the
// atlas fits max_bytes. kOutOfRange when not even one brick fits.
Result<glm::uvec3> fit_slots(glm::uvec3 wanted, uint32_t edge, uint32_t texel_bytes, uint32_t max_dim,
                             uint64_t max_bytes);

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
  bool resident(const ChunkKey& key) const { return map_.count(key) != 0; }
  // Marks a resident brick as used this frame; returns its interior origin in atlas texels.
  glm::uvec3 touch(const ChunkKey& key);

  // Loads and uploads the top level and pins it (call once, before frames).
  Status pin_top_level();
  // Loads, uploads and pins `keys` (at most half the slots), before frames.
  Status pin(const std::vector<ChunkKey>& keys);
  // Uploads requested bricks in order until `budget_bytes` (at least one brick
  // per call) or the ring is used up. Waits for the copies.
  Result<UploadStats> upload(const std::vector<ChunkKey>& requests, uint64_t budget_bytes);

  // Streaming form of upload(): chunks come from `fetch` (nullptr: not loaded
  // yet, skipped and counted as deferred) and the copies are recorded into
  // `cmd`, ahead of the frame's rays. The staging ring is reused: the
  // command buffer of the previous call must have completed.
  using Fetch = std::function<std::shared_ptr<const Chunk>(const ChunkKey&)>;
  Result<UploadStats> record_upload(VkCommandBuffer cmd, const std::vector<ChunkKey>& requests, uint64_t budget_bytes,
                                    const Fetch& fetch);

  const gpu::Image& atlas() const { return atlas_; }
  glm::uvec3 atlas_texels() const { return {atlas_.extent.width, atlas_.extent.height, atlas_.extent.depth}; }
  uint32_t capacity() const { return uint32_t(slots_.x) * slots_.y * slots_.z; }
  uint32_t used() const { return static_cast<uint32_t>(map_.size()); }
  uint64_t brick_bytes() const { return brick_bytes_; }

 private:
  struct Slot {
    ChunkKey key;
    uint64_t last_used = 0;
    bool pinned = false;
    bool used = false;
  };
  BrickPool(gpu::Context& ctx, const ChunkSource& src) : ctx_(ctx), src_(src) {}
  Result<uint32_t> free_slot(UploadStats& stats);
  // Copies requested chunks into the staging ring and assigns their slots;
  // the regions still have to be copied into the atlas (record_copies).
  Result<UploadStats> stage(const std::vector<ChunkKey>& requests, uint64_t budget_bytes,
                            const std::function<Result<std::shared_ptr<const Chunk>>(const ChunkKey&)>& fetch,
                            std::vector<VkBufferImageCopy>& regions);
  void record_copies(VkCommandBuffer cmd, const std::vector<VkBufferImageCopy>& regions);
  glm::uvec3 slot_origin(uint32_t slot) const;

  gpu::Context& ctx_;
  const ChunkSource& src_;
  glm::uvec3 slots_{0};
  uint32_t edge_ = 0;
  uint32_t texel_bytes_ = 1;
  uint64_t brick_bytes_ = 0;
  gpu::Image atlas_;
  gpu::Buffer staging_;
  std::vector<Slot> slot_;
  std::vector<uint32_t> free_;
  std::unordered_map<ChunkKey, uint32_t, ChunkKeyHash> map_;
  uint64_t frame_ = 1;
};

}  // namespace vxr
