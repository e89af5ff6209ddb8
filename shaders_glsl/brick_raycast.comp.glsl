#version 450
// Brick ray caster: each ray marches a front-to-back list of bricks from the
// LOD traversal, restarting in each brick's local voxel coordinates at its
// entry. Samples sit on a per-level grid anchored at the eye,
// t_i = (i + 0.5) * dt, so bricks of one level continue each other exactly
// and one brick covering the whole volume (the monolithic path) gives the same
// samples as its pieces. One dispatch can march all bricks (single pass), or
// a wave of (brick, 8x8 tile) work items whose bricks do not overlap on
// screen, continuing from the accumulation image (the paper's multipass,
// batched); see engine/render/lod/brick_renderer.h.
#extension GL_GOOGLE_include_directive : require
#extension GL_KHR_shader_subgroup_arithmetic : require

#include "shared/brick_params.h"
#include "shared/raycast_params.h"

layout(local_size_x = 8, local_size_y = 8) in;

layout(binding = 0) uniform sampler3D atlas_tex;
layout(binding = 1) uniform sampler2D transfer_tex;  // 256 x 1 RGBA: colour and opacity by value
layout(binding = 2, rgba8) uniform writeonly image2D out_image;
layout(binding = 3, rgba32f) uniform image2D accum_image;
layout(std430, binding = 4) readonly buffer Bricks { BrickRecord bricks[]; };
layout(std430, binding = 5) buffer Counters { uint samples_lo; uint samples_hi; };
layout(std430, binding = 6) readonly buffer Items { uvec4 items[]; };  // x: brick, y/z: tile origin in pixels

layout(push_constant) uniform Push { BrickCastParams p; };

float windowed(float v) { return clamp((v - p.shading.y) / (p.shading.z - p.shading.y), 0.0, 1.0); }

// The ray's segment [t0, t1) inside brick b (its clip box and cut plane), in
// t units (level-0 voxels along dir). False when it misses.
bool segment(uint b, vec3 dir, out float t0, out float t1) {
  const vec3 e = bricks[b].eye.xyz;
  const vec3 dl = dir * bricks[b].scale.xyz;  // local voxels per unit t
  // Slab test; NaN from 0 * inf is dropped by min/max.
  const vec3 inv = 1.0 / dl;
  const vec3 ta = (bricks[b].box_lo.xyz - e) * inv;
  const vec3 tb = (bricks[b].box_hi.xyz - e) * inv;
  const vec3 tmin = min(ta, tb), tmax = max(ta, tb);
  t0 = max(max(tmin.x, tmin.y), max(tmin.z, 0.0));
  t1 = min(min(tmax.x, tmax.y), tmax.z);
  const vec4 pl = bricks[b].plane;
  if (pl.xyz != vec3(0.0)) {
    const float num = dot(pl.xyz, e) + pl.w, den = dot(pl.xyz, dl);
    if (den > 0.0) t0 = max(t0, -num / den);
    else if (den < 0.0) t1 = min(t1, -num / den);
    else if (num < 0.0) return false;
  }
  return t1 > t0;
}

void main() {
  const uint flags = p.pass.z;
  uvec2 pix = gl_GlobalInvocationID.xy + p.pass.xy;
  uint first = p.control.z, last = p.control.z + p.control.w;
  const bool item_mode = (flags & VXR_BRICK_WORK_ITEMS) != 0u;
  if (item_mode) {
    const uvec4 item = items[p.pass.x + gl_WorkGroupID.x];
    pix = item.yz + gl_LocalInvocationID.xy;
    first = item.x;
    last = item.x + 1u;
  }
  if (pix.x >= p.control.x || pix.y >= p.control.y) return;
  const bool mip = p.pass.w == VXR_MODEL_MIP;

  vec2 ndc = (vec2(pix) + 0.5) / vec2(p.control.xy) * 2.0 - 1.0;
  vec3 dir = normalize(p.forward.xyz + ndc.x * p.right.xyz - ndc.y * p.up.xyz);

  float t0, t1;
  // A work item's pixel that misses its brick leaves the accumulation alone.
  if (item_mode && !segment(first, dir, t0, t1)) return;

  vec4 acc = vec4(0.0);  // premultiplied colour + alpha; for MIP, a = the largest windowed value
  if ((flags & VXR_BRICK_LOAD_ACCUM) != 0u) acc = imageLoad(accum_image, ivec2(pix));
  if (item_mode && !mip && acc.a >= 0.995) return;  // terminated earlier: nothing to add
  uint taken = 0u;

  const bool tile_lists = (flags & VXR_BRICK_TILE_LISTS) != 0u;
  if (tile_lists) {
    const uvec4 list = items[gl_WorkGroupID.y * gl_NumWorkGroups.x + gl_WorkGroupID.x];
    first = list.x;
    last = list.x + list.y;
  }
  for (uint j = first; j < last; ++j) {
    if (!mip && acc.a >= 0.995) break;  // early ray termination
    const uint b = tile_lists ? items[j].x : j;
    if (!item_mode && !segment(b, dir, t0, t1)) continue;
    const vec3 e = bricks[b].eye.xyz;
    const vec3 origin = bricks[b].atlas.xyz;
    const vec3 dl = dir * bricks[b].scale.xyz;
    const float dt = p.shading.x / length(dl);  // one local step, in t units
    const float i0 = ceil(t0 / dt - 0.5);
    const int n = int(ceil(t1 / dt - 0.5) - i0);
    for (int k = 0; k < n; ++k) {
      const float t = (i0 + float(k) + 0.5) * dt;  // from the index: no drift
      const vec3 pos = e + t * dl;
      const float v = windowed(textureLod(atlas_tex, (origin + pos) * p.atlas_inv.xyz, 0.0).r);
      ++taken;
      if (mip) {
        acc.a = max(acc.a, v);
      } else {
        const vec4 tf = textureLod(transfer_tex, vec2(v, 0.5), 0.0);
        const float tau = tf.a * p.shading.w * dt;
        // 1 - exp(-tau), with the series for small tau so faint tissue survives float32.
        const float a = tau < 1e-3 ? tau * (1.0 - 0.5 * tau) : 1.0 - exp(-tau);
        acc.rgb += (1.0 - acc.a) * a * tf.rgb;
        acc.a += (1.0 - acc.a) * a;
        if (acc.a >= 0.995) break;
      }
    }
  }

  // One atomic per subgroup, not per ray: contended atomics cost on CPUs.
  const uint total = subgroupAdd(taken);
  if (subgroupElect() && total > 0u) {
    const uint old = atomicAdd(samples_lo, total);
    if (old + total < old) atomicAdd(samples_hi, 1u);
  }
  if ((flags & VXR_BRICK_STORE_ACCUM) != 0u) imageStore(accum_image, ivec2(pix), acc);
  if ((flags & VXR_BRICK_STORE_FINAL) != 0u) {
    vec4 result = acc;
    if (mip) result = vec4(textureLod(transfer_tex, vec2(acc.a, 0.5), 0.0).rgb * acc.a, acc.a);
    imageStore(out_image, ivec2(pix), result);
  }
}
