#include "gpu/resources.h"

#include <atomic>
#include <cstdint>
#include <cstring>

#if defined(__linux__)
#include <sys/mman.h>
#endif

#include "core/trace.h"
#include "gpu/vk_check.h"

namespace vxr::gpu {

namespace {

// A CPU device's memory is the process's: a large linear image there (a
// brick atlas, whose slot's rows lie among every other slot's, megabytes
// apart) is read at random by rays, which with 4 KiB pages miss the TLB on
// nearly every brick. Transparent huge pages where the kernel offers them
// on request; the pages are touched later by the host's writes (sparse
// vessels at step 0.5: 2.76-2.84 ms a frame against 2.95-3.13,
// docs/skipping-perf.md, twenty-second round). A hint: nothing changes where it is refused.
void advise_huge_pages(void* base, VkDeviceSize bytes) {
#if defined(__linux__) && defined(MADV_HUGEPAGE)
  constexpr uintptr_t kHuge = uintptr_t(2) << 20;
  const uintptr_t lo = (reinterpret_cast<uintptr_t>(base) + kHuge - 1) & ~(kHuge - 1);
  const uintptr_t hi = (reinterpret_cast<uintptr_t>(base) + bytes) & ~(kHuge - 1);
  if (hi > lo) madvise(reinterpret_cast<void*>(lo), hi - lo, MADV_HUGEPAGE);
#else
  (void)base;
  (void)bytes;
#endif
}

Result<Handle<VkDeviceMemory>> allocate_memory(const Context& ctx, VkDeviceSize bytes, uint32_t type) {
  VkMemoryAllocateInfo mai{VK_STRUCTURE_TYPE_MEMORY_ALLOCATE_INFO};
  mai.allocationSize = bytes;
  mai.memoryTypeIndex = type;
  VkDeviceMemory mem = VK_NULL_HANDLE;
  VXR_VK_TRY(vkAllocateMemory(ctx.device(), &mai, nullptr, &mem));
  return Handle<VkDeviceMemory>(ctx.device(), mem);
}

}  // namespace

Result<Buffer> create_buffer(const Context& ctx, const BufferCreateInfo& info) {
  if (info.size == 0) return invalid_argument(std::string(info.debug_name) + ": buffer size is 0");
  VkDevice dev = ctx.device();
  VkBufferCreateInfo bci{VK_STRUCTURE_TYPE_BUFFER_CREATE_INFO};
  bci.size = info.size;
  bci.usage = info.usage;
  bci.sharingMode = VK_SHARING_MODE_EXCLUSIVE;
  VkBuffer raw = VK_NULL_HANDLE;
  VXR_VK_TRY(vkCreateBuffer(dev, &bci, nullptr, &raw));
  Buffer b;
  b.buffer = Handle<VkBuffer>(dev, raw);
  b.size = info.size;

  VkMemoryRequirements req;
  vkGetBufferMemoryRequirements(dev, raw, &req);
  VkMemoryPropertyFlags required = 0, preferred = 0;
  switch (info.intent) {
    case MemoryIntent::kDeviceLocal: required = VK_MEMORY_PROPERTY_DEVICE_LOCAL_BIT; break;
    case MemoryIntent::kUpload:
      required = VK_MEMORY_PROPERTY_HOST_VISIBLE_BIT | VK_MEMORY_PROPERTY_HOST_COHERENT_BIT;
      break;
    case MemoryIntent::kReadback:
    case MemoryIntent::kHostShared:
      required = VK_MEMORY_PROPERTY_HOST_VISIBLE_BIT | VK_MEMORY_PROPERTY_HOST_COHERENT_BIT;
      preferred = VK_MEMORY_PROPERTY_HOST_CACHED_BIT;
      break;
  }
  VXR_ASSIGN_OR_RETURN(uint32_t type, ctx.find_memory_type(req.memoryTypeBits, required, preferred));
  VXR_ASSIGN_OR_RETURN(b.memory, allocate_memory(ctx, req.size, type));
  VXR_VK_TRY(vkBindBufferMemory(dev, raw, b.memory, 0));
  if (info.intent != MemoryIntent::kDeviceLocal)
    VXR_VK_TRY(vkMapMemory(dev, b.memory, 0, VK_WHOLE_SIZE, 0, &b.mapped));
  return b;
}

bool host_mapped_image_supported(const Context& ctx, VkImageType type, VkFormat format, VkImageUsageFlags usage,
                                 VkExtent3D extent) {
  const VkPhysicalDeviceType t = ctx.info().type;
  if (t != VK_PHYSICAL_DEVICE_TYPE_CPU && t != VK_PHYSICAL_DEVICE_TYPE_INTEGRATED_GPU) return false;
  VkImageFormatProperties props{};
  if (vkGetPhysicalDeviceImageFormatProperties(ctx.physical_device(), format, type, VK_IMAGE_TILING_LINEAR, usage, 0,
                                               &props) != VK_SUCCESS)
    return false;
  if (extent.width > props.maxExtent.width || extent.height > props.maxExtent.height ||
      extent.depth > props.maxExtent.depth)
    return false;
  VkFormatProperties fp{};
  vkGetPhysicalDeviceFormatProperties(ctx.physical_device(), format, &fp);
  const VkFormatFeatureFlags need = VK_FORMAT_FEATURE_SAMPLED_IMAGE_BIT | VK_FORMAT_FEATURE_SAMPLED_IMAGE_FILTER_LINEAR_BIT;
  if ((fp.linearTilingFeatures & need) != need) return false;
  // Memory that is both the device's and the host's.
  return ctx.find_memory_type(~0u, VK_MEMORY_PROPERTY_DEVICE_LOCAL_BIT | VK_MEMORY_PROPERTY_HOST_VISIBLE_BIT |
                                       VK_MEMORY_PROPERTY_HOST_COHERENT_BIT)
      .is_ok();
}

uint32_t format_texel_bytes(VkFormat format) {
  switch (format) {
    case VK_FORMAT_R8_UNORM:
    case VK_FORMAT_R8_SNORM:
    case VK_FORMAT_R8_UINT: return 1;
    case VK_FORMAT_R16_UNORM:
    case VK_FORMAT_R16_SNORM:
    case VK_FORMAT_R16_SFLOAT:
    case VK_FORMAT_R16_UINT: return 2;
    case VK_FORMAT_R32_SFLOAT:
    case VK_FORMAT_R32_UINT:
    case VK_FORMAT_R8G8B8A8_UNORM:
    case VK_FORMAT_R8G8B8A8_SRGB:
    case VK_FORMAT_B8G8R8A8_UNORM:
    case VK_FORMAT_B8G8R8A8_SRGB:
    case VK_FORMAT_D32_SFLOAT: return 4;
    case VK_FORMAT_R16G16B16A16_SFLOAT: return 8;
    case VK_FORMAT_R32G32B32A32_SFLOAT: return 16;
    default: return 0;
  }
}

Result<Image> create_image(const Context& ctx, const ImageCreateInfo& info) {
  const auto& lim = ctx.limits();
  const uint32_t max_dim = info.type == VK_IMAGE_TYPE_3D ? lim.maxImageDimension3D : lim.maxImageDimension2D;
  const VkExtent3D e = info.extent;
  if (e.width == 0 || e.height == 0 || e.depth == 0)
    return invalid_argument(std::string(info.debug_name) + ": image extent has a zero side");
  if (e.width > max_dim || e.height > max_dim || (info.type == VK_IMAGE_TYPE_3D && e.depth > max_dim))
    return out_of_range(std::string(info.debug_name) + ": image " + std::to_string(e.width) + "x" +
                        std::to_string(e.height) + "x" + std::to_string(e.depth) + " exceeds the device limit " +
                        std::to_string(max_dim));

  VkDevice dev = ctx.device();
  VkImageCreateInfo ici{VK_STRUCTURE_TYPE_IMAGE_CREATE_INFO};
  ici.imageType = info.type;
  ici.format = info.format;
  ici.extent = info.type == VK_IMAGE_TYPE_3D ? e : VkExtent3D{e.width, e.height, 1};
  ici.mipLevels = 1;
  ici.arrayLayers = 1;
  ici.samples = VK_SAMPLE_COUNT_1_BIT;
  ici.tiling = info.host_mapped ? VK_IMAGE_TILING_LINEAR : VK_IMAGE_TILING_OPTIMAL;
  ici.usage = info.usage;
  ici.sharingMode = VK_SHARING_MODE_EXCLUSIVE;
  // PREINITIALIZED: what the host writes before the first transition is kept.
  ici.initialLayout = info.host_mapped ? VK_IMAGE_LAYOUT_PREINITIALIZED : VK_IMAGE_LAYOUT_UNDEFINED;
  VkImage raw = VK_NULL_HANDLE;
  VXR_VK_TRY(vkCreateImage(dev, &ici, nullptr, &raw));
  Image img;
  img.image = Handle<VkImage>(dev, raw);
  img.format = info.format;
  img.extent = ici.extent;
  img.type = info.type;
  img.layout = ici.initialLayout;

  VkMemoryRequirements req;
  vkGetImageMemoryRequirements(dev, raw, &req);
  if (req.size > lim.maxStorageBufferRange && req.size > (VkDeviceSize(2) << 30))
    return out_of_range(std::string(info.debug_name) + ": image needs " + std::to_string(req.size) +
                        " bytes, more than one allocation may hold");
  const VkMemoryPropertyFlags required =
      info.host_mapped ? VkMemoryPropertyFlags(VK_MEMORY_PROPERTY_HOST_VISIBLE_BIT | VK_MEMORY_PROPERTY_HOST_COHERENT_BIT)
                       : VkMemoryPropertyFlags(VK_MEMORY_PROPERTY_DEVICE_LOCAL_BIT);
  VXR_ASSIGN_OR_RETURN(uint32_t type, ctx.find_memory_type(req.memoryTypeBits, required, VK_MEMORY_PROPERTY_DEVICE_LOCAL_BIT));
  VXR_ASSIGN_OR_RETURN(img.memory, allocate_memory(ctx, req.size, type));
  VXR_VK_TRY(vkBindImageMemory(dev, raw, img.memory, 0));
  if (info.host_mapped) {
    void* base = nullptr;
    VXR_VK_TRY(vkMapMemory(dev, img.memory, 0, VK_WHOLE_SIZE, 0, &base));  // unmapped when the memory is freed
    if (ctx.info().is_cpu()) advise_huge_pages(base, req.size);
    const VkImageSubresource sub{VK_IMAGE_ASPECT_COLOR_BIT, 0, 0};
    VkSubresourceLayout layout{};
    vkGetImageSubresourceLayout(dev, raw, &sub, &layout);
    img.mapped = static_cast<uint8_t*>(base) + layout.offset;
    img.mapped_offset = layout.offset;
    img.memory_bytes = req.size;
    img.memory_type = type;
    img.row_pitch = layout.rowPitch;
    img.depth_pitch = info.type == VK_IMAGE_TYPE_3D ? layout.depthPitch : layout.size;
  }

  const bool depth = info.format == VK_FORMAT_D32_SFLOAT;
  VkImageViewCreateInfo vci{VK_STRUCTURE_TYPE_IMAGE_VIEW_CREATE_INFO};
  vci.image = raw;
  vci.viewType = info.type == VK_IMAGE_TYPE_3D ? VK_IMAGE_VIEW_TYPE_3D : VK_IMAGE_VIEW_TYPE_2D;
  vci.format = info.format;
  vci.subresourceRange = {static_cast<VkImageAspectFlags>(depth ? VK_IMAGE_ASPECT_DEPTH_BIT : VK_IMAGE_ASPECT_COLOR_BIT), 0, 1, 0, 1};
  VkImageView view = VK_NULL_HANDLE;
  VXR_VK_TRY(vkCreateImageView(dev, &vci, nullptr, &view));
  img.view = Handle<VkImageView>(dev, view);
  return img;
}

void image_barrier(VkCommandBuffer cmd, VkImage image, VkImageAspectFlags aspect, VkImageLayout from, VkImageLayout to,
                   VkPipelineStageFlags2 src_stage, VkAccessFlags2 src_access, VkPipelineStageFlags2 dst_stage,
                   VkAccessFlags2 dst_access) {
  VkImageMemoryBarrier2 b{VK_STRUCTURE_TYPE_IMAGE_MEMORY_BARRIER_2};
  b.srcStageMask = src_stage;
  b.srcAccessMask = src_access;
  b.dstStageMask = dst_stage;
  b.dstAccessMask = dst_access;
  b.oldLayout = from;
  b.newLayout = to;
  b.srcQueueFamilyIndex = VK_QUEUE_FAMILY_IGNORED;
  b.dstQueueFamilyIndex = VK_QUEUE_FAMILY_IGNORED;
  b.image = image;
  b.subresourceRange = {aspect, 0, 1, 0, 1};
  VkDependencyInfo dep{VK_STRUCTURE_TYPE_DEPENDENCY_INFO};
  dep.imageMemoryBarrierCount = 1;
  dep.pImageMemoryBarriers = &b;
  vkCmdPipelineBarrier2(cmd, &dep);
}

void transition_image(VkCommandBuffer cmd, Image& image, VkImageLayout new_layout, VkPipelineStageFlags2 src_stage,
                      VkAccessFlags2 src_access, VkPipelineStageFlags2 dst_stage, VkAccessFlags2 dst_access) {
  const VkImageAspectFlags aspect =
      image.format == VK_FORMAT_D32_SFLOAT ? VK_IMAGE_ASPECT_DEPTH_BIT : VK_IMAGE_ASPECT_COLOR_BIT;
  image_barrier(cmd, image.image, aspect, image.layout, new_layout, src_stage, src_access, dst_stage, dst_access);
  image.layout = new_layout;
}

Status upload_image(Context& ctx, Image& image, const void* texels, size_t bytes) {
  VXR_TRACE_SCOPE("gpu.upload_image");
  const uint64_t expected = uint64_t(image.extent.width) * image.extent.height * image.extent.depth *
                            format_texel_bytes(image.format);
  if (expected != bytes)
    return invalid_argument("upload_image: got " + std::to_string(bytes) + " bytes, image needs " +
                            std::to_string(expected));
  if (image.mapped) {
    const size_t row = size_t(image.extent.width) * format_texel_bytes(image.format);
    const auto* src = static_cast<const uint8_t*>(texels);
    for (uint32_t z = 0; z < image.extent.depth; ++z)
      for (uint32_t y = 0; y < image.extent.height; ++y)
        std::memcpy(image.mapped + z * image.depth_pitch + y * image.row_pitch,
                    src + (size_t(z) * image.extent.height + y) * row, row);
    return ctx.submit_and_wait([&](VkCommandBuffer cmd) {
      transition_image(cmd, image, VK_IMAGE_LAYOUT_GENERAL, VK_PIPELINE_STAGE_2_HOST_BIT, VK_ACCESS_2_HOST_WRITE_BIT,
                       VK_PIPELINE_STAGE_2_COMPUTE_SHADER_BIT | VK_PIPELINE_STAGE_2_FRAGMENT_SHADER_BIT,
                       VK_ACCESS_2_SHADER_SAMPLED_READ_BIT);
    });
  }
  VXR_ASSIGN_OR_RETURN(Buffer staging,
                       create_buffer(ctx, {bytes, VK_BUFFER_USAGE_TRANSFER_SRC_BIT, MemoryIntent::kUpload, "staging"}));
  std::memcpy(staging.mapped, texels, bytes);
  return ctx.submit_and_wait([&](VkCommandBuffer cmd) {
    transition_image(cmd, image, VK_IMAGE_LAYOUT_TRANSFER_DST_OPTIMAL, VK_PIPELINE_STAGE_2_NONE, 0,
                     VK_PIPELINE_STAGE_2_COPY_BIT, VK_ACCESS_2_TRANSFER_WRITE_BIT);
    VkBufferImageCopy region{};
    region.imageSubresource = {VK_IMAGE_ASPECT_COLOR_BIT, 0, 0, 1};
    region.imageExtent = image.extent;
    vkCmdCopyBufferToImage(cmd, staging.buffer, image.image, VK_IMAGE_LAYOUT_TRANSFER_DST_OPTIMAL, 1, &region);
    transition_image(cmd, image, VK_IMAGE_LAYOUT_SHADER_READ_ONLY_OPTIMAL, VK_PIPELINE_STAGE_2_COPY_BIT,
                     VK_ACCESS_2_TRANSFER_WRITE_BIT,
                     VK_PIPELINE_STAGE_2_COMPUTE_SHADER_BIT | VK_PIPELINE_STAGE_2_FRAGMENT_SHADER_BIT,
                     VK_ACCESS_2_SHADER_SAMPLED_READ_BIT);
  });
}

namespace {
std::atomic<uint64_t> g_readbacks{0};
}  // namespace

uint64_t readback_count() { return g_readbacks.load(); }

void memory_barrier(VkCommandBuffer cmd, VkPipelineStageFlags2 src_stage, VkAccessFlags2 src_access,
                    VkPipelineStageFlags2 dst_stage, VkAccessFlags2 dst_access) {
  VkMemoryBarrier2 b{VK_STRUCTURE_TYPE_MEMORY_BARRIER_2};
  b.srcStageMask = src_stage;
  b.srcAccessMask = src_access;
  b.dstStageMask = dst_stage;
  b.dstAccessMask = dst_access;
  VkDependencyInfo dep{VK_STRUCTURE_TYPE_DEPENDENCY_INFO};
  dep.memoryBarrierCount = 1;
  dep.pMemoryBarriers = &b;
  vkCmdPipelineBarrier2(cmd, &dep);
}

void buffer_barrier(VkCommandBuffer cmd, VkBuffer buffer, VkPipelineStageFlags2 src_stage, VkAccessFlags2 src_access,
                    VkPipelineStageFlags2 dst_stage, VkAccessFlags2 dst_access) {
  VkBufferMemoryBarrier2 b{VK_STRUCTURE_TYPE_BUFFER_MEMORY_BARRIER_2};
  b.srcStageMask = src_stage;
  b.srcAccessMask = src_access;
  b.dstStageMask = dst_stage;
  b.dstAccessMask = dst_access;
  b.srcQueueFamilyIndex = b.dstQueueFamilyIndex = VK_QUEUE_FAMILY_IGNORED;
  b.buffer = buffer;
  b.size = VK_WHOLE_SIZE;
  VkDependencyInfo dep{VK_STRUCTURE_TYPE_DEPENDENCY_INFO};
  dep.bufferMemoryBarrierCount = 1;
  dep.pBufferMemoryBarriers = &b;
  vkCmdPipelineBarrier2(cmd, &dep);
}

Status readback_image(Context& ctx, Image& image, void* out, size_t bytes, VkImageLayout final_layout) {
  ImageReadback once;
  return once.read(ctx, image, out, bytes, final_layout);
}

Status ImageReadback::read(Context& ctx, Image& image, void* out, size_t bytes, VkImageLayout final_layout) {
  VXR_TRACE_SCOPE("gpu.readback_image");
  ++g_readbacks;
  const bool depth = image.format == VK_FORMAT_D32_SFLOAT;
  const uint64_t expected = uint64_t(image.extent.width) * image.extent.height * image.extent.depth *
                            format_texel_bytes(image.format);
  if (expected != bytes)
    return invalid_argument("readback_image: buffer has " + std::to_string(bytes) + " bytes, image needs " +
                            std::to_string(expected));
  if (staging_.size < bytes) {
    VXR_ASSIGN_OR_RETURN(staging_, create_buffer(ctx, {bytes, VK_BUFFER_USAGE_TRANSFER_DST_BIT,
                                                       MemoryIntent::kReadback, "readback"}));
  }
  const Buffer& staging = staging_;
  VXR_RETURN_IF_ERROR(ctx.submit_and_wait([&](VkCommandBuffer cmd) {
    transition_image(cmd, image, VK_IMAGE_LAYOUT_TRANSFER_SRC_OPTIMAL, VK_PIPELINE_STAGE_2_ALL_COMMANDS_BIT,
                     VK_ACCESS_2_MEMORY_WRITE_BIT, VK_PIPELINE_STAGE_2_COPY_BIT, VK_ACCESS_2_TRANSFER_READ_BIT);
    VkBufferImageCopy region{};
    region.imageSubresource = {static_cast<VkImageAspectFlags>(depth ? VK_IMAGE_ASPECT_DEPTH_BIT : VK_IMAGE_ASPECT_COLOR_BIT), 0, 0, 1};
    region.imageExtent = image.extent;
    vkCmdCopyImageToBuffer(cmd, image.image, VK_IMAGE_LAYOUT_TRANSFER_SRC_OPTIMAL, staging.buffer, 1, &region);
    transition_image(cmd, image, final_layout, VK_PIPELINE_STAGE_2_COPY_BIT, VK_ACCESS_2_TRANSFER_READ_BIT,
                     VK_PIPELINE_STAGE_2_ALL_COMMANDS_BIT, VK_ACCESS_2_MEMORY_READ_BIT | VK_ACCESS_2_MEMORY_WRITE_BIT);
    buffer_barrier(cmd, staging.buffer, VK_PIPELINE_STAGE_2_COPY_BIT, VK_ACCESS_2_TRANSFER_WRITE_BIT,
                   VK_PIPELINE_STAGE_2_HOST_BIT, VK_ACCESS_2_HOST_READ_BIT);
  }));
  std::memcpy(out, staging.mapped, bytes);
  return Status::ok();
}

static Result<Handle<VkSampler>> make_sampler(const Context& ctx, VkFilter filter) {
  VkSamplerCreateInfo sci{VK_STRUCTURE_TYPE_SAMPLER_CREATE_INFO};
  sci.magFilter = sci.minFilter = filter;
  sci.mipmapMode = VK_SAMPLER_MIPMAP_MODE_NEAREST;
  sci.addressModeU = sci.addressModeV = sci.addressModeW = VK_SAMPLER_ADDRESS_MODE_CLAMP_TO_EDGE;
  sci.maxLod = 0.0f;
  VkSampler s = VK_NULL_HANDLE;
  VXR_VK_TRY(vkCreateSampler(ctx.device(), &sci, nullptr, &s));
  return Handle<VkSampler>(ctx.device(), s);
}

Result<Handle<VkSampler>> create_linear_clamp_sampler(const Context& ctx) {
  return make_sampler(ctx, VK_FILTER_LINEAR);
}
Result<Handle<VkSampler>> create_nearest_clamp_sampler(const Context& ctx) {
  return make_sampler(ctx, VK_FILTER_NEAREST);
}

Result<ImageTexels> create_image_texels(const Context& ctx, const Image& image, VkFormat element) {
  if (!image.mapped) return unsupported("image texels: the image is not host-mapped");
  const uint32_t eb = format_texel_bytes(element);
  // Whole elements over the texels (the memory past them is the image's too).
  const VkDeviceSize bytes = (image.depth_pitch * image.extent.depth + eb - 1) / eb * eb;
  const VkPhysicalDeviceLimits& lim = ctx.limits();
  if (eb == 0 || image.mapped_offset % lim.minTexelBufferOffsetAlignment != 0 ||
      image.mapped_offset + bytes > image.memory_bytes || bytes / eb > lim.maxTexelBufferElements)
    return unsupported("image texels: " + std::to_string(bytes) + " bytes of texels do not fit one texel view");
  VkBufferCreateInfo bci{VK_STRUCTURE_TYPE_BUFFER_CREATE_INFO};
  bci.size = image.memory_bytes;
  bci.usage = VK_BUFFER_USAGE_STORAGE_TEXEL_BUFFER_BIT;
  bci.sharingMode = VK_SHARING_MODE_EXCLUSIVE;
  VkBuffer raw = VK_NULL_HANDLE;
  VXR_VK_TRY(vkCreateBuffer(ctx.device(), &bci, nullptr, &raw));
  ImageTexels t;
  t.buffer = Handle<VkBuffer>(ctx.device(), raw);
  VkMemoryRequirements req;
  vkGetBufferMemoryRequirements(ctx.device(), raw, &req);
  if (req.size > image.memory_bytes || !(req.memoryTypeBits & (1u << image.memory_type)))
    return unsupported("image texels: a buffer cannot be bound to the image's memory");
  VXR_VK_TRY(vkBindBufferMemory(ctx.device(), raw, image.memory.get(), 0));
  VXR_ASSIGN_OR_RETURN(t.view, create_buffer_view(ctx, raw, element, image.mapped_offset, bytes));
  return t;
}

Result<Handle<VkBufferView>> create_buffer_view(const Context& ctx, VkBuffer buffer, VkFormat format,
                                                VkDeviceSize offset, VkDeviceSize range) {
  VkBufferViewCreateInfo ci{VK_STRUCTURE_TYPE_BUFFER_VIEW_CREATE_INFO};
  ci.buffer = buffer;
  ci.format = format;
  ci.offset = offset;
  ci.range = range;
  VkBufferView v = VK_NULL_HANDLE;
  VXR_VK_TRY(vkCreateBufferView(ctx.device(), &ci, nullptr, &v));
  return Handle<VkBufferView>(ctx.device(), v);
}

}  // namespace vxr::gpu
