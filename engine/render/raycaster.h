// The GPU ray caster over whole volumes held in 3D textures (one per channel).
//
// Owns the volume textures, the transfer-function table, an optional depth
// image, the compute pipeline (default path) and the full-screen fragment
// pipeline; both run the same GLSL core (shaders_glsl/include/raycast_core.glsl).
// render() casts one ray per pixel into an RGBA32F image and reads it back;
// 8-bit output is rounded on the CPU (to_rgba8), the same way for the CPU
// reference. The renderer never opens files: callers hand it DenseVolumes.
#pragma once

#include <map>
#include <memory>
#include <span>
#include <string>
#include <vector>

#include "core/image.h"
#include "core/status.h"
#include "gpu/context.h"
#include "gpu/pipeline.h"
#include "gpu/resources.h"
#include "gpu/timer.h"
#include "render/camera.h"
#include "scene/render_settings.h"
#include "volume/dense_volume.h"

namespace vxr {

// Premultiplied RGBA floats, row-major, top row first.
struct ImageRgbaF {
  uint32_t width = 0, height = 0;
  std::vector<float> rgba;
};

// Rounds to nearest (v * 255 + 0.5, clamped): the one float -> 8-bit rule.
ImageRgba8 to_rgba8(const ImageRgbaF& image);

enum class RenderPath { kCompute, kFragment };

class Raycaster {
 public:
  static Result<std::unique_ptr<Raycaster>> create(gpu::Context& ctx);

  // One channel. u8 / u16 go up as R8 / R16 UNORM textures (window in data
  // units, divided by 255 / 65535 on the way); every other dtype as R32 float.
  Status set_volume(const DenseVolume& volume);
  // 1..4 channels of the same dims and voxel size.
  Status set_channels(std::span<const DenseVolume> channels);
  // The depth image rays end at: view depth per pixel (world units along the
  // camera's forward axis, what a mesh pass writes), +inf where nothing is.
  // Its size must match the render size. clear_depth() removes it.
  Status set_depth(std::span<const float> view_depth, uint32_t width, uint32_t height);
  void clear_depth() { has_depth_ = false; }

  Result<ImageRgbaF> render_float(const Camera& camera, const RenderSettings& settings, uint32_t width,
                                  uint32_t height, RenderPath path = RenderPath::kCompute);
  // Premultiplied RGBA8, top row first.
  Result<ImageRgba8> render(const Camera& camera, const RenderSettings& settings, uint32_t width, uint32_t height,
                            RenderPath path = RenderPath::kCompute);

  uint32_t channel_count() const { return static_cast<uint32_t>(value_scales_.size()); }
  const VolumePlacement& placement() const { return placement_; }
  // GPU time of the last render in milliseconds (0 without timestamps).
  double last_gpu_ms() const { return last_gpu_ms_; }

 private:
  explicit Raycaster(gpu::Context& ctx) : ctx_(ctx) {}
  Status ensure_target(uint32_t width, uint32_t height);

  gpu::Context& ctx_;
  // Pipelines per (path, model, channels, gradient, depth colour): the core's
  // specialization constants. Built on first use.
  Result<const gpu::ComputePipeline*> pipeline_for(RenderPath path, const struct RaycastSetup& setup);
  std::map<uint32_t, gpu::ComputePipeline> pipelines_;
  gpu::Handle<VkDescriptorSetLayout> set_layout_;
  gpu::Handle<VkDescriptorPool> pool_;
  VkDescriptorSet set_ = VK_NULL_HANDLE;
  gpu::Handle<VkSampler> linear_;
  gpu::Handle<VkSampler> nearest_;
  std::vector<gpu::Image> volume_tex_;
  gpu::Image transfer_tex_;
  std::vector<glm::vec4> uploaded_table_;  // what transfer_tex_ holds
  gpu::Image depth_tex_;
  gpu::Image empty_depth_;
  gpu::Image target_;
  gpu::Buffer params_;
  gpu::GpuTimer timer_;
  VolumePlacement placement_;
  std::vector<double> value_scales_;  // data units per texel unit, per channel
  bool has_depth_ = false;
  double last_gpu_ms_ = 0.0;
};

// Premultiplied RGBA over an opaque black background (what PNG viewers show).
ImageRgba8 over_black(const ImageRgba8& premultiplied);

}  // namespace vxr
