#version 450
// Compute path of the ray caster: one invocation per pixel, premultiplied
// RGBA32F out. All the ray casting is in include/raycast_core.glsl.
#extension GL_GOOGLE_include_directive : require

#include "shared/raycast_params.h"

layout(local_size_x = 8, local_size_y = 8) in;
layout(binding = 2, rgba32f) uniform writeonly image2D out_image;

#include "include/raycast_dense.glsl"

void main() {
  uvec2 pix = gl_GlobalInvocationID.xy;
  if (pix.x >= p.control.y || pix.y >= p.control.z) return;
  imageStore(out_image, ivec2(pix), vxr_dense_pixel(pix));
}
