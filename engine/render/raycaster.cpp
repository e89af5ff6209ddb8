#include "render/raycaster.h"

#include <vector>

#include "core/trace.h"
#include "render/colormap.h"
#include "shared/raycast_params.h"

namespace vxr {
namespace {

std::vector<VkDescriptorSetLayoutBinding> raycast_bindings() {
  return {
      {0, VK_DESCRIPTOR_TYPE_COMBINED_IMAGE_SAMPLER, 1, VK_SHADER_STAGE_COMPUTE_BIT, nullptr},
      {1, VK_DESCRIPTOR_TYPE_COMBINED_IMAGE_SAMPLER, 1, VK_SHADER_STAGE_COMPUTE_BIT, nullptr},
      {2, VK_DESCRIPTOR_TYPE_STORAGE_IMAGE, 1, VK_SHADER_STAGE_COMPUTE_BIT, nullptr},
  };
}

glm::vec4 to_vec4(const glm::dvec3& v, double w = 0.0) {
  return glm::vec4(static_cast<float>(v.x), static_cast<float>(v.y), static_cast<float>(v.z), static_cast<float>(w));
}

}  // namespace

Result<std::unique_ptr<Raycaster>> Raycaster::create(gpu::Context& ctx) {
  std::unique_ptr<Raycaster> r(new Raycaster(ctx));
  const auto bindings = raycast_bindings();
  VXR_ASSIGN_OR_RETURN(r->pipeline_,
                       gpu::create_compute_pipeline(ctx, {"raycast.comp", bindings, sizeof(shader::RaycastParams), {}}));
  VXR_ASSIGN_OR_RETURN(r->pool_, gpu::create_descriptor_pool(ctx, bindings, 1));
  VXR_ASSIGN_OR_RETURN(r->set_, gpu::allocate_descriptor_set(ctx, r->pool_, r->pipeline_.set_layout));
  VXR_ASSIGN_OR_RETURN(r->linear_, gpu::create_linear_clamp_sampler(ctx));
  VXR_ASSIGN_OR_RETURN(r->timer_, gpu::GpuTimer::create(ctx));
  VXR_ASSIGN_OR_RETURN(r->transfer_tex_,
                       gpu::create_image(ctx, {VK_IMAGE_TYPE_2D, VK_FORMAT_R32G32B32A32_SFLOAT, {256, 1, 1},
                                               VK_IMAGE_USAGE_SAMPLED_BIT | VK_IMAGE_USAGE_TRANSFER_DST_BIT,
                                               "transfer function"}));
  return r;
}

Status Raycaster::set_volume(const DenseVolume& volume) {
  VXR_TRACE_SCOPE("raycaster.set_volume");
  VkFormat format;
  switch (volume.dtype) {
    case DType::kU8: format = VK_FORMAT_R8_UNORM; value_scale_ = 255.0; break;
    case DType::kU16: format = VK_FORMAT_R16_UNORM; value_scale_ = 65535.0; break;
    default:
      return unsupported(std::string("the GPU ray caster takes u8 or u16 volumes, not ") + dtype_name(volume.dtype));
  }
  VXR_ASSIGN_OR_RETURN(volume_tex_, gpu::create_image(ctx_, {VK_IMAGE_TYPE_3D, format,
                                                             {volume.dims[0], volume.dims[1], volume.dims[2]},
                                                             VK_IMAGE_USAGE_SAMPLED_BIT | VK_IMAGE_USAGE_TRANSFER_DST_BIT,
                                                             "volume"}));
  VXR_RETURN_IF_ERROR(gpu::upload_image(ctx_, volume_tex_, volume.data.data(), volume.data.size()));
  placement_ = {volume.dims, volume.voxel_size};
  gpu::write_combined_image(ctx_, set_, 0, volume_tex_.view, linear_);
  has_volume_ = true;
  return Status::ok();
}

Status Raycaster::ensure_target(uint32_t width, uint32_t height) {
  if (target_.image && target_.extent.width == width && target_.extent.height == height) return Status::ok();
  VXR_ASSIGN_OR_RETURN(target_, gpu::create_image(ctx_, {VK_IMAGE_TYPE_2D, VK_FORMAT_R8G8B8A8_UNORM,
                                                         {width, height, 1},
                                                         VK_IMAGE_USAGE_STORAGE_BIT | VK_IMAGE_USAGE_TRANSFER_SRC_BIT,
                                                         "raycast target"}));
  gpu::write_storage_image(ctx_, set_, 2, target_.view);
  return Status::ok();
}

Status Raycaster::upload_transfer(const RaycastSettings& s) {
  auto cmap = find_colormap(s.colormap);
  if (!cmap) return invalid_argument("unknown colormap '" + s.colormap + "'");
  std::vector<glm::vec4> table(256);
  for (int i = 0; i < 256; ++i) table[i] = glm::vec4((*cmap)[i], static_cast<float>(i) / 255.0f);
  VXR_RETURN_IF_ERROR(gpu::upload_image(ctx_, transfer_tex_, table.data(), table.size() * sizeof(glm::vec4)));
  gpu::write_combined_image(ctx_, set_, 1, transfer_tex_.view, linear_);
  return Status::ok();
}

Result<ImageRgba8> Raycaster::render(const Camera& camera, const RaycastSettings& s, uint32_t width,
                                     uint32_t height) {
  VXR_TRACE_SCOPE("raycaster.render");
  if (!has_volume_) return invalid_argument("render: no volume was set");
  if (width == 0 || height == 0) return invalid_argument("render: image size has a zero side");
  if (!(s.step_voxels > 0.0)) return invalid_argument("render: step must be > 0 voxels");
  if (!(s.window_hi > s.window_lo)) return invalid_argument("render: window lo must be below hi");
  VXR_RETURN_IF_ERROR(ensure_target(width, height));
  VXR_RETURN_IF_ERROR(upload_transfer(s));

  const VoxelSpaceRays rays = rays_in_voxel_space(camera, placement_, width, height);
  shader::RaycastParams p{};
  p.eye = to_vec4(rays.eye);
  p.forward = to_vec4(rays.forward);
  p.right = to_vec4(rays.right);
  p.up = to_vec4(rays.up);
  p.dims = glm::vec4(placement_.dims[0], placement_.dims[1], placement_.dims[2], 0.0f);
  p.shading = glm::vec4(static_cast<float>(s.step_voxels), static_cast<float>(s.window_lo / value_scale_),
                        static_cast<float>(s.window_hi / value_scale_), static_cast<float>(s.density));
  p.control = glm::uvec4(s.model == OpticalModel::kMip ? VXR_MODEL_MIP : VXR_MODEL_EMISSION_ABSORPTION, width,
                         height, s.max_steps);

  VXR_RETURN_IF_ERROR(ctx_.submit_and_wait([&](VkCommandBuffer cmd) {
    gpu::transition_image(cmd, target_, VK_IMAGE_LAYOUT_GENERAL, VK_PIPELINE_STAGE_2_NONE, 0,
                          VK_PIPELINE_STAGE_2_COMPUTE_SHADER_BIT, VK_ACCESS_2_SHADER_STORAGE_WRITE_BIT);
    timer_.begin(cmd, "gpu.raycast");
    vkCmdBindPipeline(cmd, VK_PIPELINE_BIND_POINT_COMPUTE, pipeline_.pipeline);
    vkCmdBindDescriptorSets(cmd, VK_PIPELINE_BIND_POINT_COMPUTE, pipeline_.layout, 0, 1, &set_, 0, nullptr);
    vkCmdPushConstants(cmd, pipeline_.layout, VK_SHADER_STAGE_COMPUTE_BIT, 0, sizeof(p), &p);
    vkCmdDispatch(cmd, (width + 7) / 8, (height + 7) / 8, 1);
    timer_.end(cmd);
  }));
  VXR_RETURN_IF_ERROR(timer_.collect().status());

  ImageRgba8 img(width, height);
  VXR_RETURN_IF_ERROR(gpu::readback_image(ctx_, target_, img.pixels.data(), img.pixels.size()));
  return img;
}

ImageRgba8 over_black(const ImageRgba8& premultiplied) {
  ImageRgba8 out = premultiplied;
  for (size_t i = 3; i < out.pixels.size(); i += 4) out.pixels[i] = 255;
  return out;
}

}  // namespace vxr
