// Records the views of a frame through the out-of-core renderer
// (VolumeRenderer, implemented by BrickRenderer) into a FrameTarget's images:
// the frame loop records every eye, lens warp included, into one
// command buffer and submits it once; nothing is read back.
//
// Lens warp: the warped grid (xr/lens_warp.h) is ONE view whose rays follow
// the warp (RenderTarget::warp_x/warp_y), drawn into one intermediate image
// per eye (RGBA8 for 8-bit UNORM targets, float for the others so an sRGB
// target encodes unrounded linear values); one blit of up to nine
// linear-filtered regions stretches the bands onto the eye's pixels (the
// centre band is a 1:1 copy).
#pragma once

#include <memory>
#include <vector>

#include "gpu/resources.h"
#include "render/annotation_renderer.h"
#include "render/lod/brick_renderer.h"
#include "xr/frame_target.h"
#include "xr/lens_warp.h"
#include "xr/volume_transform.h"

namespace vxr::xr {

class EyeRenderer {
 public:
  // `stream_from` (may be null): the cache whose loader threads read missing
  // bricks; null reads them after each render() (tests). Small volumes are
  // preloaded whole.
  // `channels`: the source channels drawn (BrickPoolOptions::channels; empty: the first up to 4).
  static Result<std::unique_ptr<EyeRenderer>> create(gpu::Context& ctx, std::shared_ptr<const ChunkSource> source,
                                                     ChunkCache* stream_from = nullptr,
                                                     std::vector<uint32_t> channels = {});

  // Annotations drawn with every view from now on (world units, the volume
  // centred at the origin: AnnotationScene). Each view records their pass
  // first, into the same command buffer; rays end at their depth. Empty: none
  // (`make_pass` builds the pass anyway: scenes that come later add no pipeline).
  Status set_annotations(AnnotationScene scene, bool make_pass = false);

  Status begin_frame(VkCommandBuffer cmd, const BrickFrameSettings& frame) {
    return renderer_->begin_frame(cmd, frame);
  }
  // Records view `index` of the frame into `target` (shown over black: alpha
  // 1). `rays` receives the rays cast, `stats` the view's LOD figures.
  Status record(VkCommandBuffer cmd, size_t index, const ViewSpec& view, const VolumeTransform& t,
                const RenderSettings& settings, const BrickFrameSettings& frame, const LensWarp& warp,
                const TargetImage& target, uint64_t* rays = nullptr, BrickFrameStats* stats = nullptr);

  // Tests and benchmarks: one frame of one view into an offscreen RGBA8
  // image, submitted, waited for and read back (opaque, over black).
  Result<ImageRgba8> render(const ViewSpec& view, const VolumeTransform& t, const RenderSettings& settings,
                            const LensWarp& warp, uint64_t* rays = nullptr);

  VolumePlacement placement() const { return renderer_->placement(); }
  BrickRenderer& renderer() { return *renderer_; }

 private:
  explicit EyeRenderer(gpu::Context& ctx) : ctx_(ctx) {}
  // The warped intermediate of view `index`, (re)made at this size and format.
  Result<gpu::Image*> warp_image(size_t index, uint32_t width, uint32_t height, VkFormat format);

  gpu::Context& ctx_;
  std::shared_ptr<const ChunkSource> source_;
  std::unique_ptr<BrickRenderer> renderer_;
  std::unique_ptr<AnnotationRenderer> annotation_renderer_;  // made when a scene is set
  AnnotationScene annotations_;
  std::vector<gpu::Image> warped_;  // per view index
  gpu::Image offscreen_;            // render()'s target
  gpu::ImageReadback readback_;     // render()'s staging, kept between frames
};

// Records a whole-image layout change with full (ALL_COMMANDS) dependencies:
// used at hand-over points between vxr and a target's owner.
void image_barrier(VkCommandBuffer cmd, VkImage image, VkImageAspectFlags aspect, VkImageLayout from,
                   VkImageLayout to);

}  // namespace vxr::xr
