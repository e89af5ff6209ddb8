// Layouts of imposter.vert / imposter.frag, shared by GLSL and C++: annotation
// spheres and the tangent cones joining them, ray-cast in the fragment shader
// from a bounding box the vertex shader builds (the guide geometry). Every
// position is camera-relative world units (eye at the origin), computed in
// double on the CPU, so the GPU never sees a large coordinate.
// Only vec4 members, so std430/std140 and C++ agree on offsets.
#ifndef VXR_IMPOSTER_PARAMS_H
#define VXR_IMPOSTER_PARAMS_H

#ifdef __cplusplus
#include <glm/glm.hpp>
namespace vxr::shader {
using vec4 = glm::vec4;
#endif

// A sphere (b.w < 0) or a round cone: the convex hull of sphere (a.xyz, a.w)
// and sphere (b.xyz, b.w), i.e. both spheres and the cone tangent to them.
struct ImposterPrimitive {
  vec4 a;      // xyz: centre, w: radius
  vec4 b;      // xyz: centre, w: radius; w < 0: a sphere, b unused
  vec4 color;  // linear RGB, straight alpha
};

// The view: a pixel's ray is d = forward + nx * right - ny * up from the eye
// (nx, ny in -1..1 at pixel centres, top row ny = -1), as the ray casters use
// (engine/render/camera.h); t along d is view depth in world units.
struct ImposterView {
  vec4 to_ray0;  // rows of the inverse of the matrix [forward right up]:
  vec4 to_ray1;  // p -> (s, s nx, -s ny) for a camera-relative point p
  vec4 to_ray2;
  vec4 forward;
  vec4 right;
  vec4 up;
  vec4 size;  // xy: image size in pixels, z: depth scale (window depth = t / (t + z))
};

#ifdef __cplusplus
}  // namespace vxr::shader
#endif
#endif
