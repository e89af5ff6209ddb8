// Push constants of raycast.comp, shared by GLSL and C++ (one layout, two languages).
// Only vec4/uvec4 members: std430 and C++ agree on their offsets without padding rules.
#ifndef VXR_RAYCAST_PARAMS_H
#define VXR_RAYCAST_PARAMS_H

#ifdef __cplusplus
#include <glm/glm.hpp>
namespace vxr::shader {
using vec4 = glm::vec4;
using uvec4 = glm::uvec4;
#endif

// Optical models (params.model).
#define VXR_MODEL_EMISSION_ABSORPTION 0
#define VXR_MODEL_MIP 1

struct RaycastParams {
  // Camera in voxel coordinates of the volume (voxel centres at i + 0.5).
  vec4 eye;      // xyz: eye position
  vec4 forward;  // xyz: direction through the image centre
  vec4 right;    // xyz: +x of the image at unit distance (scaled by tan(fov/2) * aspect)
  vec4 up;       // xyz: +y of the image at unit distance (scaled by tan(fov/2))
  vec4 dims;     // xyz: volume size in voxels
  vec4 shading;  // x: step (voxels), y: window lo, z: window hi (0..1 of the texel range), w: extinction per voxel at TF opacity 1
  uvec4 control; // x: model, y: image width, z: image height, w: max steps
};

#ifdef __cplusplus
static_assert(sizeof(RaycastParams) == 112, "push constants must stay within 128 bytes");
}  // namespace vxr::shader
#endif

#endif
