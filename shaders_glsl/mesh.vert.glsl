#version 450
// Annotation meshes (OBJ surfaces): one vertex per triangle corner, pulled
// from a storage buffer (camera-relative world units), projected with the ray
// casters' pixel-ray mapping like the imposters' guide boxes; flat normal per
// triangle from its own corners.
#extension GL_GOOGLE_include_directive : require
#include "shared/imposter_params.h"

layout(std430, binding = 0) readonly buffer Corners { vec4 corners[]; };
layout(std140, binding = 1) uniform View { ImposterView V; };
layout(std430, binding = 2) readonly buffer Colors { vec4 colors[]; };

layout(location = 0) flat out vec4 color;
layout(location = 1) flat out vec3 normal;
layout(location = 2) out vec3 point;  // camera-relative
layout(location = 3) out float view_depth;

void main() {
  int tri = gl_VertexIndex / 3;
  vec3 a = corners[tri * 3].xyz, b = corners[tri * 3 + 1].xyz, c = corners[tri * 3 + 2].xyz;
  vec3 p = corners[gl_VertexIndex].xyz;
  normal = normalize(cross(b - a, c - a));
  color = colors[tri];
  point = p;
  float s = dot(V.to_ray0.xyz, p);
  view_depth = s;
  gl_Position = vec4(dot(V.to_ray1.xyz, p), -dot(V.to_ray2.xyz, p), 0.5 * s, s);
}
