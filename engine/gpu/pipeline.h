// Compute and graphics pipelines and their descriptor sets.
#pragma once

#include <vulkan/vulkan.h>

#include <string_view>
#include <vector>

#include "core/status.h"
#include "gpu/context.h"
#include "gpu/handle.h"

namespace vxr::gpu {

struct SpecializationConstant {
  uint32_t id;
  uint32_t value;  // ints, bools and floats (bit-cast) all fit
};

struct ComputePipelineCreateInfo {
  std::string_view shader;  // embedded name, e.g. "brick_raycast.comp"
  std::vector<VkDescriptorSetLayoutBinding> bindings;  // set 0
  uint32_t push_constant_bytes = 0;
  std::vector<SpecializationConstant> specialization;
};

struct ComputePipeline {
  Handle<VkDescriptorSetLayout> set_layout;
  Handle<VkPipelineLayout> layout;
  Handle<VkPipeline> pipeline;
};

Result<ComputePipeline> create_compute_pipeline(const Context& ctx, const ComputePipelineCreateInfo& info);

// A graphics pipeline for dynamic rendering with no vertex buffers (the vertex
// shader builds its geometry from gl_VertexIndex / gl_InstanceIndex and
// storage buffers), any number of colour attachments (no blending), an
// optional depth attachment with a LESS test and writes. Viewport and scissor
// are dynamic.
struct GraphicsPipelineCreateInfo {
  std::string_view vertex_shader;
  std::string_view fragment_shader;
  std::vector<VkDescriptorSetLayoutBinding> bindings;  // set 0
  std::vector<VkFormat> color_formats{VK_FORMAT_R8G8B8A8_UNORM};
  VkFormat depth_format = VK_FORMAT_UNDEFINED;  // none
  VkCullModeFlags cull_mode = VK_CULL_MODE_NONE;
  std::vector<SpecializationConstant> specialization;  // fragment stage
};
Result<ComputePipeline> create_graphics_pipeline(const Context& ctx, const GraphicsPipelineCreateInfo& info);

// A descriptor pool sized for `max_sets` sets of the given bindings each.
Result<Handle<VkDescriptorPool>> create_descriptor_pool(const Context& ctx,
                                                        const std::vector<VkDescriptorSetLayoutBinding>& bindings,
                                                        uint32_t max_sets);
// Sets are freed with their pool.
Result<VkDescriptorSet> allocate_descriptor_set(const Context& ctx, VkDescriptorPool pool,
                                                VkDescriptorSetLayout layout);

// Small writers for the descriptor kinds vxr uses.
void write_combined_image(const Context& ctx, VkDescriptorSet set, uint32_t binding, VkImageView view,
                          VkSampler sampler, VkImageLayout layout = VK_IMAGE_LAYOUT_SHADER_READ_ONLY_OPTIMAL);
void write_storage_image(const Context& ctx, VkDescriptorSet set, uint32_t binding, VkImageView view);
void write_storage_buffer(const Context& ctx, VkDescriptorSet set, uint32_t binding, VkBuffer buffer,
                          VkDeviceSize size = VK_WHOLE_SIZE, VkDeviceSize offset = 0);
void write_uniform_buffer(const Context& ctx, VkDescriptorSet set, uint32_t binding, VkBuffer buffer,
                          VkDeviceSize size = VK_WHOLE_SIZE, VkDeviceSize offset = 0);
void write_storage_texel_buffer(const Context& ctx, VkDescriptorSet set, uint32_t binding, VkBufferView view);

}  // namespace vxr::gpu
