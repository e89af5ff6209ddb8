// The GPU ray caster over one 3D texture (the whole volume at one level).
//
// Owns the volume texture, the transfer-function texture and the compute
// pipeline; render() dispatches one ray per pixel and reads the image back.
// The renderer never opens files: callers hand it a DenseVolume.
#pragma once

#include <memory>
#include <string>

#include "core/image.h"
#include "core/status.h"
#include "gpu/context.h"
#include "gpu/pipeline.h"
#include "gpu/resources.h"
#include "gpu/timer.h"
#include "render/camera.h"
#include "volume/dense_volume.h"

namespace vxr {

enum class OpticalModel { kEmissionAbsorption, kMip };

struct RaycastSettings {
  OpticalModel model = OpticalModel::kEmissionAbsorption;
  std::string colormap = "gray";
  // Window in the data's own units; values below lo map to 0, above hi to 1.
  double window_lo = 0.0;
  double window_hi = 255.0;
  double step_voxels = 0.5;
  // Extinction per voxel where the transfer function's opacity is 1.
  double density = 0.25;
  uint32_t max_steps = 1u << 16;
};

class Raycaster {
 public:
  static Result<std::unique_ptr<Raycaster>> create(gpu::Context& ctx);

  // Uploads the volume as an R8/R16 UNORM 3D texture (u8 / u16 data).
  Status set_volume(const DenseVolume& volume);
  // Renders premultiplied RGBA, top row first.
  Result<ImageRgba8> render(const Camera& camera, const RaycastSettings& settings, uint32_t width, uint32_t height);

 private:
  explicit Raycaster(gpu::Context& ctx) : ctx_(ctx) {}
  Status ensure_target(uint32_t width, uint32_t height);
  Status upload_transfer(const RaycastSettings& settings);

  gpu::Context& ctx_;
  gpu::ComputePipeline pipeline_;
  gpu::Handle<VkDescriptorPool> pool_;
  VkDescriptorSet set_ = VK_NULL_HANDLE;
  gpu::Handle<VkSampler> linear_;
  gpu::Image volume_tex_;
  gpu::Image transfer_tex_;
  gpu::Image target_;
  gpu::GpuTimer timer_;
  VolumePlacement placement_;
  double value_scale_ = 255.0;  // data units per normalised texel unit
  bool has_volume_ = false;
};

// Premultiplied RGBA over an opaque black background (what PNG viewers show).
ImageRgba8 over_black(const ImageRgba8& premultiplied);

}  // namespace vxr
