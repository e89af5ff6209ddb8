#include "render/raycaster.h"

#include <chrono>
#include <cmath>
#include <cstring>
#include <limits>

#include "core/trace.h"
#include "render/raycast_setup.h"
#include "render/transfer_function.h"
#include "shared/raycast_params.h"

namespace vxr {
namespace {

constexpr VkShaderStageFlags kStages = VK_SHADER_STAGE_COMPUTE_BIT | VK_SHADER_STAGE_FRAGMENT_BIT;

// One layout for both paths, so one descriptor set serves the compute and the
// fragment pipeline (identically defined layouts are compatible).
std::vector<VkDescriptorSetLayoutBinding> raycast_bindings() {
  return {
      {0, VK_DESCRIPTOR_TYPE_COMBINED_IMAGE_SAMPLER, VXR_MAX_CHANNELS, kStages, nullptr},  // volume, per channel
      {1, VK_DESCRIPTOR_TYPE_COMBINED_IMAGE_SAMPLER, 1, kStages, nullptr},                 // transfer table
      {2, VK_DESCRIPTOR_TYPE_STORAGE_IMAGE, 1, kStages, nullptr},                          // compute output
      {3, VK_DESCRIPTOR_TYPE_COMBINED_IMAGE_SAMPLER, 1, kStages, nullptr},                 // depth image
      {4, VK_DESCRIPTOR_TYPE_UNIFORM_BUFFER, 1, kStages, nullptr},                         // RaycastParams
  };
}

void write_volume_array(const gpu::Context& ctx, VkDescriptorSet set, const std::vector<gpu::Image>& tex,
                        VkSampler sampler) {
  VkDescriptorImageInfo infos[VXR_MAX_CHANNELS];
  for (int c = 0; c < VXR_MAX_CHANNELS; ++c)
    infos[c] = {sampler, tex[std::min<size_t>(c, tex.size() - 1)].view, VK_IMAGE_LAYOUT_SHADER_READ_ONLY_OPTIMAL};
  VkWriteDescriptorSet w{VK_STRUCTURE_TYPE_WRITE_DESCRIPTOR_SET};
  w.dstSet = set;
  w.dstBinding = 0;
  w.descriptorCount = VXR_MAX_CHANNELS;
  w.descriptorType = VK_DESCRIPTOR_TYPE_COMBINED_IMAGE_SAMPLER;
  w.pImageInfo = infos;
  vkUpdateDescriptorSets(ctx.device(), 1, &w, 0, nullptr);
}

bool linear_filterable(const gpu::Context& ctx, VkFormat format) {
  VkFormatProperties props;
  vkGetPhysicalDeviceFormatProperties(ctx.physical_device(), format, &props);
  return props.optimalTilingFeatures & VK_FORMAT_FEATURE_SAMPLED_IMAGE_FILTER_LINEAR_BIT;
}

}  // namespace

ImageRgba8 to_rgba8(const ImageRgbaF& f) {
  ImageRgba8 img(f.width, f.height);
  for (size_t i = 0; i < f.rgba.size(); ++i) {
    const float v = f.rgba[i];
    const float c = v > 0.0f ? (v < 1.0f ? v : 1.0f) : 0.0f;  // NaN -> 0
    img.pixels[i] = static_cast<uint8_t>(c * 255.0f + 0.5f);
  }
  return img;
}

Result<std::unique_ptr<Raycaster>> Raycaster::create(gpu::Context& ctx) {
  std::unique_ptr<Raycaster> r(new Raycaster(ctx));
  const auto bindings = raycast_bindings();
  VkDescriptorSetLayoutCreateInfo dl{VK_STRUCTURE_TYPE_DESCRIPTOR_SET_LAYOUT_CREATE_INFO};
  dl.bindingCount = static_cast<uint32_t>(bindings.size());
  dl.pBindings = bindings.data();
  VkDescriptorSetLayout layout = VK_NULL_HANDLE;
  if (vkCreateDescriptorSetLayout(ctx.device(), &dl, nullptr, &layout) != VK_SUCCESS)
    return gpu_error("ray caster: vkCreateDescriptorSetLayout failed");
  r->set_layout_ = gpu::Handle<VkDescriptorSetLayout>(ctx.device(), layout);
  VXR_ASSIGN_OR_RETURN(r->pool_, gpu::create_descriptor_pool(ctx, bindings, 1));
  VXR_ASSIGN_OR_RETURN(r->set_, gpu::allocate_descriptor_set(ctx, r->pool_, r->set_layout_));
  VXR_ASSIGN_OR_RETURN(r->linear_, gpu::create_linear_clamp_sampler(ctx));
  VXR_ASSIGN_OR_RETURN(r->nearest_, gpu::create_nearest_clamp_sampler(ctx));
  VXR_ASSIGN_OR_RETURN(r->timer_, gpu::GpuTimer::create(ctx));
  VXR_ASSIGN_OR_RETURN(r->transfer_tex_,
                       gpu::create_image(ctx, {VK_IMAGE_TYPE_2D, VK_FORMAT_R32G32B32A32_SFLOAT,
                                               {VXR_TF_SIZE, VXR_MAX_CHANNELS, 1},
                                               VK_IMAGE_USAGE_SAMPLED_BIT | VK_IMAGE_USAGE_TRANSFER_DST_BIT,
                                               "transfer function"}));
  VXR_ASSIGN_OR_RETURN(r->empty_depth_,
                       gpu::create_image(ctx, {VK_IMAGE_TYPE_2D, VK_FORMAT_R32_SFLOAT, {1, 1, 1},
                                               VK_IMAGE_USAGE_SAMPLED_BIT | VK_IMAGE_USAGE_TRANSFER_DST_BIT,
                                               "no depth"}));
  const float inf = std::numeric_limits<float>::infinity();
  VXR_RETURN_IF_ERROR(gpu::upload_image(ctx, r->empty_depth_, &inf, sizeof(inf)));
  VXR_ASSIGN_OR_RETURN(r->params_, gpu::create_buffer(ctx, {sizeof(shader::RaycastParams),
                                                            VK_BUFFER_USAGE_UNIFORM_BUFFER_BIT,
                                                            gpu::MemoryIntent::kUpload, "raycast params"}));
  gpu::write_uniform_buffer(ctx, r->set_, 4, r->params_.buffer);
  gpu::write_combined_image(ctx, r->set_, 1, r->transfer_tex_.view, r->nearest_);
  gpu::write_combined_image(ctx, r->set_, 3, r->empty_depth_.view, r->nearest_);
  return r;
}

Result<const gpu::ComputePipeline*> Raycaster::pipeline_for(RenderPath path, const RaycastSetup& r) {
  const uint32_t model = pack_params(r, false).control.x;
  const bool depth = r.depth_mode != DepthColorMode::kOff;
  bool gamma = false;
  for (uint32_t c = 0; c < r.channels && c < VXR_MAX_CHANNELS; ++c) gamma = gamma || r.window[c].z != 1.0;
  const bool naive = !r.opacity_correction;
  const uint32_t key = (path == RenderPath::kFragment ? 1u : 0u) | (model << 1) | (r.channels << 4) |
                       (r.gradient ? 1u << 8 : 0u) | (depth ? 1u << 9 : 0u) | (gamma ? 1u << 10 : 0u) |
                       (naive ? 1u << 11 : 0u);
  if (auto it = pipelines_.find(key); it != pipelines_.end()) return &it->second;
  const std::vector<gpu::SpecializationConstant> spec = {{100, model},
                                                         {101, r.channels},
                                                         {102, r.gradient ? 1u : 0u},
                                                         {103, depth ? 1u : 0u},
                                                         {104, gamma ? 1u : 0u},
                                                         {105, naive ? 1u : 0u}};
  gpu::ComputePipeline p;
  if (path == RenderPath::kCompute) {
    VXR_ASSIGN_OR_RETURN(p, gpu::create_compute_pipeline(ctx_, {"raycast.comp", raycast_bindings(), 0, spec}));
  } else {
    VXR_ASSIGN_OR_RETURN(p, gpu::create_fullscreen_pipeline(ctx_, {"fullscreen.vert", "raycast.frag", raycast_bindings(),
                                                                   VK_FORMAT_R32G32B32A32_SFLOAT, spec}));
  }
  return &pipelines_.emplace(key, std::move(p)).first->second;
}

Status Raycaster::set_volume(const DenseVolume& volume) { return set_channels(std::span(&volume, 1)); }

Status Raycaster::set_channels(std::span<const DenseVolume> channels) {
  VXR_TRACE_SCOPE("raycaster.set_channels");
  if (channels.empty() || channels.size() > VXR_MAX_CHANNELS)
    return invalid_argument("the ray caster takes 1 to " + std::to_string(VXR_MAX_CHANNELS) + " channels, not " +
                            std::to_string(channels.size()));
  std::vector<gpu::Image> textures;
  std::vector<double> scales;
  for (const DenseVolume& v : channels) {
    if (v.dims != channels[0].dims)
      return invalid_argument("all channels must have the same dims");
    VXR_RETURN_IF_ERROR(check_renderable(v));
    VkFormat format = VK_FORMAT_R32_SFLOAT;
    double scale = 1.0;
    std::vector<float> converted;
    const void* texels = v.data.data();
    size_t bytes = v.data.size();
    if (v.dtype == DType::kU8) {
      format = VK_FORMAT_R8_UNORM;
      scale = 255.0;
    } else if (v.dtype == DType::kU16) {
      format = VK_FORMAT_R16_UNORM;
      scale = 65535.0;
    } else {
      // Signed and 32-bit data: float texels in the data's own units.
      if (!linear_filterable(ctx_, VK_FORMAT_R32_SFLOAT))
        return unsupported(ctx_.info().name + " cannot filter R32_SFLOAT 3D textures; " + dtype_name(v.dtype) +
                           " volumes need it");
      converted.resize(v.voxel_count());
      for (uint32_t z = 0, i = 0; z < v.dims[2]; ++z)
        for (uint32_t y = 0; y < v.dims[1]; ++y)
          for (uint32_t x = 0; x < v.dims[0]; ++x) converted[i++] = static_cast<float>(renderable_value(v.value_at(x, y, z)));
      texels = converted.data();
      bytes = converted.size() * sizeof(float);
    }
    VXR_ASSIGN_OR_RETURN(gpu::Image tex,
                         gpu::create_image(ctx_, {VK_IMAGE_TYPE_3D, format, {v.dims[0], v.dims[1], v.dims[2]},
                                                  VK_IMAGE_USAGE_SAMPLED_BIT | VK_IMAGE_USAGE_TRANSFER_DST_BIT,
                                                  "volume"}));
    VXR_RETURN_IF_ERROR(gpu::upload_image(ctx_, tex, texels, bytes));
    textures.push_back(std::move(tex));
    scales.push_back(scale);
  }
  volume_tex_ = std::move(textures);
  value_scales_ = std::move(scales);
  placement_ = {channels[0].dims, channels[0].voxel_size,
                {channels[0].origin[0], channels[0].origin[1], channels[0].origin[2]}};
  write_volume_array(ctx_, set_, volume_tex_, linear_);
  return Status::ok();
}

Status Raycaster::set_depth(std::span<const float> depth, uint32_t width, uint32_t height) {
  if (depth.size() != size_t(width) * height) return invalid_argument("depth image: size does not match width*height");
  if (!depth_tex_.image || depth_tex_.extent.width != width || depth_tex_.extent.height != height) {
    VXR_ASSIGN_OR_RETURN(depth_tex_, gpu::create_image(ctx_, {VK_IMAGE_TYPE_2D, VK_FORMAT_R32_SFLOAT, {width, height, 1},
                                                              VK_IMAGE_USAGE_SAMPLED_BIT | VK_IMAGE_USAGE_TRANSFER_DST_BIT,
                                                              "depth"}));
  }
  VXR_RETURN_IF_ERROR(gpu::upload_image(ctx_, depth_tex_, depth.data(), depth.size_bytes()));
  has_depth_ = true;
  return Status::ok();
}

Status Raycaster::ensure_target(uint32_t width, uint32_t height) {
  if (target_.image && target_.extent.width == width && target_.extent.height == height) return Status::ok();
  VXR_ASSIGN_OR_RETURN(target_, gpu::create_image(ctx_, {VK_IMAGE_TYPE_2D, VK_FORMAT_R32G32B32A32_SFLOAT,
                                                         {width, height, 1},
                                                         VK_IMAGE_USAGE_STORAGE_BIT | VK_IMAGE_USAGE_TRANSFER_SRC_BIT |
                                                             VK_IMAGE_USAGE_COLOR_ATTACHMENT_BIT,
                                                         "raycast target"}));
  gpu::write_storage_image(ctx_, set_, 2, target_.view);
  return Status::ok();
}

Result<ImageRgbaF> Raycaster::render_float(const Camera& camera, const RenderSettings& s, uint32_t width,
                                           uint32_t height, RenderPath path) {
  VXR_TRACE_SCOPE("raycaster.render");
  if (volume_tex_.empty()) return invalid_argument("render: no volume was set");
  if (width == 0 || height == 0) return invalid_argument("render: image size has a zero side");
  if (has_depth_ && (depth_tex_.extent.width != width || depth_tex_.extent.height != height))
    return invalid_argument("render: the depth image is " + std::to_string(depth_tex_.extent.width) + "x" +
                            std::to_string(depth_tex_.extent.height) + ", the render " + std::to_string(width) + "x" +
                            std::to_string(height));
  VXR_RETURN_IF_ERROR(validate_render_settings(s, channel_count()));
  VXR_RETURN_IF_ERROR(ensure_target(width, height));

  // The table changes only when the settings do: a frame loop (XR, benches)
  // pays its upload (a staging copy and a submit) once, not per eye and frame.
  TransferTable table = build_transfer_table(s);
  if (table.rgba != uploaded_table_) {
    VXR_RETURN_IF_ERROR(
        gpu::upload_image(ctx_, transfer_tex_, table.rgba.data(), table.rgba.size() * sizeof(glm::vec4)));
    uploaded_table_ = std::move(table.rgba);
  }
  gpu::write_combined_image(ctx_, set_, 3, has_depth_ ? depth_tex_.view : empty_depth_.view, nearest_);

  const RaycastSetup setup = plan_raycast(camera, s, placement_, value_scales_, width, height);
  const shader::RaycastParams p = pack_params(setup, has_depth_);
  std::memcpy(params_.mapped, &p, sizeof(p));
  VXR_ASSIGN_OR_RETURN(const gpu::ComputePipeline* pipe, pipeline_for(path, setup));

  const auto t_start = std::chrono::steady_clock::now();
  VXR_RETURN_IF_ERROR(ctx_.submit_and_wait([&](VkCommandBuffer cmd) {
    if (path == RenderPath::kCompute) {
      gpu::transition_image(cmd, target_, VK_IMAGE_LAYOUT_GENERAL, VK_PIPELINE_STAGE_2_NONE, 0,
                            VK_PIPELINE_STAGE_2_COMPUTE_SHADER_BIT, VK_ACCESS_2_SHADER_STORAGE_WRITE_BIT);
      timer_.begin(cmd, "gpu.raycast.compute");
      vkCmdBindPipeline(cmd, VK_PIPELINE_BIND_POINT_COMPUTE, pipe->pipeline);
      vkCmdBindDescriptorSets(cmd, VK_PIPELINE_BIND_POINT_COMPUTE, pipe->layout, 0, 1, &set_, 0, nullptr);
      vkCmdDispatch(cmd, (width + 7) / 8, (height + 7) / 8, 1);
      timer_.end(cmd);
    } else {
      gpu::transition_image(cmd, target_, VK_IMAGE_LAYOUT_COLOR_ATTACHMENT_OPTIMAL, VK_PIPELINE_STAGE_2_NONE, 0,
                            VK_PIPELINE_STAGE_2_COLOR_ATTACHMENT_OUTPUT_BIT, VK_ACCESS_2_COLOR_ATTACHMENT_WRITE_BIT);
      VkRenderingAttachmentInfo color{VK_STRUCTURE_TYPE_RENDERING_ATTACHMENT_INFO};
      color.imageView = target_.view;
      color.imageLayout = VK_IMAGE_LAYOUT_COLOR_ATTACHMENT_OPTIMAL;
      color.loadOp = VK_ATTACHMENT_LOAD_OP_DONT_CARE;
      color.storeOp = VK_ATTACHMENT_STORE_OP_STORE;
      VkRenderingInfo ri{VK_STRUCTURE_TYPE_RENDERING_INFO};
      ri.renderArea = {{0, 0}, {width, height}};
      ri.layerCount = 1;
      ri.colorAttachmentCount = 1;
      ri.pColorAttachments = &color;
      timer_.begin(cmd, "gpu.raycast.fragment");
      vkCmdBeginRendering(cmd, &ri);
      VkViewport vp{0.0f, 0.0f, float(width), float(height), 0.0f, 1.0f};
      VkRect2D sc{{0, 0}, {width, height}};
      vkCmdSetViewport(cmd, 0, 1, &vp);
      vkCmdSetScissor(cmd, 0, 1, &sc);
      vkCmdBindPipeline(cmd, VK_PIPELINE_BIND_POINT_GRAPHICS, pipe->pipeline);
      vkCmdBindDescriptorSets(cmd, VK_PIPELINE_BIND_POINT_GRAPHICS, pipe->layout, 0, 1, &set_, 0, nullptr);
      vkCmdDraw(cmd, 3, 1, 0, 0);
      vkCmdEndRendering(cmd);
      timer_.end(cmd);
    }
  }));
  last_gpu_ms_ = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t_start).count();
  VXR_RETURN_IF_ERROR(timer_.collect().status());

  ImageRgbaF img{width, height, std::vector<float>(size_t(width) * height * 4)};
  VXR_RETURN_IF_ERROR(gpu::readback_image(ctx_, target_, img.rgba.data(), img.rgba.size() * sizeof(float)));
  return img;
}

Result<ImageRgba8> Raycaster::render(const Camera& camera, const RenderSettings& s, uint32_t width, uint32_t height,
                                     RenderPath path) {
  VXR_ASSIGN_OR_RETURN(ImageRgbaF f, render_float(camera, s, width, height, path));
  return to_rgba8(f);
}

ImageRgba8 over_black(const ImageRgba8& premultiplied) {
  ImageRgba8 out = premultiplied;
  for (size_t i = 3; i < out.pixels.size(); i += 4) out.pixels[i] = 255;
  return out;
}

}  // namespace vxr
