#version 450
// Fragment path of the ray caster: a full-screen triangle (raycast.vert), one
// fragment per pixel, the same core as raycast.comp.
#extension GL_GOOGLE_include_directive : require

#include "shared/raycast_params.h"

layout(location = 0) out vec4 out_color;

#include "include/raycast_dense.glsl"

void main() { out_color = vxr_dense_pixel(uvec2(gl_FragCoord.xy)); }
