#include "xr/eye_renderer.h"

#include <cstring>

#include "core/trace.h"

namespace vxr::xr {

void image_barrier(VkCommandBuffer cmd, VkImage image, VkImageAspectFlags aspect, VkImageLayout from,
                   VkImageLayout to) {
  constexpr VkAccessFlags2 kAll = VK_ACCESS_2_MEMORY_WRITE_BIT | VK_ACCESS_2_MEMORY_READ_BIT;
  gpu::image_barrier(cmd, image, aspect, from, to, VK_PIPELINE_STAGE_2_ALL_COMMANDS_BIT, kAll,
                     VK_PIPELINE_STAGE_2_ALL_COMMANDS_BIT, kAll);
}

Result<std::unique_ptr<EyeRenderer>> EyeRenderer::create(gpu::Context& ctx, std::shared_ptr<const ChunkSource> source,
                                                         ChunkCache* stream_from, std::vector<uint32_t> channels) {
  if (!source) return invalid_argument("eye renderer: no volume");
  std::unique_ptr<EyeRenderer> r(new EyeRenderer(ctx));
  r->source_ = std::move(source);
  BrickRendererOptions o;
  o.stream_from = stream_from;
  o.preload_if_fits = true;
  o.pool.channels = std::move(channels);
  VXR_ASSIGN_OR_RETURN(r->renderer_, BrickRenderer::create(ctx, *r->source_, o));
  return r;
}

Status EyeRenderer::set_annotations(AnnotationScene scene, bool make_pass) {
  if ((make_pass || !scene.empty()) && !annotation_renderer_) {
    VXR_ASSIGN_OR_RETURN(annotation_renderer_, AnnotationRenderer::create(ctx_));
  }
  annotations_ = std::move(scene);
  return Status::ok();
}

Result<gpu::Image*> EyeRenderer::warp_image(size_t index, uint32_t width, uint32_t height, VkFormat format) {
  if (warped_.size() <= index) warped_.resize(index + 1);
  gpu::Image& img = warped_[index];
  if (img.image && img.extent.width == width && img.extent.height == height && img.format == format) return &img;
  VkImageUsageFlags usage = VK_IMAGE_USAGE_TRANSFER_SRC_BIT | VK_IMAGE_USAGE_TRANSFER_DST_BIT;
  // RGBA8: the rays write it; float (sRGB targets): filled by blits, sampled only by the view's creation rules.
  usage |= format == VK_FORMAT_R8G8B8A8_UNORM ? VK_IMAGE_USAGE_STORAGE_BIT : VK_IMAGE_USAGE_SAMPLED_BIT;
  // Made at the first frame (or when the eye size changes), not per frame.
  VXR_ASSIGN_OR_RETURN(img, gpu::create_image(ctx_, {VK_IMAGE_TYPE_2D, format, {width, height, 1}, usage,
                                                     "lens-warped eye"}));
  VXR_RETURN_IF_ERROR(ctx_.submit_and_wait([&](VkCommandBuffer cmd) {
    gpu::transition_image(cmd, img, VK_IMAGE_LAYOUT_GENERAL, VK_PIPELINE_STAGE_2_NONE, 0,
                          VK_PIPELINE_STAGE_2_ALL_COMMANDS_BIT,
                          VK_ACCESS_2_MEMORY_READ_BIT | VK_ACCESS_2_MEMORY_WRITE_BIT);
  }));
  return &img;
}

Status EyeRenderer::record(VkCommandBuffer cmd, size_t index, const ViewSpec& view, const VolumeTransform& t,
                           const RenderSettings& settings, const BrickFrameSettings& frame, const LensWarp& warp,
                           const TargetImage& target, uint64_t* rays, BrickFrameStats* stats) {
  VXR_TRACE_SCOPE("xr.record_view");
  if (target.extent.width != view.width || target.extent.height != view.height)
    return invalid_argument("target image is " + std::to_string(target.extent.width) + "x" +
                            std::to_string(target.extent.height) + ", the view is " + std::to_string(view.width) +
                            "x" + std::to_string(view.height));
  const Camera camera = camera_for_view(view, t);
  const WarpAxis ax = warp_axis(view.width, warp), ay = warp_axis(view.height, warp);
  RenderTarget out{target.image, target.storage_view, target.format, target.extent, target.layout};
  out.opaque = true;
  if (!annotations_.empty()) {
    // At the eye's full size; with lens warp each ray reads the pixel it passes through.
    VXR_ASSIGN_OR_RETURN(out.under,
                         annotation_renderer_->record(cmd, index, camera, annotations_, view.width, view.height));
  }
  if (!warp.enabled || (ax.warped() == view.width && ay.warped() == view.height)) {
    if (rays) *rays = uint64_t(view.width) * view.height;
    return renderer_->record_view(cmd, camera, settings, frame, out, stats);
  }

  // One view over the whole frustum whose rays follow the warped grid, into
  // the eye's warped intermediate.
  const VkFormat wf = is_unorm8(target.format) ? VK_FORMAT_R8G8B8A8_UNORM : VK_FORMAT_R32G32B32A32_SFLOAT;
  VXR_ASSIGN_OR_RETURN(gpu::Image * wimg, warp_image(index, ax.warped(), ay.warped(), wf));
  RenderTarget grid{wimg->image, wf == VK_FORMAT_R8G8B8A8_UNORM ? wimg->view.get() : VK_NULL_HANDLE, wf,
                    {wimg->extent.width, wimg->extent.height}, VK_IMAGE_LAYOUT_GENERAL};
  grid.opaque = true;
  grid.under = out.under;
  grid.warp_x = ax;
  grid.warp_y = ay;
  VXR_RETURN_IF_ERROR(renderer_->record_view(cmd, camera, settings, frame, grid, stats));
  std::vector<VkImageBlit> blits;
  for (const WarpBand& band : warp_bands(ax, ay)) {
    VkImageBlit b{};
    b.srcSubresource = b.dstSubresource = {VK_IMAGE_ASPECT_COLOR_BIT, 0, 0, 1};
    b.srcOffsets[0] = {int32_t(band.warped[0]), int32_t(band.warped[1]), 0};
    b.srcOffsets[1] = {int32_t(band.warped[2]), int32_t(band.warped[3]), 1};
    b.dstOffsets[0] = {int32_t(band.full[0]), int32_t(band.full[1]), 0};
    b.dstOffsets[1] = {int32_t(band.full[2]), int32_t(band.full[3]), 1};
    blits.push_back(b);
  }
  // Resample: the bands stretched onto the eye's pixels (bilinear, like resample_warped).
  const VkImageLayout final_layout =
      target.layout == VK_IMAGE_LAYOUT_UNDEFINED ? VK_IMAGE_LAYOUT_GENERAL : target.layout;
  image_barrier(cmd, wimg->image, VK_IMAGE_ASPECT_COLOR_BIT, VK_IMAGE_LAYOUT_GENERAL,
                VK_IMAGE_LAYOUT_TRANSFER_SRC_OPTIMAL);
  image_barrier(cmd, target.image, VK_IMAGE_ASPECT_COLOR_BIT, target.layout, VK_IMAGE_LAYOUT_TRANSFER_DST_OPTIMAL);
  vkCmdBlitImage(cmd, wimg->image, VK_IMAGE_LAYOUT_TRANSFER_SRC_OPTIMAL, target.image,
                 VK_IMAGE_LAYOUT_TRANSFER_DST_OPTIMAL, static_cast<uint32_t>(blits.size()), blits.data(),
                 VK_FILTER_LINEAR);
  image_barrier(cmd, target.image, VK_IMAGE_ASPECT_COLOR_BIT, VK_IMAGE_LAYOUT_TRANSFER_DST_OPTIMAL, final_layout);
  image_barrier(cmd, wimg->image, VK_IMAGE_ASPECT_COLOR_BIT, VK_IMAGE_LAYOUT_TRANSFER_SRC_OPTIMAL,
                VK_IMAGE_LAYOUT_GENERAL);
  if (rays) *rays = uint64_t(ax.warped()) * ay.warped();
  return Status::ok();
}

Result<ImageRgba8> EyeRenderer::render(const ViewSpec& view, const VolumeTransform& t, const RenderSettings& settings,
                                       const LensWarp& warp, uint64_t* rays) {
  VXR_TRACE_SCOPE("xr.render_view");
  if (!offscreen_.image || offscreen_.extent.width != view.width || offscreen_.extent.height != view.height) {
    VXR_ASSIGN_OR_RETURN(offscreen_, gpu::create_image(ctx_, {VK_IMAGE_TYPE_2D, VK_FORMAT_R8G8B8A8_UNORM,
                                                              {view.width, view.height, 1},
                                                              VK_IMAGE_USAGE_STORAGE_BIT | VK_IMAGE_USAGE_TRANSFER_SRC_BIT |
                                                                  VK_IMAGE_USAGE_TRANSFER_DST_BIT,
                                                              "offscreen eye"}));
  }
  const TargetImage target{offscreen_.image, offscreen_.format, {view.width, view.height}, VK_IMAGE_LAYOUT_UNDEFINED,
                           offscreen_.view};
  Status recorded = Status::ok();
  const BrickFrameSettings frame;
  VXR_RETURN_IF_ERROR(ctx_.submit_and_wait([&](VkCommandBuffer cmd) {
    recorded = renderer_->begin_frame(cmd, frame);
    if (recorded) recorded = record(cmd, 0, view, t, settings, frame, warp, target, rays);
  }));
  VXR_RETURN_IF_ERROR(recorded);
  offscreen_.layout = VK_IMAGE_LAYOUT_GENERAL;
  ImageRgba8 img(view.width, view.height);
  VXR_RETURN_IF_ERROR(readback_.read(ctx_, offscreen_, img.pixels.data(), img.pixels.size()));
  return img;
}

}  // namespace vxr::xr
