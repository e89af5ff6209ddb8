// Annotations drawn with the volume: count markers as spheres, traced
// skeletons as spheres joined by the cones tangent to them, segmented
// surfaces (OBJ meshes) as flat-shaded triangles (the paper's
// method: each primitive is ray-cast exactly in a fragment shader over guide
// geometry, its bounding box, that the vertex shader builds on the GPU; no
// tessellated meshes, so a sphere is round at any zoom).
//
// The pass writes premultiplied colour and view depth per pixel (world units
// along the camera's forward axis, +inf where nothing is). The volume is then
// cast with that depth as where its rays end (Raycaster::set_depth), and
// composite_volume_over puts what the volume drew in front over the
// annotations: a marker inside a bright region is dimmed by what lies
// between it and the eye, and one in front of it is seen whole.
#pragma once

#include <glm/glm.hpp>
#include <memory>
#include <span>
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
#include "render/raycaster.h"  // ImageRgbaF

namespace vxr {

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
// their radius (at least `min_node_radius`), each edge as a cone.
AnnotationScene annotation_scene(std::span<const annotate::Marker> markers,
                                 std::span<const annotate::Skeleton> skeletons, const VolumePlacement& placement,
                                 uint32_t timepoint, double marker_radius, double min_node_radius,
                                 glm::vec4 skeleton_color = {0.2f, 0.8f, 1.0f, 1.0f});

struct AnnotationImage {
  ImageRgba8 color;               // premultiplied, top row first; transparent where nothing is
  std::vector<float> view_depth;  // per pixel, +inf where nothing is
};

class AnnotationRenderer {
 public:
  static Result<std::unique_ptr<AnnotationRenderer>> create(gpu::Context& ctx);

  // Draws the scene offscreen and reads it back (PNG output, tests, and the
  // depth the volume pass ends its rays at).
  Result<AnnotationImage> render(const Camera& camera, const AnnotationScene& scene, uint32_t width, uint32_t height);

 private:
  explicit AnnotationRenderer(gpu::Context& ctx) : ctx_(ctx) {}
  Status ensure_targets(uint32_t width, uint32_t height);

  gpu::Context& ctx_;
  gpu::ComputePipeline pipeline_, mesh_pipeline_;
  gpu::Handle<VkDescriptorPool> pool_, mesh_pool_;
  VkDescriptorSet set_ = VK_NULL_HANDLE, mesh_set_ = VK_NULL_HANDLE;
  gpu::Buffer prims_, view_, corners_, colors_;
  gpu::Image color_, depth_out_, zbuffer_;
};

// The volume (premultiplied float RGBA, rays ended at the annotations' depth)
// over the annotations, rounded once (v * 255 + 0.5).
ImageRgba8 composite_volume_over(const ImageRgbaF& volume, const ImageRgba8& annotations);

}  // namespace vxr
