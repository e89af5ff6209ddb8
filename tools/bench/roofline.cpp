#include "roofline.h"

#include <chrono>
#include <cstring>
#include <vector>

#include "bench.h"
#include "gpu/pipeline.h"
#include "gpu/resources.h"

namespace vxr::bench {
namespace {

constexpr VkDeviceSize kCopyBytes = VkDeviceSize(64) << 20;  // under lavapipe's 128 MiB storage-buffer range
constexpr int kCopyDispatches = 8;
constexpr uint32_t kVolume = 256, kGrid = 512, kSteps = 256;

void compute_barrier(VkCommandBuffer cmd) {
  gpu::memory_barrier(cmd, VK_PIPELINE_STAGE_2_COMPUTE_SHADER_BIT, VK_ACCESS_2_SHADER_STORAGE_WRITE_BIT,
                      VK_PIPELINE_STAGE_2_COMPUTE_SHADER_BIT,
                      VK_ACCESS_2_SHADER_STORAGE_WRITE_BIT | VK_ACCESS_2_SHADER_STORAGE_READ_BIT);
}

Result<double> time_copy(gpu::Context& ctx, int repeats) {
  const std::vector<VkDescriptorSetLayoutBinding> bindings = {
      {0, VK_DESCRIPTOR_TYPE_STORAGE_BUFFER, 1, VK_SHADER_STAGE_COMPUTE_BIT, nullptr},
      {1, VK_DESCRIPTOR_TYPE_STORAGE_BUFFER, 1, VK_SHADER_STAGE_COMPUTE_BIT, nullptr}};
  VXR_ASSIGN_OR_RETURN(auto pipeline, gpu::create_compute_pipeline(ctx, {"bench_copy.comp", bindings, 4, {}}));
  VXR_ASSIGN_OR_RETURN(auto pool, gpu::create_descriptor_pool(ctx, bindings, 1));
  VXR_ASSIGN_OR_RETURN(VkDescriptorSet set, gpu::allocate_descriptor_set(ctx, pool, pipeline.set_layout));
  VXR_ASSIGN_OR_RETURN(auto src, gpu::create_buffer(ctx, {kCopyBytes, VK_BUFFER_USAGE_STORAGE_BUFFER_BIT |
                                                                          VK_BUFFER_USAGE_TRANSFER_DST_BIT,
                                                         gpu::MemoryIntent::kDeviceLocal, "copy src"}));
  VXR_ASSIGN_OR_RETURN(auto dst, gpu::create_buffer(ctx, {kCopyBytes, VK_BUFFER_USAGE_STORAGE_BUFFER_BIT,
                                                         gpu::MemoryIntent::kDeviceLocal, "copy dst"}));
  gpu::write_storage_buffer(ctx, set, 0, src.buffer);
  gpu::write_storage_buffer(ctx, set, 1, dst.buffer);
  const uint32_t count = static_cast<uint32_t>(kCopyBytes / 16);
  // Defined contents: a fill keeps validation and the driver honest.
  VXR_RETURN_IF_ERROR(ctx.submit_and_wait([&](VkCommandBuffer cmd) {
    vkCmdFillBuffer(cmd, src.buffer, 0, VK_WHOLE_SIZE, 0x3f800000u);
    gpu::memory_barrier(cmd, VK_PIPELINE_STAGE_2_CLEAR_BIT, VK_ACCESS_2_TRANSFER_WRITE_BIT,
                        VK_PIPELINE_STAGE_2_COMPUTE_SHADER_BIT, VK_ACCESS_2_SHADER_STORAGE_READ_BIT);
  }));
  Status err;
  const double ms = median_ms(repeats, [&] {
    return ctx.submit_and_wait([&](VkCommandBuffer cmd) {
      vkCmdBindPipeline(cmd, VK_PIPELINE_BIND_POINT_COMPUTE, pipeline.pipeline);
      vkCmdBindDescriptorSets(cmd, VK_PIPELINE_BIND_POINT_COMPUTE, pipeline.layout, 0, 1, &set, 0, nullptr);
      vkCmdPushConstants(cmd, pipeline.layout, VK_SHADER_STAGE_COMPUTE_BIT, 0, 4, &count);
      for (int i = 0; i < kCopyDispatches; ++i) {
        if (i) compute_barrier(cmd);
        vkCmdDispatch(cmd, (count + 256 * 16 - 1) / (256 * 16), 1, 1);
      }
    });
  }, &err);
  if (!err.is_ok()) return err;
  return ms;
}

// vkCmdCopyBuffer: the driver's own copy path (memcpy on CPU drivers, copy
// engines on GPUs), for comparison with the shader's load/store stream.
Result<double> time_transfer(gpu::Context& ctx, int repeats) {
  VXR_ASSIGN_OR_RETURN(auto src, gpu::create_buffer(ctx, {kCopyBytes, VK_BUFFER_USAGE_TRANSFER_SRC_BIT |
                                                                          VK_BUFFER_USAGE_TRANSFER_DST_BIT,
                                                         gpu::MemoryIntent::kDeviceLocal, "transfer src"}));
  VXR_ASSIGN_OR_RETURN(auto dst, gpu::create_buffer(ctx, {kCopyBytes, VK_BUFFER_USAGE_TRANSFER_DST_BIT,
                                                         gpu::MemoryIntent::kDeviceLocal, "transfer dst"}));
  Status err;
  const double ms = median_ms(repeats, [&] {
    return ctx.submit_and_wait([&](VkCommandBuffer cmd) {
      vkCmdFillBuffer(cmd, src.buffer, 0, VK_WHOLE_SIZE, 0x3f800000u);
      for (int i = 0; i < kCopyDispatches; ++i) {
        gpu::memory_barrier(cmd, VK_PIPELINE_STAGE_2_ALL_TRANSFER_BIT, VK_ACCESS_2_TRANSFER_WRITE_BIT,
                            VK_PIPELINE_STAGE_2_ALL_TRANSFER_BIT,
                            VK_ACCESS_2_TRANSFER_READ_BIT | VK_ACCESS_2_TRANSFER_WRITE_BIT);
        VkBufferCopy region{0, 0, kCopyBytes};
        vkCmdCopyBuffer(cmd, src.buffer, dst.buffer, 1, &region);
      }
    });
  }, &err);
  if (!err.is_ok()) return err;
  return ms;
}

}  // namespace

struct SamplingCeiling::Resources {
  gpu::ComputePipeline pipeline;
  gpu::Handle<VkDescriptorPool> pool;
  VkDescriptorSet set = VK_NULL_HANDLE;
  gpu::Handle<VkSampler> sampler;
  gpu::Image tex;
  gpu::Buffer out;
};

SamplingCeiling::SamplingCeiling(gpu::Context& ctx) : ctx_(ctx), res_(std::make_unique<Resources>()) {}
SamplingCeiling::~SamplingCeiling() = default;

double SamplingCeiling::samples() { return double(kGrid) * kGrid * kSteps; }

Result<std::unique_ptr<SamplingCeiling>> SamplingCeiling::create(gpu::Context& ctx) {
  std::unique_ptr<SamplingCeiling> c(new SamplingCeiling(ctx));
  Resources& r = *c->res_;
  const std::vector<VkDescriptorSetLayoutBinding> bindings = {
      {0, VK_DESCRIPTOR_TYPE_COMBINED_IMAGE_SAMPLER, 1, VK_SHADER_STAGE_COMPUTE_BIT, nullptr},
      {1, VK_DESCRIPTOR_TYPE_STORAGE_BUFFER, 1, VK_SHADER_STAGE_COMPUTE_BIT, nullptr}};
  VXR_ASSIGN_OR_RETURN(r.pipeline, gpu::create_compute_pipeline(ctx, {"bench_sample.comp", bindings, 16, {}}));
  VXR_ASSIGN_OR_RETURN(r.pool, gpu::create_descriptor_pool(ctx, bindings, 1));
  VXR_ASSIGN_OR_RETURN(r.set, gpu::allocate_descriptor_set(ctx, r.pool, r.pipeline.set_layout));
  VXR_ASSIGN_OR_RETURN(r.sampler, gpu::create_linear_clamp_sampler(ctx));
  VXR_ASSIGN_OR_RETURN(r.tex, gpu::create_image(ctx, {VK_IMAGE_TYPE_3D, VK_FORMAT_R8_UNORM,
                                                      {kVolume, kVolume, kVolume},
                                                      VK_IMAGE_USAGE_SAMPLED_BIT | VK_IMAGE_USAGE_TRANSFER_DST_BIT,
                                                      "roofline volume"}));
  std::vector<uint8_t> voxels(size_t(kVolume) * kVolume * kVolume);
  uint32_t h = 2166136261u;
  for (auto& v : voxels) v = static_cast<uint8_t>((h = (h ^ 0x5bd1e995u) * 16777619u) >> 24);
  VXR_RETURN_IF_ERROR(gpu::upload_image(ctx, r.tex, voxels.data(), voxels.size()));
  VXR_ASSIGN_OR_RETURN(r.out, gpu::create_buffer(ctx, {VkDeviceSize(kGrid) * kGrid * 4,
                                                      VK_BUFFER_USAGE_STORAGE_BUFFER_BIT,
                                                      gpu::MemoryIntent::kDeviceLocal, "roofline out"}));
  gpu::write_combined_image(ctx, r.set, 0, r.tex.view, r.sampler);
  gpu::write_storage_buffer(ctx, r.set, 1, r.out.buffer);
  return c;
}

Result<double> SamplingCeiling::time_ms() {
  const uint32_t push[4] = {kGrid, kGrid, kSteps, 0};
  const auto t0 = std::chrono::steady_clock::now();
  VXR_RETURN_IF_ERROR(ctx_.submit_and_wait([&](VkCommandBuffer cmd) {
    vkCmdBindPipeline(cmd, VK_PIPELINE_BIND_POINT_COMPUTE, res_->pipeline.pipeline);
    vkCmdBindDescriptorSets(cmd, VK_PIPELINE_BIND_POINT_COMPUTE, res_->pipeline.layout, 0, 1, &res_->set, 0, nullptr);
    vkCmdPushConstants(cmd, res_->pipeline.layout, VK_SHADER_STAGE_COMPUTE_BIT, 0, sizeof(push), push);
    vkCmdDispatch(cmd, kGrid / 8, kGrid / 8, 1);
  }));
  return ms_since(t0);
}

namespace {

Result<double> time_sampling(SamplingCeiling& ceiling, int repeats) {
  VXR_RETURN_IF_ERROR(ceiling.time_ms().status());  // warm-up, as median_ms
  std::vector<double> ms;
  for (int i = 0; i < repeats; ++i) {
    VXR_ASSIGN_OR_RETURN(double t, ceiling.time_ms());
    ms.push_back(t);
  }
  return median(ms);
}

}  // namespace

Result<Roofline> measure_roofline(gpu::Context& ctx, SamplingCeiling& ceiling, int repeats) {
  Roofline r;
  VXR_ASSIGN_OR_RETURN(r.copy_ms, time_copy(ctx, repeats));
  VXR_ASSIGN_OR_RETURN(r.sample_ms, time_sampling(ceiling, repeats));
  VXR_ASSIGN_OR_RETURN(r.transfer_ms, time_transfer(ctx, repeats));
  // The transfer run also includes one fill of the source: kCopyBytes written.
  r.transfer_gb_per_s = (2.0 * kCopyBytes * kCopyDispatches + kCopyBytes) / (r.transfer_ms * 1e-3) / 1e9;
  r.copy_gb_per_s = 2.0 * kCopyBytes * kCopyDispatches / (r.copy_ms * 1e-3) / 1e9;
  r.trilinear_samples_per_s = SamplingCeiling::samples() / (r.sample_ms * 1e-3);
  return r;
}

}  // namespace vxr::bench
