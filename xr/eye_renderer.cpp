#include "xr/eye_renderer.h"

#include <cstring>

#include "core/trace.h"

namespace vxr::xr {

void image_barrier(VkCommandBuffer cmd, VkImage image, VkImageAspectFlags aspect, VkImageLayout from,
                   VkImageLayout to) {
  VkImageMemoryBarrier2 b{VK_STRUCTURE_TYPE_IMAGE_MEMORY_BARRIER_2};
  b.srcStageMask = VK_PIPELINE_STAGE_2_ALL_COMMANDS_BIT;
  b.srcAccessMask = VK_ACCESS_2_MEMORY_WRITE_BIT | VK_ACCESS_2_MEMORY_READ_BIT;
  b.dstStageMask = VK_PIPELINE_STAGE_2_ALL_COMMANDS_BIT;
  b.dstAccessMask = VK_ACCESS_2_MEMORY_WRITE_BIT | VK_ACCESS_2_MEMORY_READ_BIT;
  b.oldLayout = from;
  b.newLayout = to;
  b.srcQueueFamilyIndex = b.dstQueueFamilyIndex = VK_QUEUE_FAMILY_IGNORED;
  b.image = image;
  b.subresourceRange = {aspect, 0, 1, 0, 1};
  VkDependencyInfo dep{VK_STRUCTURE_TYPE_DEPENDENCY_INFO};
  dep.imageMemoryBarrierCount = 1;
  dep.pImageMemoryBarriers = &b;
  vkCmdPipelineBarrier2(cmd, &dep);
}

Result<std::unique_ptr<EyeRenderer>> EyeRenderer::create(gpu::Context& ctx, const DenseVolume& volume) {
  std::unique_ptr<EyeRenderer> r(new EyeRenderer(ctx));
  VXR_ASSIGN_OR_RETURN(r->caster_, Raycaster::create(ctx));
  VXR_RETURN_IF_ERROR(r->caster_->set_volume(volume));
  r->placement_ = {volume.dims, volume.voxel_size};
  return r;
}

Result<ImageRgba8> EyeRenderer::render(const ViewSpec& view, const VolumeTransform& t,
                                       const RenderSettings& settings, const LensWarp& warp, uint64_t* rays) {
  VXR_TRACE_SCOPE("xr.render_view");
  const Camera camera = camera_for_view(view, t);
  if (warp.enabled) return render_lens_warped(*caster_, camera, settings, view.width, view.height, warp, rays);
  if (rays) *rays = uint64_t(view.width) * view.height;
  return caster_->render(camera, settings, view.width, view.height);
}

Status EyeRenderer::upload(const TargetImage& target, const ImageRgba8& image) {
  VXR_TRACE_SCOPE("xr.upload_view");
  if (target.extent.width != image.width || target.extent.height != image.height)
    return invalid_argument("target image is " + std::to_string(target.extent.width) + "x" +
                            std::to_string(target.extent.height) + ", the view was rendered at " +
                            std::to_string(image.width) + "x" + std::to_string(image.height));
  bool bgra = false;
  switch (target.format) {
    case VK_FORMAT_R8G8B8A8_UNORM:
    case VK_FORMAT_R8G8B8A8_SRGB: break;
    case VK_FORMAT_B8G8R8A8_UNORM:
    case VK_FORMAT_B8G8R8A8_SRGB: bgra = true; break;
    default: return unsupported("target image format " + std::to_string(target.format) + " is not 8-bit RGBA/BGRA");
  }
  const VkDeviceSize bytes = image.pixels.size();
  if (!staging_.buffer || staging_.size < bytes) {
    VXR_ASSIGN_OR_RETURN(staging_, gpu::create_buffer(ctx_, {bytes, VK_BUFFER_USAGE_TRANSFER_SRC_BIT,
                                                             gpu::MemoryIntent::kUpload, "eye staging"}));
  }
  auto* dst = static_cast<uint8_t*>(staging_.mapped);
  for (size_t i = 0; i < bytes; i += 4) {
    dst[i + 0] = image.pixels[i + (bgra ? 2 : 0)];
    dst[i + 1] = image.pixels[i + 1];
    dst[i + 2] = image.pixels[i + (bgra ? 0 : 2)];
    dst[i + 3] = 255;  // premultiplied over black: opaque
  }
  if (!staging_.host_coherent) {
    VkMappedMemoryRange range{VK_STRUCTURE_TYPE_MAPPED_MEMORY_RANGE};
    range.memory = staging_.memory;
    range.size = VK_WHOLE_SIZE;
    vkFlushMappedMemoryRanges(ctx_.device(), 1, &range);
  }
  return ctx_.submit_and_wait([&](VkCommandBuffer cmd) {
    image_barrier(cmd, target.image, VK_IMAGE_ASPECT_COLOR_BIT, target.layout, VK_IMAGE_LAYOUT_TRANSFER_DST_OPTIMAL);
    VkBufferImageCopy region{};
    region.imageSubresource = {VK_IMAGE_ASPECT_COLOR_BIT, 0, 0, 1};
    region.imageExtent = {image.width, image.height, 1};
    vkCmdCopyBufferToImage(cmd, staging_.buffer, target.image, VK_IMAGE_LAYOUT_TRANSFER_DST_OPTIMAL, 1, &region);
    image_barrier(cmd, target.image, VK_IMAGE_ASPECT_COLOR_BIT, VK_IMAGE_LAYOUT_TRANSFER_DST_OPTIMAL,
                  target.layout == VK_IMAGE_LAYOUT_UNDEFINED ? VK_IMAGE_LAYOUT_GENERAL : target.layout);
  });
}

}  // namespace vxr::xr
