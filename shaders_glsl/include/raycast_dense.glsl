// Bindings and storage hooks of the dense (whole volume in textures) ray
// caster, shared by raycast.comp and raycast.frag. Channels beyond the
// volume's count are bound to channel 0's texture and never read.
#ifndef VXR_RAYCAST_DENSE_GLSL
#define VXR_RAYCAST_DENSE_GLSL

layout(binding = 0) uniform sampler3D volume_tex[VXR_MAX_CHANNELS];
layout(binding = 1) uniform sampler2D transfer_tex;  // VXR_TF_SIZE x VXR_MAX_CHANNELS RGBA32F
layout(binding = 3) uniform sampler2D depth_tex;     // R32F view depth per pixel (+inf: nothing)
layout(std140, binding = 4) uniform Params { RaycastParams p; };

#include "include/raycast_core.glsl"

vec4 vxr_sample(vec3 pos) {
  vec3 uvw = pos / p.dims.xyz;
  // Constant indices only: dynamic indexing of sampler arrays needs a feature.
  vec4 v = vec4(textureLod(volume_tex[0], uvw, 0.0).r, 0.0, 0.0, 0.0);
  const int n = VXR_SC_CHANNELS;
  if (n > 1) v.y = textureLod(volume_tex[1], uvw, 0.0).r;
  if (n > 2) v.z = textureLod(volume_tex[2], uvw, 0.0).r;
  if (n > 3) v.w = textureLod(volume_tex[3], uvw, 0.0).r;
  return v;
}

vec4 vxr_transfer(int channel, float x) { return vxr_transfer_table(transfer_tex, channel, x); }

vec4 vxr_dense_pixel(uvec2 pix) {
  float depth = p.shading.y != 0.0 ? texelFetch(depth_tex, ivec2(pix), 0).r : 1.0 / 0.0;
  return vxr_cast(p, pix, depth);
}

#endif
