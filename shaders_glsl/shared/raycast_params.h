// Uniform block of the ray caster (brick_raycast.comp, through
// include/raycast_core.glsl), shared by GLSL and C++.
// Only vec4/uvec4 members: std140 and C++ agree on their offsets without padding rules.
#ifndef VXR_RAYCAST_PARAMS_H
#define VXR_RAYCAST_PARAMS_H

#ifdef __cplusplus
#include <glm/glm.hpp>
namespace vxr::shader {
using vec4 = glm::vec4;
using uvec4 = glm::uvec4;
#endif

// Optical models (control.x).
#define VXR_MODEL_EMISSION_ABSORPTION 0
#define VXR_MODEL_MIP 1
#define VXR_MODEL_EMISSION 2
#define VXR_MODEL_MINIP 3
#define VXR_MODEL_AVERAGE 4
#define VXR_MODEL_ISOSURFACE 5

// How channels combine (control2.x).
#define VXR_BLEND_ADDITIVE 0   // each channel is its own medium; images add
#define VXR_BLEND_COMPOSITE 1  // channels mix into one medium at every sample

// Depth-coded colour (depth.x): the colour coordinate is depth, not value.
#define VXR_DEPTH_COLOR_OFF 0
#define VXR_DEPTH_COLOR_VIEW 1  // distance along the view axis across the volume's box
#define VXR_DEPTH_COLOR_AXIS_X 2
#define VXR_DEPTH_COLOR_AXIS_Y 3
#define VXR_DEPTH_COLOR_AXIS_Z 4

#define VXR_MAX_CHANNELS 4
#define VXR_TF_SIZE 256  // entries per channel in the transfer-function table, entry i at x = i / 255

struct RaycastParams {
  // Camera in voxel coordinates of the volume (voxel centres at i + 0.5, box [0, dims]).
  vec4 eye;       // xyz: eye position
  vec4 forward;   // xyz: direction through the image centre (unit length in world space, mapped to voxels)
  vec4 right;     // xyz: +x of the image at unit distance (scaled by tan(fov/2) * aspect)
  vec4 up;        // xyz: +y of the image at unit distance (scaled by tan(fov/2))
  vec4 dims;      // xyz: volume size in voxels; w: channel count (1..4)
  vec4 march;     // x: step (voxels), y: extinction per voxel at TF opacity 1,
                  // z: early-termination epsilon (stop when transmittance <= eps),
                  // w: sample offset within each segment (0..1), or < 0 for per-pixel jitter
  vec4 iso;       // x: iso value (window-normalised 0..1), y: ambient, z: diffuse, w: specular
  vec4 shading;   // x: shininess, y: depth image present (0/1), z,w: unused
  vec4 depth;     // x: depth-colour mode, y: view-depth at the box's nearest corner, z: at its farthest, w: unused
  vec4 gradient;  // x: gradient-magnitude opacity on (0/1), y: |g| where the factor starts rising, z: |g| where it reaches 1
  uvec4 control;  // x: model, y: image width, z: image height, w: max steps per ray
  uvec4 control2; // x: channel blend, y: index of the iso channel, z: naive linear opacity (1) or exact (0),
                  // w: iso crossings refined against the sample a step back read in the crossing's brick (1; brick_raycast.comp)
  vec4 window[VXR_MAX_CHANNELS];  // per channel: x lo, y hi (texel units), z gamma, w 1 / (y - x) where drawn
                                  // (in float, as a shader would compute it; once, not per sample), 0 where off
  vec4 world_opacity;  // xyz: voxel size / opacity unit distance (world-unit opacity), all 0: per voxel; w: unused
  vec4 region_lo;      // xyz: the volume's box within the ROI, voxel coordinates (as eye); w: unused
  vec4 region_hi;
  vec4 cut;            // the cut plane in voxel coordinates: keep dot(xyz, p) + w >= 0; xyz = 0: none
};

#ifdef __cplusplus
static_assert(sizeof(RaycastParams) == 320, "std140 layout of RaycastParams changed: update both languages");
}  // namespace vxr::shader
#endif

#endif
