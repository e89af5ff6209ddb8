// Renders one view of the volume for a FrameTarget and copies it into the
// target's image.
//
// Uses the ray caster's public API (render() returns the picture on the CPU),
// then uploads it into the target's VkImage through a staging buffer. At the
// eye sizes vxr uses on lavapipe this round trip costs well under a
// millisecond; a GPU-resident path can replace upload() without touching
// the targets.
#pragma once

#include <memory>

#include "gpu/resources.h"
#include "render/raycaster.h"
#include "xr/frame_target.h"
#include "xr/lens_warp.h"
#include "xr/volume_transform.h"

namespace vxr::xr {

class EyeRenderer {
 public:
  static Result<std::unique_ptr<EyeRenderer>> create(gpu::Context& ctx, const DenseVolume& volume);

  // Premultiplied RGBA of `view`; `rays` receives the rays cast.
  Result<ImageRgba8> render(const ViewSpec& view, const VolumeTransform& t, const RenderSettings& settings,
                            const LensWarp& warp, uint64_t* rays = nullptr);

  // Copies `image` (shown over black, opaque) into `target`, which must be
  // `image`'s size, an 8-bit RGBA or BGRA format and allow transfer writes.
  Status upload(const TargetImage& target, const ImageRgba8& image);

  const VolumePlacement& placement() const { return placement_; }

 private:
  explicit EyeRenderer(gpu::Context& ctx) : ctx_(ctx) {}
  gpu::Context& ctx_;
  std::unique_ptr<Raycaster> caster_;
  VolumePlacement placement_;
  gpu::Buffer staging_;
};

// Records a whole-image layout change with full (ALL_COMMANDS) dependencies:
// used at hand-over points between vxr and a target's owner.
void image_barrier(VkCommandBuffer cmd, VkImage image, VkImageAspectFlags aspect, VkImageLayout from,
                   VkImageLayout to);

}  // namespace vxr::xr
