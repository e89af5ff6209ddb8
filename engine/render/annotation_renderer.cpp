#include "render/annotation_renderer.h"

#include <algorithm>
#include <cmath>
#include <cstring>
#include <limits>

#include "annotate/annotation_store.h"
#include "core/trace.h"
#include "shared/imposter_params.h"

namespace vxr {
namespace {

glm::vec4 to_vec4(const glm::dvec3& v, double w) { return glm::vec4(float(v.x), float(v.y), float(v.z), float(w)); }

glm::dvec3 world_of(const VolumePlacement& v, const annotate::Vec3& voxel) {
  // Volume coordinates have voxel centres at i + 0.5 and the box centred at `origin`.
  const glm::dvec3 dims(v.dims[0], v.dims[1], v.dims[2]);
  return v.origin + (glm::dvec3(voxel[0], voxel[1], voxel[2]) - 0.5 * dims) *
                        glm::dvec3(v.voxel_size[0], v.voxel_size[1], v.voxel_size[2]);
}

std::vector<VkDescriptorSetLayoutBinding> bindings() {
  const VkShaderStageFlags stages = VK_SHADER_STAGE_VERTEX_BIT | VK_SHADER_STAGE_FRAGMENT_BIT;
  return {{0, VK_DESCRIPTOR_TYPE_STORAGE_BUFFER, 1, stages, nullptr},
          {1, VK_DESCRIPTOR_TYPE_UNIFORM_BUFFER, 1, stages, nullptr}};
}

std::vector<VkDescriptorSetLayoutBinding> mesh_bindings() {
  const VkShaderStageFlags stages = VK_SHADER_STAGE_VERTEX_BIT | VK_SHADER_STAGE_FRAGMENT_BIT;
  return {{0, VK_DESCRIPTOR_TYPE_STORAGE_BUFFER, 1, VK_SHADER_STAGE_VERTEX_BIT, nullptr},
          {1, VK_DESCRIPTOR_TYPE_UNIFORM_BUFFER, 1, stages, nullptr},
          {2, VK_DESCRIPTOR_TYPE_STORAGE_BUFFER, 1, VK_SHADER_STAGE_VERTEX_BIT, nullptr}};
}

// A host-visible storage buffer at least `bytes` long, grown (and rebound) when needed.
Status ensure_storage(gpu::Context& ctx, gpu::Buffer& buffer, VkDeviceSize bytes, VkDescriptorSet set,
                      uint32_t binding, const char* name) {
  bytes = std::max<VkDeviceSize>(bytes, 16);
  if (buffer.size >= bytes) return Status::ok();
  VXR_ASSIGN_OR_RETURN(buffer, gpu::create_buffer(ctx, {bytes, VK_BUFFER_USAGE_STORAGE_BUFFER_BIT,
                                                        gpu::MemoryIntent::kUpload, name}));
  gpu::write_storage_buffer(ctx, set, binding, buffer.buffer);
  return Status::ok();
}

}  // namespace

AnnotationScene annotation_scene(std::span<const annotate::Marker> markers,
                                 std::span<const annotate::Skeleton> skeletons, const VolumePlacement& placement,
                                 uint32_t timepoint, double marker_radius, double min_node_radius,
                                 glm::vec4 skeleton_color) {
  AnnotationScene scene;
  for (const annotate::Marker& m : markers) {
    if (m.timepoint != timepoint) continue;
    scene.spheres.push_back({world_of(placement, m.pos), marker_radius,
                             glm::vec4(float(m.color[0]), float(m.color[1]), float(m.color[2]), float(m.color[3]))});
  }
  const double voxel = std::min({placement.voxel_size[0], placement.voxel_size[1], placement.voxel_size[2]});
  for (const annotate::Skeleton& sk : skeletons) {
    for (const auto& [id, n] : sk.nodes()) {
      const double r = std::max(n.radius * voxel, min_node_radius);
      scene.spheres.push_back({world_of(placement, n.pos), r, skeleton_color});
      if (n.parent == annotate::kNoParent) continue;
      const annotate::SkeletonNode* p = sk.find(n.parent);
      if (!p) continue;
      scene.cones.push_back({world_of(placement, p->pos), world_of(placement, n.pos), std::max(p->radius * voxel, min_node_radius),
                             r, skeleton_color});
    }
  }
  return scene;
}

Result<AnnotationScene> load_annotation_scene(const std::string& store_path, const VolumePlacement& placement,
                                              uint32_t timepoint, double marker_radius) {
  VXR_TRACE_SCOPE("annotations.load");
  auto opened = annotate::AnnotationStore::open(store_path, /*create=*/false);
  if (!opened) return opened.status();  // names the store
  return annotation_scene_of_store(**opened, placement, timepoint, marker_radius);
}

Result<AnnotationScene> annotation_scene_of_store(const annotate::AnnotationStore& store,
                                                  const VolumePlacement& placement, uint32_t timepoint,
                                                  double marker_radius) {
  const std::string& store_path = store.path();
  VXR_ASSIGN_OR_RETURN(std::vector<annotate::Marker> markers, store.markers());
  VXR_ASSIGN_OR_RETURN(std::vector<annotate::SkeletonInfo> infos, store.skeletons());
  std::vector<annotate::Skeleton> skeletons;
  for (const annotate::SkeletonInfo& info : infos) {
    VXR_ASSIGN_OR_RETURN(annotate::Skeleton sk, store.skeleton(info.id));
    skeletons.push_back(std::move(sk));
  }
  const double diagonal = glm::length(placement.extent());
  if (!(marker_radius > 0.0)) marker_radius = 0.015 * diagonal;
  const double voxel = std::min({placement.voxel_size[0], placement.voxel_size[1], placement.voxel_size[2]});
  AnnotationScene scene = annotation_scene(markers, skeletons, placement, timepoint, marker_radius, 0.5 * voxel);
  VXR_ASSIGN_OR_RETURN(std::vector<annotate::StoredMesh> meshes, store.meshes());
  for (const annotate::StoredMesh& stored : meshes) {
    VXR_ASSIGN_OR_RETURN(annotate::Mesh mesh, store.mesh_geometry(stored.id));
    AnnotationMesh m;
    const glm::vec4 color(float(stored.color[0]), float(stored.color[1]), float(stored.color[2]), float(stored.color[3]));
    for (const auto& tri : mesh.triangles) {
      for (uint32_t v : tri) {
        if (v >= mesh.positions.size())
          return corrupt(store_path + ": mesh " + std::to_string(stored.id) + " has a triangle past its vertices");
        m.corners.push_back(world_of(placement, mesh.positions[v]));
      }
      m.colors.push_back(color);
    }
    if (!m.colors.empty()) scene.meshes.push_back(std::move(m));
  }
  return scene;
}

AnnotationMesh annotation_mesh(const annotate::Mesh& mesh, const glm::dvec3& offset, double scale, float alpha) {
  AnnotationMesh out;
  out.corners.reserve(mesh.triangles.size() * 3);
  out.colors.reserve(mesh.triangles.size());
  for (size_t t = 0; t < mesh.triangles.size(); ++t) {
    for (uint32_t v : mesh.triangles[t]) {
      const annotate::Vec3& p = mesh.positions[v];
      out.corners.push_back(offset + scale * glm::dvec3(p[0], p[1], p[2]));
    }
    const auto& c = mesh.materials[mesh.triangle_material[t]].color;
    out.colors.push_back({c[0], c[1], c[2], alpha});
  }
  return out;
}

Result<std::unique_ptr<AnnotationRenderer>> AnnotationRenderer::create(gpu::Context& ctx) {
  std::unique_ptr<AnnotationRenderer> r(new AnnotationRenderer(ctx));
  gpu::GraphicsPipelineCreateInfo info;
  info.vertex_shader = "imposter.vert";
  info.fragment_shader = "imposter.frag";
  info.bindings = bindings();
  info.color_formats = {VK_FORMAT_R8G8B8A8_UNORM, VK_FORMAT_R32_SFLOAT};
  info.depth_format = VK_FORMAT_D32_SFLOAT;
  VXR_ASSIGN_OR_RETURN(r->pipeline_, gpu::create_graphics_pipeline(ctx, info));
  VXR_ASSIGN_OR_RETURN(r->pool_, gpu::create_descriptor_pool(ctx, info.bindings, kMaxViews));

  gpu::GraphicsPipelineCreateInfo mesh = info;
  mesh.vertex_shader = "mesh.vert";
  mesh.fragment_shader = "mesh.frag";
  mesh.bindings = mesh_bindings();
  VXR_ASSIGN_OR_RETURN(r->mesh_pipeline_, gpu::create_graphics_pipeline(ctx, mesh));
  VXR_ASSIGN_OR_RETURN(r->mesh_pool_, gpu::create_descriptor_pool(ctx, mesh.bindings, kMaxViews));
  return r;
}

Result<AnnotationRenderer::View*> AnnotationRenderer::view(size_t index) {
  if (index >= kMaxViews)
    return out_of_range("annotations: view " + std::to_string(index) + " of a frame; at most " +
                        std::to_string(kMaxViews) + " views are drawn");
  while (views_.size() <= index) {
    auto v = std::make_unique<View>();
    VXR_ASSIGN_OR_RETURN(v->set, gpu::allocate_descriptor_set(ctx_, pool_, pipeline_.set_layout));
    VXR_ASSIGN_OR_RETURN(v->mesh_set, gpu::allocate_descriptor_set(ctx_, mesh_pool_, mesh_pipeline_.set_layout));
    VXR_ASSIGN_OR_RETURN(v->params, gpu::create_buffer(ctx_, {sizeof(shader::ImposterView),
                                                              VK_BUFFER_USAGE_UNIFORM_BUFFER_BIT,
                                                              gpu::MemoryIntent::kUpload, "imposter view"}));
    gpu::write_uniform_buffer(ctx_, v->set, 1, v->params.buffer);
    gpu::write_uniform_buffer(ctx_, v->mesh_set, 1, v->params.buffer);
    views_.push_back(std::move(v));
  }
  return views_[index].get();
}

Status AnnotationRenderer::ensure_targets(View& v, uint32_t width, uint32_t height) {
  if (v.color.extent.width == width && v.color.extent.height == height) return Status::ok();
  const VkExtent3D e{width, height, 1};
  // Storage: the brick ray caster reads both per pixel; transfer: render() reads them back.
  const VkImageUsageFlags usage =
      VK_IMAGE_USAGE_COLOR_ATTACHMENT_BIT | VK_IMAGE_USAGE_STORAGE_BIT | VK_IMAGE_USAGE_TRANSFER_SRC_BIT;
  VXR_ASSIGN_OR_RETURN(v.color, gpu::create_image(ctx_, {VK_IMAGE_TYPE_2D, VK_FORMAT_R8G8B8A8_UNORM, e, usage,
                                                         "annotation colour"}));
  VXR_ASSIGN_OR_RETURN(v.depth_out, gpu::create_image(ctx_, {VK_IMAGE_TYPE_2D, VK_FORMAT_R32_SFLOAT, e, usage,
                                                             "annotation view depth"}));
  VXR_ASSIGN_OR_RETURN(v.zbuffer, gpu::create_image(ctx_, {VK_IMAGE_TYPE_2D, VK_FORMAT_D32_SFLOAT, e,
                                                           VK_IMAGE_USAGE_DEPTH_STENCIL_ATTACHMENT_BIT,
                                                           "annotation z-buffer"}));
  return Status::ok();
}

Result<ViewUnderlay> AnnotationRenderer::record(VkCommandBuffer cmd, size_t index, const Camera& camera,
                                                const AnnotationScene& scene, uint32_t width, uint32_t height) {
  VXR_TRACE_SCOPE("annotations.record");
  if (width == 0 || height == 0) return invalid_argument("annotations: image size has a zero side");
  VXR_ASSIGN_OR_RETURN(View * v, view(index));
  VXR_RETURN_IF_ERROR(ensure_targets(*v, width, height));

  // Primitives camera-relative, in double until the last step.
  const PixelRays rays = rays_in_world(camera, width, height);
  std::vector<shader::ImposterPrimitive> prims;
  prims.reserve(scene.spheres.size() + scene.cones.size());
  for (const AnnotationSphere& s : scene.spheres) {
    if (!(s.radius > 0.0)) continue;
    prims.push_back({to_vec4(s.centre - rays.eye, s.radius), glm::vec4(0, 0, 0, -1), s.color});
  }
  for (const AnnotationCone& c : scene.cones) {
    if (!(c.ra > 0.0) || !(c.rb > 0.0)) continue;
    prims.push_back({to_vec4(c.a - rays.eye, c.ra), to_vec4(c.b - rays.eye, c.rb), c.color});
  }
  VXR_RETURN_IF_ERROR(ensure_storage(ctx_, v->prims, prims.size() * sizeof(shader::ImposterPrimitive), v->set, 0,
                                     "imposter primitives"));
  if (!prims.empty()) std::memcpy(v->prims.mapped, prims.data(), prims.size() * sizeof(shader::ImposterPrimitive));

  // Mesh corners camera-relative too, all meshes in one draw.
  std::vector<glm::vec4> corners, colors;
  for (const AnnotationMesh& m : scene.meshes) {
    if (m.corners.size() != m.colors.size() * 3)
      return invalid_argument("annotations: a mesh needs 3 corners per triangle colour");
    for (const glm::dvec3& c : m.corners) corners.push_back(to_vec4(c - rays.eye, 1.0));
    colors.insert(colors.end(), m.colors.begin(), m.colors.end());
  }
  VXR_RETURN_IF_ERROR(ensure_storage(ctx_, v->corners, corners.size() * sizeof(glm::vec4), v->mesh_set, 0, "mesh corners"));
  VXR_RETURN_IF_ERROR(ensure_storage(ctx_, v->colors, colors.size() * sizeof(glm::vec4), v->mesh_set, 2, "mesh colours"));
  if (!corners.empty()) {
    std::memcpy(v->corners.mapped, corners.data(), corners.size() * sizeof(glm::vec4));
    std::memcpy(v->colors.mapped, colors.data(), colors.size() * sizeof(glm::vec4));
  }

  // [forward right up] maps (s, s nx, -s ny) to a camera-relative point; the
  // vertex shader needs the inverse.
  const glm::dmat3 m(rays.forward, rays.right, rays.up);
  const glm::dmat3 inv = glm::inverse(m);
  shader::ImposterView iv{};
  iv.to_ray0 = to_vec4(glm::dvec3(inv[0][0], inv[1][0], inv[2][0]), 0);
  iv.to_ray1 = to_vec4(glm::dvec3(inv[0][1], inv[1][1], inv[2][1]), 0);
  iv.to_ray2 = to_vec4(glm::dvec3(inv[0][2], inv[1][2], inv[2][2]), 0);
  iv.forward = to_vec4(rays.forward, 0);
  iv.right = to_vec4(rays.right, 0);
  iv.up = to_vec4(rays.up, 0);
  // Window depth t / (t + scale): scale near the scene's distance keeps the float z-buffer's
  // resolution where the primitives are.
  const double scale = std::max(1e-6, glm::length(camera.target - camera.eye));
  iv.size = glm::vec4(float(width), float(height), float(scale), 0.0f);
  std::memcpy(v->params.mapped, &iv, sizeof iv);

  // The previous frame's compute pass read these images: its reads finish before the clear.
  for (gpu::Image* img : {&v->color, &v->depth_out}) {
    img->layout = VK_IMAGE_LAYOUT_UNDEFINED;  // contents discarded
    gpu::transition_image(cmd, *img, VK_IMAGE_LAYOUT_COLOR_ATTACHMENT_OPTIMAL, VK_PIPELINE_STAGE_2_ALL_COMMANDS_BIT, 0,
                          VK_PIPELINE_STAGE_2_COLOR_ATTACHMENT_OUTPUT_BIT, VK_ACCESS_2_COLOR_ATTACHMENT_WRITE_BIT);
  }
  v->zbuffer.layout = VK_IMAGE_LAYOUT_UNDEFINED;
  gpu::transition_image(cmd, v->zbuffer, VK_IMAGE_LAYOUT_DEPTH_ATTACHMENT_OPTIMAL,
                        VK_PIPELINE_STAGE_2_EARLY_FRAGMENT_TESTS_BIT | VK_PIPELINE_STAGE_2_LATE_FRAGMENT_TESTS_BIT, 0,
                        VK_PIPELINE_STAGE_2_EARLY_FRAGMENT_TESTS_BIT | VK_PIPELINE_STAGE_2_LATE_FRAGMENT_TESTS_BIT,
                        VK_ACCESS_2_DEPTH_STENCIL_ATTACHMENT_READ_BIT | VK_ACCESS_2_DEPTH_STENCIL_ATTACHMENT_WRITE_BIT);
  VkRenderingAttachmentInfo attachments[2] = {{VK_STRUCTURE_TYPE_RENDERING_ATTACHMENT_INFO},
                                              {VK_STRUCTURE_TYPE_RENDERING_ATTACHMENT_INFO}};
  attachments[0].imageView = v->color.view;
  attachments[0].clearValue.color = {{0.0f, 0.0f, 0.0f, 0.0f}};
  attachments[1].imageView = v->depth_out.view;
  attachments[1].clearValue.color = {{std::numeric_limits<float>::infinity(), 0.0f, 0.0f, 0.0f}};
  for (auto& c : attachments) {
    c.imageLayout = VK_IMAGE_LAYOUT_COLOR_ATTACHMENT_OPTIMAL;
    c.loadOp = VK_ATTACHMENT_LOAD_OP_CLEAR;
    c.storeOp = VK_ATTACHMENT_STORE_OP_STORE;
  }
  VkRenderingAttachmentInfo z{VK_STRUCTURE_TYPE_RENDERING_ATTACHMENT_INFO};
  z.imageView = v->zbuffer.view;
  z.imageLayout = VK_IMAGE_LAYOUT_DEPTH_ATTACHMENT_OPTIMAL;
  z.loadOp = VK_ATTACHMENT_LOAD_OP_CLEAR;
  z.storeOp = VK_ATTACHMENT_STORE_OP_DONT_CARE;
  z.clearValue.depthStencil = {1.0f, 0};
  VkRenderingInfo ri{VK_STRUCTURE_TYPE_RENDERING_INFO};
  ri.renderArea = {{0, 0}, {width, height}};
  ri.layerCount = 1;
  ri.colorAttachmentCount = 2;
  ri.pColorAttachments = attachments;
  ri.pDepthAttachment = &z;
  vkCmdBeginRendering(cmd, &ri);
  const VkViewport vp{0.0f, 0.0f, float(width), float(height), 0.0f, 1.0f};
  const VkRect2D sc{{0, 0}, {width, height}};
  vkCmdSetViewport(cmd, 0, 1, &vp);
  vkCmdSetScissor(cmd, 0, 1, &sc);
  if (!prims.empty()) {
    vkCmdBindPipeline(cmd, VK_PIPELINE_BIND_POINT_GRAPHICS, pipeline_.pipeline);
    vkCmdBindDescriptorSets(cmd, VK_PIPELINE_BIND_POINT_GRAPHICS, pipeline_.layout, 0, 1, &v->set, 0, nullptr);
    vkCmdDraw(cmd, 36, uint32_t(prims.size()), 0, 0);
  }
  if (!corners.empty()) {
    vkCmdBindPipeline(cmd, VK_PIPELINE_BIND_POINT_GRAPHICS, mesh_pipeline_.pipeline);
    vkCmdBindDescriptorSets(cmd, VK_PIPELINE_BIND_POINT_GRAPHICS, mesh_pipeline_.layout, 0, 1, &v->mesh_set, 0,
                            nullptr);
    vkCmdDraw(cmd, uint32_t(corners.size()), 1, 0, 0);
  }
  vkCmdEndRendering(cmd);
  // For the volume's compute pass (storage reads) and render()'s readback.
  for (gpu::Image* img : {&v->color, &v->depth_out})
    gpu::transition_image(cmd, *img, VK_IMAGE_LAYOUT_GENERAL, VK_PIPELINE_STAGE_2_COLOR_ATTACHMENT_OUTPUT_BIT,
                          VK_ACCESS_2_COLOR_ATTACHMENT_WRITE_BIT,
                          VK_PIPELINE_STAGE_2_COMPUTE_SHADER_BIT | VK_PIPELINE_STAGE_2_COPY_BIT,
                          VK_ACCESS_2_SHADER_STORAGE_READ_BIT | VK_ACCESS_2_TRANSFER_READ_BIT);
  return ViewUnderlay{v->depth_out.view, v->color.view, {width, height}};
}

Result<AnnotationImage> AnnotationRenderer::render(const Camera& camera, const AnnotationScene& scene, uint32_t width,
                                                   uint32_t height) {
  VXR_TRACE_SCOPE("annotations.render");
  Status recorded = Status::ok();
  VXR_RETURN_IF_ERROR(ctx_.submit_and_wait([&](VkCommandBuffer cmd) {
    recorded = record(cmd, 0, camera, scene, width, height).status();
  }));
  VXR_RETURN_IF_ERROR(recorded);
  View& v = *views_[0];
  AnnotationImage out{ImageRgba8(width, height), std::vector<float>(size_t(width) * height)};
  VXR_RETURN_IF_ERROR(readback_.read(ctx_, v.color, out.color.pixels.data(), out.color.pixels.size()));
  VXR_RETURN_IF_ERROR(readback_.read(ctx_, v.depth_out, out.view_depth.data(), out.view_depth.size() * sizeof(float)));
  return out;
}

ImageRgba8 composite_volume_over(const ImageRgbaF& volume, const ImageRgba8& annotations) {
  ImageRgbaF out = volume;
  for (size_t i = 0; i + 3 < out.rgba.size(); i += 4) {
    const float keep = 1.0f - std::clamp(volume.rgba[i + 3], 0.0f, 1.0f);
    for (int c = 0; c < 4; ++c) out.rgba[i + c] += keep * (float(annotations.pixels[i + c]) / 255.0f);
  }
  return to_rgba8(out);
}

}  // namespace vxr
