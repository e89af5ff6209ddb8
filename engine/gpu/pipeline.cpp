#include "gpu/pipeline.h"

#include <map>

#include "gpu/shaders.h"
#include "gpu/vk_check.h"

namespace vxr::gpu {

namespace {

// Set layout (set 0) and pipeline layout with an optional compute push-constant range.
Status create_layouts(const Context& ctx, const std::vector<VkDescriptorSetLayoutBinding>& bindings,
                      uint32_t push_constant_bytes, ComputePipeline& p) {
  VkDevice dev = ctx.device();
  VkDescriptorSetLayoutCreateInfo dl{VK_STRUCTURE_TYPE_DESCRIPTOR_SET_LAYOUT_CREATE_INFO};
  dl.bindingCount = static_cast<uint32_t>(bindings.size());
  dl.pBindings = bindings.data();
  VkDescriptorSetLayout set_layout = VK_NULL_HANDLE;
  VXR_VK_TRY(vkCreateDescriptorSetLayout(dev, &dl, nullptr, &set_layout));
  p.set_layout = Handle<VkDescriptorSetLayout>(dev, set_layout);

  VkPushConstantRange range{VK_SHADER_STAGE_COMPUTE_BIT, 0, push_constant_bytes};
  VkPipelineLayoutCreateInfo pl{VK_STRUCTURE_TYPE_PIPELINE_LAYOUT_CREATE_INFO};
  pl.setLayoutCount = 1;
  pl.pSetLayouts = &set_layout;
  pl.pushConstantRangeCount = push_constant_bytes ? 1 : 0;
  pl.pPushConstantRanges = &range;
  VkPipelineLayout layout = VK_NULL_HANDLE;
  VXR_VK_TRY(vkCreatePipelineLayout(dev, &pl, nullptr, &layout));
  p.layout = Handle<VkPipelineLayout>(dev, layout);
  return Status::ok();
}

// 32-bit specialization constants packed back to back; info() is null when there are none.
struct Specialization {
  std::vector<VkSpecializationMapEntry> entries;
  std::vector<uint32_t> values;
  VkSpecializationInfo vk{};
  explicit Specialization(const std::vector<SpecializationConstant>& constants) {
    for (const auto& sc : constants) {
      entries.push_back({sc.id, static_cast<uint32_t>(values.size() * 4), 4});
      values.push_back(sc.value);
    }
    vk = {static_cast<uint32_t>(entries.size()), entries.data(), values.size() * 4, values.data()};
  }
  const VkSpecializationInfo* info() const { return entries.empty() ? nullptr : &vk; }
};

}  // namespace

Result<ComputePipeline> create_compute_pipeline(const Context& ctx, const ComputePipelineCreateInfo& info) {
  VkDevice dev = ctx.device();
  if (info.push_constant_bytes > ctx.limits().maxPushConstantsSize)
    return out_of_range(std::string(info.shader) + ": push constants of " + std::to_string(info.push_constant_bytes) +
                        " bytes exceed the device limit " + std::to_string(ctx.limits().maxPushConstantsSize));
  ComputePipeline p;
  VXR_RETURN_IF_ERROR(create_layouts(ctx, info.bindings, info.push_constant_bytes, p));
  VXR_ASSIGN_OR_RETURN(Handle<VkShaderModule> module, create_shader_module(ctx, info.shader));
  const Specialization spec(info.specialization);

  VkComputePipelineCreateInfo ci{VK_STRUCTURE_TYPE_COMPUTE_PIPELINE_CREATE_INFO};
  ci.stage = {VK_STRUCTURE_TYPE_PIPELINE_SHADER_STAGE_CREATE_INFO};
  ci.stage.stage = VK_SHADER_STAGE_COMPUTE_BIT;
  ci.stage.module = module;
  ci.stage.pName = "main";
  ci.stage.pSpecializationInfo = spec.info();
  ci.layout = p.layout;
  VkPipeline pipeline = VK_NULL_HANDLE;
  VXR_VK_TRY(vkCreateComputePipelines(dev, ctx.pipeline_cache(), 1, &ci, nullptr, &pipeline));
  ctx.count_pipeline_built();
  p.pipeline = Handle<VkPipeline>(dev, pipeline);
  return p;
}

Result<ComputePipeline> create_graphics_pipeline(const Context& ctx, const GraphicsPipelineCreateInfo& info) {
  VkDevice dev = ctx.device();
  ComputePipeline p;
  VXR_RETURN_IF_ERROR(create_layouts(ctx, info.bindings, 0, p));

  VXR_ASSIGN_OR_RETURN(Handle<VkShaderModule> vs, create_shader_module(ctx, info.vertex_shader));
  VXR_ASSIGN_OR_RETURN(Handle<VkShaderModule> fs, create_shader_module(ctx, info.fragment_shader));
  VkPipelineShaderStageCreateInfo stages[2] = {};
  stages[0] = {VK_STRUCTURE_TYPE_PIPELINE_SHADER_STAGE_CREATE_INFO};
  stages[0].stage = VK_SHADER_STAGE_VERTEX_BIT;
  stages[0].module = vs;
  stages[0].pName = "main";
  stages[1] = {VK_STRUCTURE_TYPE_PIPELINE_SHADER_STAGE_CREATE_INFO};
  stages[1].stage = VK_SHADER_STAGE_FRAGMENT_BIT;
  stages[1].module = fs;
  stages[1].pName = "main";
  const Specialization spec(info.specialization);
  stages[1].pSpecializationInfo = spec.info();

  VkPipelineVertexInputStateCreateInfo vi{VK_STRUCTURE_TYPE_PIPELINE_VERTEX_INPUT_STATE_CREATE_INFO};
  VkPipelineInputAssemblyStateCreateInfo ia{VK_STRUCTURE_TYPE_PIPELINE_INPUT_ASSEMBLY_STATE_CREATE_INFO};
  ia.topology = VK_PRIMITIVE_TOPOLOGY_TRIANGLE_LIST;
  VkPipelineViewportStateCreateInfo vp{VK_STRUCTURE_TYPE_PIPELINE_VIEWPORT_STATE_CREATE_INFO};
  vp.viewportCount = 1;
  vp.scissorCount = 1;
  VkPipelineRasterizationStateCreateInfo rs{VK_STRUCTURE_TYPE_PIPELINE_RASTERIZATION_STATE_CREATE_INFO};
  rs.polygonMode = VK_POLYGON_MODE_FILL;
  rs.cullMode = info.cull_mode;
  rs.frontFace = VK_FRONT_FACE_COUNTER_CLOCKWISE;
  rs.lineWidth = 1.0f;
  VkPipelineMultisampleStateCreateInfo ms{VK_STRUCTURE_TYPE_PIPELINE_MULTISAMPLE_STATE_CREATE_INFO};
  ms.rasterizationSamples = VK_SAMPLE_COUNT_1_BIT;
  VkPipelineDepthStencilStateCreateInfo dss{VK_STRUCTURE_TYPE_PIPELINE_DEPTH_STENCIL_STATE_CREATE_INFO};
  dss.depthTestEnable = info.depth_format != VK_FORMAT_UNDEFINED;
  dss.depthWriteEnable = dss.depthTestEnable;
  dss.depthCompareOp = VK_COMPARE_OP_LESS;
  std::vector<VkPipelineColorBlendAttachmentState> atts(info.color_formats.size());
  for (auto& att : atts)
    att.colorWriteMask = VK_COLOR_COMPONENT_R_BIT | VK_COLOR_COMPONENT_G_BIT | VK_COLOR_COMPONENT_B_BIT |
                         VK_COLOR_COMPONENT_A_BIT;
  VkPipelineColorBlendStateCreateInfo cb{VK_STRUCTURE_TYPE_PIPELINE_COLOR_BLEND_STATE_CREATE_INFO};
  cb.attachmentCount = static_cast<uint32_t>(atts.size());
  cb.pAttachments = atts.data();
  const VkDynamicState dyn[] = {VK_DYNAMIC_STATE_VIEWPORT, VK_DYNAMIC_STATE_SCISSOR};
  VkPipelineDynamicStateCreateInfo ds{VK_STRUCTURE_TYPE_PIPELINE_DYNAMIC_STATE_CREATE_INFO};
  ds.dynamicStateCount = 2;
  ds.pDynamicStates = dyn;
  VkPipelineRenderingCreateInfo rendering{VK_STRUCTURE_TYPE_PIPELINE_RENDERING_CREATE_INFO};
  rendering.colorAttachmentCount = static_cast<uint32_t>(info.color_formats.size());
  rendering.pColorAttachmentFormats = info.color_formats.data();
  rendering.depthAttachmentFormat = info.depth_format;

  VkGraphicsPipelineCreateInfo ci{VK_STRUCTURE_TYPE_GRAPHICS_PIPELINE_CREATE_INFO};
  ci.pNext = &rendering;
  ci.stageCount = 2;
  ci.pStages = stages;
  ci.pVertexInputState = &vi;
  ci.pInputAssemblyState = &ia;
  ci.pViewportState = &vp;
  ci.pRasterizationState = &rs;
  ci.pMultisampleState = &ms;
  ci.pDepthStencilState = info.depth_format != VK_FORMAT_UNDEFINED ? &dss : nullptr;
  ci.pColorBlendState = &cb;
  ci.pDynamicState = &ds;
  ci.layout = p.layout;
  VkPipeline pipeline = VK_NULL_HANDLE;
  VXR_VK_TRY(vkCreateGraphicsPipelines(dev, ctx.pipeline_cache(), 1, &ci, nullptr, &pipeline));
  ctx.count_pipeline_built();
  p.pipeline = Handle<VkPipeline>(dev, pipeline);
  return p;
}

Result<Handle<VkDescriptorPool>> create_descriptor_pool(const Context& ctx,
                                                        const std::vector<VkDescriptorSetLayoutBinding>& bindings,
                                                        uint32_t max_sets) {
  std::map<VkDescriptorType, uint32_t> counts;
  for (const auto& b : bindings) counts[b.descriptorType] += b.descriptorCount * max_sets;
  std::vector<VkDescriptorPoolSize> sizes;
  for (auto [type, n] : counts) sizes.push_back({type, n});
  VkDescriptorPoolCreateInfo ci{VK_STRUCTURE_TYPE_DESCRIPTOR_POOL_CREATE_INFO};
  ci.maxSets = max_sets;
  ci.poolSizeCount = static_cast<uint32_t>(sizes.size());
  ci.pPoolSizes = sizes.data();
  VkDescriptorPool pool = VK_NULL_HANDLE;
  VXR_VK_TRY(vkCreateDescriptorPool(ctx.device(), &ci, nullptr, &pool));
  return Handle<VkDescriptorPool>(ctx.device(), pool);
}

Result<VkDescriptorSet> allocate_descriptor_set(const Context& ctx, VkDescriptorPool pool,
                                                VkDescriptorSetLayout layout) {
  VkDescriptorSetAllocateInfo ai{VK_STRUCTURE_TYPE_DESCRIPTOR_SET_ALLOCATE_INFO};
  ai.descriptorPool = pool;
  ai.descriptorSetCount = 1;
  ai.pSetLayouts = &layout;
  VkDescriptorSet set = VK_NULL_HANDLE;
  VXR_VK_TRY(vkAllocateDescriptorSets(ctx.device(), &ai, &set));
  return set;
}

// One descriptor of `type`: exactly one of image, buffer and texels is set.
static void write_descriptor(const Context& ctx, VkDescriptorSet set, uint32_t binding, VkDescriptorType type,
                             const VkDescriptorImageInfo* image, const VkDescriptorBufferInfo* buffer,
                             const VkBufferView* texels) {
  VkWriteDescriptorSet w{VK_STRUCTURE_TYPE_WRITE_DESCRIPTOR_SET};
  w.dstSet = set;
  w.dstBinding = binding;
  w.descriptorCount = 1;
  w.descriptorType = type;
  w.pImageInfo = image;
  w.pBufferInfo = buffer;
  w.pTexelBufferView = texels;
  vkUpdateDescriptorSets(ctx.device(), 1, &w, 0, nullptr);
}

static void write_image(const Context& ctx, VkDescriptorSet set, uint32_t binding, VkDescriptorType type,
                        VkImageView view, VkSampler sampler, VkImageLayout layout) {
  const VkDescriptorImageInfo ii{sampler, view, layout};
  write_descriptor(ctx, set, binding, type, &ii, nullptr, nullptr);
}

static void write_buffer(const Context& ctx, VkDescriptorSet set, uint32_t binding, VkDescriptorType type,
                         VkBuffer buffer, VkDeviceSize size, VkDeviceSize offset) {
  const VkDescriptorBufferInfo bi{buffer, offset, size};
  write_descriptor(ctx, set, binding, type, nullptr, &bi, nullptr);
}

void write_combined_image(const Context& ctx, VkDescriptorSet set, uint32_t binding, VkImageView view,
                          VkSampler sampler, VkImageLayout layout) {
  write_image(ctx, set, binding, VK_DESCRIPTOR_TYPE_COMBINED_IMAGE_SAMPLER, view, sampler, layout);
}
void write_storage_image(const Context& ctx, VkDescriptorSet set, uint32_t binding, VkImageView view) {
  write_image(ctx, set, binding, VK_DESCRIPTOR_TYPE_STORAGE_IMAGE, view, VK_NULL_HANDLE, VK_IMAGE_LAYOUT_GENERAL);
}
void write_storage_buffer(const Context& ctx, VkDescriptorSet set, uint32_t binding, VkBuffer buffer,
                          VkDeviceSize size, VkDeviceSize offset) {
  write_buffer(ctx, set, binding, VK_DESCRIPTOR_TYPE_STORAGE_BUFFER, buffer, size, offset);
}
void write_uniform_buffer(const Context& ctx, VkDescriptorSet set, uint32_t binding, VkBuffer buffer,
                          VkDeviceSize size, VkDeviceSize offset) {
  write_buffer(ctx, set, binding, VK_DESCRIPTOR_TYPE_UNIFORM_BUFFER, buffer, size, offset);
}
void write_storage_texel_buffer(const Context& ctx, VkDescriptorSet set, uint32_t binding, VkBufferView view) {
  write_descriptor(ctx, set, binding, VK_DESCRIPTOR_TYPE_STORAGE_TEXEL_BUFFER, nullptr, nullptr, &view);
}

}  // namespace vxr::gpu
