#version 450
// Flat-shaded mesh fragment: the same headlight, outputs and window depth as
// the imposters (imposter.frag), so both share one depth test.
#extension GL_GOOGLE_include_directive : require
#include "shared/imposter_params.h"

layout(std140, binding = 1) uniform View { ImposterView V; };

layout(location = 0) flat in vec4 color;
layout(location = 1) flat in vec3 normal;
layout(location = 2) in vec3 point;
layout(location = 3) in float view_depth;
layout(location = 0) out vec4 out_color;
layout(location = 1) out float out_depth;

void main() {
  vec3 rd = normalize(point);
  float lambert = abs(dot(normal, rd));  // two-sided: a cut-open surface shows its inside too
  vec3 rgb = color.rgb * (0.3 + 0.7 * lambert);
  out_color = vec4(rgb * color.a, color.a);
  out_depth = view_depth;
  gl_FragDepth = view_depth / (view_depth + V.size.z);
}
