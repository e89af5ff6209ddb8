#version 450
// Guide geometry for one annotation primitive per instance: the 36 vertices of
// its bounding box, projected with the ray casters' pixel-ray mapping. The
// fragment shader ray-casts the exact sphere or cone inside it.
#extension GL_GOOGLE_include_directive : require
#include "shared/imposter_params.h"

layout(std430, binding = 0) readonly buffer Primitives { ImposterPrimitive prims[]; };
layout(std140, binding = 1) uniform View { ImposterView V; };

layout(location = 0) flat out uint prim_index;

const int kCorner[36] = int[36](0, 1, 3, 0, 3, 2,  4, 6, 7, 4, 7, 5,  0, 4, 5, 0, 5, 1,
                                2, 3, 7, 2, 7, 6,  0, 2, 6, 0, 6, 4,  1, 5, 7, 1, 7, 3);

void main() {
  ImposterPrimitive p = prims[gl_InstanceIndex];
  vec3 lo = p.a.xyz - vec3(p.a.w), hi = p.a.xyz + vec3(p.a.w);
  if (p.b.w >= 0.0) {
    lo = min(lo, p.b.xyz - vec3(p.b.w));
    hi = max(hi, p.b.xyz + vec3(p.b.w));
  }
  int c = kCorner[gl_VertexIndex];
  vec3 corner = mix(lo, hi, vec3(c & 1, (c >> 1) & 1, (c >> 2) & 1));
  float s = dot(V.to_ray0.xyz, corner);
  float sx = dot(V.to_ray1.xyz, corner);
  float sy = -dot(V.to_ray2.xyz, corner);  // = s * ny; Vulkan's ndc y grows downwards like image rows
  // z stays inside [0, w] for every point in front of the eye: only the eye
  // plane clips; the fragment shader writes the true depth.
  gl_Position = vec4(sx, sy, 0.5 * s, s);
  prim_index = gl_InstanceIndex;
}
