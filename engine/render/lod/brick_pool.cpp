#include "render/lod/brick_pool.h"

#include <algorithm>
#include <cstring>
#include <string>

#include "core/trace.h"

namespace vxr {

Result<glm::uvec3> fit_slots(glm::uvec3 wanted, uint32_t edge, uint32_t texel_bytes, uint32_t max_dim,
                             uint64_t max_bytes) {
  const uint64_t brick_bytes = uint64_t(edge) * edge * edge * texel_bytes;
  if (edge > max_dim || brick_bytes > max_bytes)
    return out_of_range("brick pool: one brick of " + std::to_string(edge) + "^3 texels does not fit the device (" +
                        std::to_string(max_dim) + " texels a side, " + std::to_string(max_bytes >> 20) +
                        " MiB); import with a smaller --chunk");
  glm::uvec3 s;
  for (int a = 0; a < 3; ++a) s[a] = std::max(1u, std::min(wanted[a], max_dim / edge));
  // Shrink the longest axis until the atlas fits the heap; at least one slot always fits (checked above).
  while (uint64_t(s.x) * s.y * s.z * brick_bytes > max_bytes) {
    const int a = s.x >= s.y && s.x >= s.z ? 0 : (s.y >= s.z ? 1 : 2);
    --s[a];
  }
  return s;
}

Result<std::unique_ptr<BrickPool>> BrickPool::create(gpu::Context& ctx, const ChunkSource& source,
                                                     const BrickPoolOptions& options) {
  std::unique_ptr<BrickPool> p(new BrickPool(ctx, source));
  VkFormat format;
  switch (source.info().dtype) {
    case DType::kU8: format = VK_FORMAT_R8_UNORM; p->texel_bytes_ = 1; break;
    case DType::kU16: format = VK_FORMAT_R16_UNORM; p->texel_bytes_ = 2; break;
    default:
      return unsupported(std::string("brick pool: bricks must be u8 or u16, not ") + dtype_name(source.info().dtype));
  }
  if (options.slots.x == 0 || options.slots.y == 0 || options.slots.z == 0)
    return invalid_argument("brick pool: every axis needs at least one slot");
  p->edge_ = source.chunk_size() + 2 * source.apron();
  p->brick_bytes_ = uint64_t(p->edge_) * p->edge_ * p->edge_ * p->texel_bytes_;
  VXR_ASSIGN_OR_RETURN(p->slots_, fit_slots(options.slots, p->edge_, p->texel_bytes_, ctx.limits().maxImageDimension3D,
                                            kMaxAtlasBytes));
  const uint64_t ext[3] = {uint64_t(p->slots_.x) * p->edge_, uint64_t(p->slots_.y) * p->edge_,
                           uint64_t(p->slots_.z) * p->edge_};
  // The ring must hold at least one brick, however wide the container's chunks are.
  const uint64_t staging_bytes = std::max(options.staging_bytes, p->brick_bytes_);
  VXR_ASSIGN_OR_RETURN(p->atlas_, gpu::create_image(ctx, {VK_IMAGE_TYPE_3D, format,
                                                          {uint32_t(ext[0]), uint32_t(ext[1]), uint32_t(ext[2])},
                                                          VK_IMAGE_USAGE_SAMPLED_BIT | VK_IMAGE_USAGE_TRANSFER_DST_BIT,
                                                          "brick atlas"}));
  VXR_ASSIGN_OR_RETURN(p->staging_, gpu::create_buffer(ctx, {staging_bytes, VK_BUFFER_USAGE_TRANSFER_SRC_BIT,
                                                             gpu::MemoryIntent::kUpload, "brick staging ring"}));
  // Clear once so never-written texels are defined (validation and determinism).
  VXR_RETURN_IF_ERROR(ctx.submit_and_wait([&](VkCommandBuffer cmd) {
    gpu::transition_image(cmd, p->atlas_, VK_IMAGE_LAYOUT_TRANSFER_DST_OPTIMAL, VK_PIPELINE_STAGE_2_NONE, 0,
                          VK_PIPELINE_STAGE_2_CLEAR_BIT, VK_ACCESS_2_TRANSFER_WRITE_BIT);
    VkClearColorValue zero{};
    VkImageSubresourceRange range{VK_IMAGE_ASPECT_COLOR_BIT, 0, 1, 0, 1};
    vkCmdClearColorImage(cmd, p->atlas_.image, VK_IMAGE_LAYOUT_TRANSFER_DST_OPTIMAL, &zero, 1, &range);
    gpu::transition_image(cmd, p->atlas_, VK_IMAGE_LAYOUT_SHADER_READ_ONLY_OPTIMAL, VK_PIPELINE_STAGE_2_CLEAR_BIT,
                          VK_ACCESS_2_TRANSFER_WRITE_BIT, VK_PIPELINE_STAGE_2_COMPUTE_SHADER_BIT,
                          VK_ACCESS_2_SHADER_SAMPLED_READ_BIT);
  }));
  p->slot_.resize(p->capacity());
  for (uint32_t i = p->capacity(); i-- > 0;) p->free_.push_back(i);
  return p;
}

glm::uvec3 BrickPool::slot_origin(uint32_t slot) const {
  const uint32_t x = slot % slots_.x, y = (slot / slots_.x) % slots_.y, z = slot / (slots_.x * slots_.y);
  const uint32_t a = src_.apron();
  return {x * edge_ + a, y * edge_ + a, z * edge_ + a};
}

glm::uvec3 BrickPool::touch(const ChunkKey& key) {
  const uint32_t s = map_.at(key);
  slot_[s].last_used = frame_;
  return slot_origin(s);
}

Result<uint32_t> BrickPool::free_slot(UploadStats& stats) {
  if (!free_.empty()) {
    const uint32_t s = free_.back();
    free_.pop_back();
    return s;
  }
  // Least recently used, never one drawn this frame or pinned.
  uint32_t best = UINT32_MAX;
  for (uint32_t i = 0; i < slot_.size(); ++i) {
    const Slot& s = slot_[i];
    if (!s.used || s.pinned || s.last_used >= frame_) continue;
    if (best == UINT32_MAX || s.last_used < slot_[best].last_used) best = i;
  }
  if (best == UINT32_MAX) return out_of_range("brick pool: every slot is in use this frame");
  map_.erase(slot_[best].key);
  slot_[best].used = false;
  ++stats.evicted;
  return best;
}

Result<UploadStats> BrickPool::stage(
    const std::vector<ChunkKey>& requests, uint64_t budget_bytes,
    const std::function<Result<std::shared_ptr<const Chunk>>(const ChunkKey&)>& fetch,
    std::vector<VkBufferImageCopy>& regions) {
  UploadStats st;
  uint64_t ring = 0;
  for (const ChunkKey& key : requests) {
    if (resident(key)) continue;
    const bool over_budget = st.bricks > 0 && st.bytes + brick_bytes_ > budget_bytes;
    if (over_budget || ring + brick_bytes_ > staging_.size) {
      ++st.deferred;
      continue;
    }
    VXR_ASSIGN_OR_RETURN(auto chunk, fetch(key));
    if (!chunk) {  // streaming: not decoded yet
      ++st.deferred;
      continue;
    }
    if (chunk->edge != edge_ || chunk->data.size() != brick_bytes_)
      return internal_error("brick pool: chunk level " + std::to_string(key.level) + " has edge " +
                            std::to_string(chunk->edge) + ", expected " + std::to_string(edge_));
    auto slot = free_slot(st);
    if (!slot) {
      ++st.deferred;
      break;
    }
    std::memcpy(static_cast<uint8_t*>(staging_.mapped) + ring, chunk->data.data(), brick_bytes_);
    const glm::uvec3 o = slot_origin(*slot) - glm::uvec3(src_.apron());
    VkBufferImageCopy r{};
    r.bufferOffset = ring;
    r.imageSubresource = {VK_IMAGE_ASPECT_COLOR_BIT, 0, 0, 1};
    r.imageOffset = {int32_t(o.x), int32_t(o.y), int32_t(o.z)};
    r.imageExtent = {edge_, edge_, edge_};
    regions.push_back(r);
    ring += (brick_bytes_ + 15) & ~uint64_t(15);
    slot_[*slot] = {key, frame_, false, true};
    map_[key] = *slot;
    ++st.bricks;
    st.bytes += brick_bytes_;
  }
  return st;
}

void BrickPool::record_copies(VkCommandBuffer cmd, const std::vector<VkBufferImageCopy>& regions) {
  gpu::transition_image(cmd, atlas_, VK_IMAGE_LAYOUT_TRANSFER_DST_OPTIMAL, VK_PIPELINE_STAGE_2_COMPUTE_SHADER_BIT,
                        VK_ACCESS_2_SHADER_SAMPLED_READ_BIT, VK_PIPELINE_STAGE_2_COPY_BIT,
                        VK_ACCESS_2_TRANSFER_WRITE_BIT);
  vkCmdCopyBufferToImage(cmd, staging_.buffer, atlas_.image, VK_IMAGE_LAYOUT_TRANSFER_DST_OPTIMAL,
                         static_cast<uint32_t>(regions.size()), regions.data());
  gpu::transition_image(cmd, atlas_, VK_IMAGE_LAYOUT_SHADER_READ_ONLY_OPTIMAL, VK_PIPELINE_STAGE_2_COPY_BIT,
                        VK_ACCESS_2_TRANSFER_WRITE_BIT, VK_PIPELINE_STAGE_2_COMPUTE_SHADER_BIT,
                        VK_ACCESS_2_SHADER_SAMPLED_READ_BIT);
}

Result<UploadStats> BrickPool::upload(const std::vector<ChunkKey>& requests, uint64_t budget_bytes) {
  VXR_TRACE_SCOPE("brick_pool.upload");
  std::vector<VkBufferImageCopy> regions;
  VXR_ASSIGN_OR_RETURN(UploadStats st,
                       stage(requests, budget_bytes, [this](const ChunkKey& k) { return src_.read(k); }, regions));
  if (regions.empty()) return st;
  VXR_RETURN_IF_ERROR(ctx_.submit_and_wait([&](VkCommandBuffer cmd) { record_copies(cmd, regions); }));
  return st;
}

Result<UploadStats> BrickPool::record_upload(VkCommandBuffer cmd, const std::vector<ChunkKey>& requests,
                                             uint64_t budget_bytes, const Fetch& fetch) {
  VXR_TRACE_SCOPE("brick_pool.record_upload");
  std::vector<VkBufferImageCopy> regions;
  VXR_ASSIGN_OR_RETURN(UploadStats st, stage(requests, budget_bytes,
                                             [&](const ChunkKey& k) -> Result<std::shared_ptr<const Chunk>> {
                                               return fetch(k);
                                             },
                                             regions));
  if (!regions.empty()) record_copies(cmd, regions);
  return st;
}

Status BrickPool::pin_top_level() {
  const uint32_t top = static_cast<uint32_t>(src_.levels().size()) - 1;
  const auto& li = src_.levels()[top];
  std::vector<ChunkKey> keys;
  for (uint32_t z = 0; z < li.chunk_counts[2]; ++z)
    for (uint32_t y = 0; y < li.chunk_counts[1]; ++y)
      for (uint32_t x = 0; x < li.chunk_counts[0]; ++x) keys.push_back({top, x, y, z, 0, 0});
  return pin(keys);
}

Status BrickPool::pin(const std::vector<ChunkKey>& keys) {
  if (keys.size() > capacity() / 2)
    return out_of_range("brick pool: " + std::to_string(keys.size()) + " chunks are too many to pin in " +
                        std::to_string(capacity()) + " slots");
  while (true) {
    VXR_ASSIGN_OR_RETURN(UploadStats st, upload(keys, UINT64_MAX));
    if (st.deferred == 0) break;
    if (st.bricks == 0) return out_of_range("brick pool: no room to pin " + std::to_string(keys.size()) + " chunks");
  }
  for (const ChunkKey& k : keys) slot_[map_.at(k)].pinned = true;
  return Status::ok();
}

}  // namespace vxr
