#version 450
// First end-to-end ray caster: one ray per pixel through a 3D texture, MIP or
// front-to-back emission-absorption, premultiplied RGBA out.
// Numerics (../shared/design/numerics.md): sample positions come from the step
// index, opacity from extinction (exact for any step), NaN-safe slab test.
#extension GL_GOOGLE_include_directive : require

#include "shared/raycast_params.h"

layout(local_size_x = 8, local_size_y = 8) in;

layout(binding = 0) uniform sampler3D volume_tex;
layout(binding = 1) uniform sampler2D transfer_tex;  // 256 x 1 RGBA: colour and opacity by value
layout(binding = 2, rgba8) uniform writeonly image2D out_image;

layout(push_constant) uniform Push { RaycastParams p; };

// Ray against the box [0, dims]. Divisions by zero give +-inf; min/max with
// the NaN from 0 * inf drop it, so axis-parallel rays and origins on a face work.
bool hit_box(vec3 o, vec3 d, vec3 box_max, out float t0, out float t1) {
  vec3 inv = 1.0 / d;
  vec3 ta = (vec3(0.0) - o) * inv;
  vec3 tb = (box_max - o) * inv;
  vec3 tmin = min(ta, tb);
  vec3 tmax = max(ta, tb);
  t0 = max(max(tmin.x, tmin.y), max(tmin.z, 0.0));
  t1 = min(min(tmax.x, tmax.y), tmax.z);
  t1 *= 1.0 + 6.0 * 5.96e-8;  // conservative exit (pbrt's gamma(3)), closes cracks
  return t1 > t0;
}

float windowed(float v) {
  return clamp((v - p.shading.y) / (p.shading.z - p.shading.y), 0.0, 1.0);
}

void main() {
  uvec2 pix = gl_GlobalInvocationID.xy;
  if (pix.x >= p.control.y || pix.y >= p.control.z) return;

  vec2 ndc = (vec2(pix) + 0.5) / vec2(p.control.yz) * 2.0 - 1.0;
  vec3 dir = p.forward.xyz + ndc.x * p.right.xyz - ndc.y * p.up.xyz;
  dir = normalize(dir);
  vec3 eye = p.eye.xyz;
  vec3 dims = p.dims.xyz;

  vec4 result = vec4(0.0);
  float t0, t1;
  if (hit_box(eye, dir, dims, t0, t1)) {
    float step_len = p.shading.x;
    uint n = min(uint(ceil((t1 - t0) / step_len)), p.control.w);
    if (p.control.x == VXR_MODEL_MIP) {
      float best = 0.0;
      for (uint i = 0; i < n; ++i) {
        float t = t0 + (float(i) + 0.5) * step_len;  // from the index: no drift
        vec3 pos = eye + t * dir;
        best = max(best, windowed(texture(volume_tex, pos / dims).r));
      }
      vec4 tf = texture(transfer_tex, vec2(best, 0.5));
      result = vec4(tf.rgb * best, best);
    } else {
      vec3 color = vec3(0.0);
      float alpha = 0.0;
      for (uint i = 0; i < n; ++i) {
        float t = t0 + (float(i) + 0.5) * step_len;
        // The last sample covers only what is left of the segment.
        float seg = min(step_len, t1 - (t0 + float(i) * step_len));
        vec3 pos = eye + t * dir;
        vec4 tf = texture(transfer_tex, vec2(windowed(texture(volume_tex, pos / dims).r), 0.5));
        float tau = tf.a * p.shading.w * seg;
        // 1 - exp(-tau), with the series for small tau so faint tissue survives float32.
        float a = tau < 1e-3 ? tau * (1.0 - 0.5 * tau) : 1.0 - exp(-tau);
        color += (1.0 - alpha) * a * tf.rgb;
        alpha += (1.0 - alpha) * a;
        if (alpha >= 0.995) break;
      }
      result = vec4(color, alpha);
    }
  }
  imageStore(out_image, ivec2(pix), result);
}
