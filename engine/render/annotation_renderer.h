// Annotations drawn with the volume: count markers as spheres, traced
// skeletons as spheres joined by the cones tangent to them, segmented
// surfaces (OBJ meshes) as flat-shaded triangles (the paper's
// method: each primitive is ray-cast exactly in a fragment shader over guide
// geometry, its bounding box, that the vertex shader builds on the GPU; no
// tessellated meshes, so a sphere is round at any zoom).
//
// The pass writes premultiplied colour and view depth per pixel (world units
// along the camera's forward axis, +inf where nothing is). The volume is then
// cast with that depth as where its rays end and composited over the
// annotations: a marker inside a bright region is dimmed by what lies
// between it and the eye, and one in front of it is seen whole. The frame
// path: record() into the frame's command buffer, then the brick renderer's
// record_view with the returned ViewUnderlay (RenderTarget::under) does both
// in its compute pass. The CPU comparison: render() reads the images back,
// the CPU reference ends its rays at view_depth (ReferenceOptions), then
// composite_volume_over.
#pragma once

#include <glm/glm.hpp>
#include <memory>
#include <span>
#include <string>
#include <vector>

#include "annotate/annotations.h"
#include "annotate/obj.h"
#include "annotate/skeleton.h"
#include "core/image.h"
#include "core/status.h"
#include "gpu/context.h"
#include "gpu/pipeline.h"
#include "gpu/resources.h"
#include "render/camera.h"
#include "core/image.h"
#include "render/volume_renderer.h"  // ViewUnderlay

namespace vxr {
namespace annotate {
class AnnotationStore;
}

// World units (the volume centred at the origin, as Camera).
struct AnnotationSphere {
  glm::dvec3 centre{0.0};
  double radius = 1.0;
  glm::vec4 color{1, 1, 0, 1};  // linear RGB, straight alpha
};
// Spheres (a, ra) and (b, rb) and the cone tangent to both: a skeleton edge.
struct AnnotationCone {
  glm::dvec3 a{0.0}, b{0.0};
  double ra = 1.0, rb = 1.0;
  glm::vec4 color{1, 1, 0, 1};
};
// A triangle mesh (a segmented surface), drawn flat-shaded with depth.
struct AnnotationMesh {
  std::vector<glm::dvec3> corners;  // 3 per triangle, world units
  std::vector<glm::vec4> colors;    // per triangle, linear RGB, straight alpha
};
struct AnnotationScene {
  std::vector<AnnotationSphere> spheres;
  std::vector<AnnotationCone> cones;
  std::vector<AnnotationMesh> meshes;
  bool empty() const { return spheres.empty() && cones.empty() && meshes.empty(); }
};

// An OBJ mesh placed in world space: world = offset + scale * p, each
// triangle in its material's colour with `alpha`.
AnnotationMesh annotation_mesh(const annotate::Mesh& mesh, const glm::dvec3& offset, double scale, float alpha = 1.0f);

// A store's markers (at `timepoint`) and skeletons placed in world space:
// markers as spheres of `marker_radius` world units, nodes as spheres of
// their radius (voxels of the smallest side; at least `min_node_radius`
// world units), each edge as a cone.
AnnotationScene annotation_scene(std::span<const annotate::Marker> markers,
                                 std::span<const annotate::Skeleton> skeletons, const VolumePlacement& placement,
                                 uint32_t timepoint, double marker_radius, double min_node_radius,
                                 glm::vec4 skeleton_color = {0.2f, 0.8f, 1.0f, 1.0f});

// Everything an annotation store holds that is drawn, placed for the volume:
// markers at `timepoint` as spheres of `marker_radius` world units (0: 1.5%
// of the box diagonal), skeletons (node radii in voxels of the smallest side,
// at least half a voxel), and every stored mesh in its colour (positions in
// voxels). Errors name the store.
Result<AnnotationScene> load_annotation_scene(const std::string& store_path, const VolumePlacement& placement,
                                              uint32_t timepoint, double marker_radius = 0.0);
// The same from a store already open (the view's hand tools hold it: one
// LevelDB lock per store).
Result<AnnotationScene> annotation_scene_of_store(const annotate::AnnotationStore& store,
                                                  const VolumePlacement& placement, uint32_t timepoint,
                                                  double marker_radius = 0.0);

struct AnnotationImage {
  ImageRgba8 color;               // premultiplied, top row first; transparent where nothing is
  std::vector<float> view_depth;  // per pixel, +inf where nothing is
};

class AnnotationRenderer {
 public:
  // Views one frame can record (one set of images and buffers each: eyes).
  static constexpr size_t kMaxViews = 8;
  static Result<std::unique_ptr<AnnotationRenderer>> create(gpu::Context& ctx);

  // Records view `index` (< kMaxViews) of the frame into `cmd`: the scene
  // drawn into that view's colour and depth images, left in GENERAL for the
  // volume renderer's compute pass (RenderTarget::under). Nothing is read
  // back; the images and buffers of `index` are reused by the next frame, so
  // the caller waits for this one first.
  Result<ViewUnderlay> record(VkCommandBuffer cmd, size_t index, const Camera& camera, const AnnotationScene& scene,
                              uint32_t width, uint32_t height);

  // Draws the scene offscreen (view 0), submits, waits and reads it back
  // (tests, and the CPU reference's depth input: ReferenceOptions::view_depth).
  Result<AnnotationImage> render(const Camera& camera, const AnnotationScene& scene, uint32_t width, uint32_t height);

 private:
  // One view's images, buffers and descriptor sets.
  struct View {
    VkDescriptorSet set = VK_NULL_HANDLE, mesh_set = VK_NULL_HANDLE;
    gpu::Buffer prims, params, corners, colors;
    gpu::Image color, depth_out, zbuffer;
  };
  explicit AnnotationRenderer(gpu::Context& ctx) : ctx_(ctx) {}
  Result<View*> view(size_t index);
  Status ensure_targets(View& v, uint32_t width, uint32_t height);

  gpu::Context& ctx_;
  gpu::ComputePipeline pipeline_, mesh_pipeline_;
  gpu::Handle<VkDescriptorPool> pool_, mesh_pool_;
  std::vector<std::unique_ptr<View>> views_;
  gpu::ImageReadback readback_;  // render()'s staging (colour, then depth), kept between frames
};

// The volume (premultiplied float RGBA, rays ended at the annotations' depth)
// over the annotations, rounded once (v * 255 + 0.5).
ImageRgba8 composite_volume_over(const ImageRgbaF& volume, const ImageRgba8& annotations);

}  // namespace vxr
