// Buffers and images with their memory, made from plain create-info structs.
//
// Memory intent is an enum, not raw flags: kDeviceLocal for GPU-only data,
// kUpload for host-written staging, kReadback for host-read results,
// kHostShared for data the host writes and also reads back (cached where the
// device offers it: reads of write-combined memory crawl).
#pragma once

#include <vulkan/vulkan.h>

#include <cstddef>
#include <cstdint>
#include <string>

#include "core/status.h"
#include "gpu/context.h"
#include "gpu/handle.h"

namespace vxr::gpu {

enum class MemoryIntent { kDeviceLocal, kUpload, kReadback, kHostShared };

struct BufferCreateInfo {
  VkDeviceSize size = 0;
  VkBufferUsageFlags usage = 0;
  MemoryIntent intent = MemoryIntent::kDeviceLocal;
  const char* debug_name = "buffer";
};

// The buffer owns its memory; host-visible buffers stay mapped for their life.
struct Buffer {
  Handle<VkBuffer> buffer;
  Handle<VkDeviceMemory> memory;
  VkDeviceSize size = 0;
  void* mapped = nullptr;  // non-null for kUpload / kReadback
  bool host_coherent = true;
};

Result<Buffer> create_buffer(const Context& ctx, const BufferCreateInfo& info);

struct ImageCreateInfo {
  VkImageType type = VK_IMAGE_TYPE_2D;
  VkFormat format = VK_FORMAT_R8G8B8A8_UNORM;
  VkExtent3D extent{1, 1, 1};
  VkImageUsageFlags usage = 0;
  const char* debug_name = "image";
  // Linear tiling in host-visible memory, mapped for the image's life, so the
  // host writes texels in place (no staging copy). Only where
  // host_mapped_image_supported() says so.
  bool host_mapped = false;
};

// A device-local image with a view over all of it. `layout` tracks the layout
// the last recorded barrier left it in.
struct Image {
  Handle<VkImage> image;
  Handle<VkDeviceMemory> memory;
  Handle<VkImageView> view;
  VkFormat format = VK_FORMAT_UNDEFINED;
  VkExtent3D extent{0, 0, 0};
  VkImageType type = VK_IMAGE_TYPE_2D;
  VkImageLayout layout = VK_IMAGE_LAYOUT_UNDEFINED;
  // Host-mapped images only: texel (x, y, z) is at mapped + z * depth_pitch + y * row_pitch + x * texel bytes.
  uint8_t* mapped = nullptr;
  VkDeviceSize row_pitch = 0, depth_pitch = 0;
  VkDeviceSize mapped_offset = 0;  // texel (0, 0, 0)'s offset in `memory`
  VkDeviceSize memory_bytes = 0;   // the size of `memory`
  uint32_t memory_type = 0;
};

// Whether create_image can make a host-mapped image of this kind: a device
// whose memory is the host's (a CPU or integrated device, where linear
// textures sample as fast as optimal ones) that allows linear tiling for it.
bool host_mapped_image_supported(const Context& ctx, VkImageType type, VkFormat format, VkImageUsageFlags usage,
                                 VkExtent3D extent);

// Checks the extent against the device's limits first: lavapipe does not
// refuse oversize images, it misbehaves later.
Result<Image> create_image(const Context& ctx, const ImageCreateInfo& info);

// Bytes per texel of the formats vxr uses; 0 for others.
uint32_t format_texel_bytes(VkFormat format);

// Records a global memory barrier (synchronization2).
void memory_barrier(VkCommandBuffer cmd, VkPipelineStageFlags2 src_stage, VkAccessFlags2 src_access,
                    VkPipelineStageFlags2 dst_stage, VkAccessFlags2 dst_access);

// Records a barrier on the whole buffer (synchronization2).
void buffer_barrier(VkCommandBuffer cmd, VkBuffer buffer, VkPipelineStageFlags2 src_stage, VkAccessFlags2 src_access,
                    VkPipelineStageFlags2 dst_stage, VkAccessFlags2 dst_access);

// Records a layout transition of any image's first mip and layer
// (synchronization2): for targets a caller or a swapchain owns, which carry
// no tracked layout.
void image_barrier(VkCommandBuffer cmd, VkImage image, VkImageAspectFlags aspect, VkImageLayout from, VkImageLayout to,
                   VkPipelineStageFlags2 src_stage, VkAccessFlags2 src_access, VkPipelineStageFlags2 dst_stage,
                   VkAccessFlags2 dst_access);

// Records a layout transition of the whole image and notes its new layout
// (synchronization2).
void transition_image(VkCommandBuffer cmd, Image& image, VkImageLayout new_layout,
                      VkPipelineStageFlags2 src_stage, VkAccessFlags2 src_access,
                      VkPipelineStageFlags2 dst_stage, VkAccessFlags2 dst_access);

// Copies tightly packed texels into the whole image through a staging buffer,
// waits, and leaves the image in SHADER_READ_ONLY_OPTIMAL. A host-mapped
// image: the rows are written in place and it is left in GENERAL.
Status upload_image(Context& ctx, Image& image, const void* texels, size_t bytes);

// Copies the whole image (2D) back into `out` (tightly packed), waits, and
// leaves the image in `final_layout`. Counted in readback_count().
Status readback_image(Context& ctx, Image& image, void* out, size_t bytes,
                      VkImageLayout final_layout = VK_IMAGE_LAYOUT_GENERAL);

// readback_image through one staging buffer kept between calls (grown to the
// largest image), for loops that read a frame back every frame: a new
// buffer each time is host memory allocated, mapped and faulted in per frame.
class ImageReadback {
 public:
  Status read(Context& ctx, Image& image, void* out, size_t bytes,
              VkImageLayout final_layout = VK_IMAGE_LAYOUT_GENERAL);

 private:
  Buffer staging_;
};

// Image readbacks (readback_image) in this process so far: frame loops report
// how many a frame took (none on the XR and desktop paths).
uint64_t readback_count();

Result<Handle<VkSampler>> create_linear_clamp_sampler(const Context& ctx);
Result<Handle<VkSampler>> create_nearest_clamp_sampler(const Context& ctx);

// A host-mapped image's texels as a storage texel buffer over its memory,
// in elements of `element` (R8_UINT, R16_UINT, R32_UINT; the first starts at
// texel (0, 0, 0)), for shaders that filter by hand with the image's row
// and depth pitch. A linear image in GENERAL and a buffer over the same
// memory read the same bytes (Vulkan's rules for host-accessible aliases).
// kUnsupported where the image is not host-mapped or its texels do not fit
// one texel view.
struct ImageTexels {
  Handle<VkBuffer> buffer;
  Handle<VkBufferView> view;
};
Result<ImageTexels> create_image_texels(const Context& ctx, const Image& image, VkFormat element);

// A texel view of `range` bytes of `buffer` from `offset` (the buffer needs a texel-buffer usage).
Result<Handle<VkBufferView>> create_buffer_view(const Context& ctx, VkBuffer buffer, VkFormat format,
                                                VkDeviceSize offset, VkDeviceSize range);

}  // namespace vxr::gpu
