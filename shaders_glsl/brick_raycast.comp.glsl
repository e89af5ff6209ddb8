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
//
// Classification and compositing are the shared core's
// (include/raycast_core.glsl: vxr_step, vxr_finish), with the same
// RaycastParams the dense ray caster reads; this file only decides where the
// samples are and carries a ray's state between passes.
#extension GL_GOOGLE_include_directive : require
#extension GL_KHR_shader_subgroup_arithmetic : require

#include "shared/brick_params.h"
#include "shared/raycast_params.h"

layout(local_size_x = 8, local_size_y = 8) in;

layout(binding = 0) uniform sampler3D atlas_tex;
layout(binding = 1) uniform sampler2D transfer_tex;  // VXR_TF_SIZE x VXR_MAX_CHANNELS RGBA32F
layout(binding = 2, rgba8) uniform writeonly image2D out_image;
layout(binding = 3, rgba32f) uniform image2D accum_image;
layout(std430, binding = 4) readonly buffer Bricks { BrickRecord bricks[]; };
layout(std430, binding = 5) buffer Counters { uint samples_lo; uint samples_hi; };
layout(std430, binding = 6) readonly buffer Items { uvec4 items[]; };  // x: brick, y/z: tile origin in pixels
layout(std140, binding = 7) uniform Params { RaycastParams P; };

layout(push_constant) uniform Push { BrickCastParams p; };

#include "include/raycast_core.glsl"

// The brick being marched: vxr_sample reads its atlas slot.
vec3 g_atlas_origin;

vec4 vxr_sample(vec3 pos) {
  return vec4(textureLod(atlas_tex, (g_atlas_origin + pos) * p.atlas_inv.xyz, 0.0).r, 0.0, 0.0, 0.0);
}

vec4 vxr_transfer(int channel, float x) { return vxr_transfer_table(transfer_tex, channel, x); }

// A ray's state between passes, one channel: EA and emission keep colour and
// optical depth, MIP the largest windowed value.
vec4 pack_ray(VxrRay r) {
  if (VXR_SC_MODEL == VXR_MODEL_MIP) return vec4(r.reduce.x, r.reduce_depth.x, r.count, 0.0);
  return vec4(r.acc[0].rgb, r.tau.x);
}

VxrRay unpack_ray(vec4 v) {
  VxrRay r = vxr_begin(P);
  if (VXR_SC_MODEL == VXR_MODEL_MIP) {
    r.reduce.x = v.x;
    r.reduce_depth.x = v.y;
    r.count = v.z;
  } else {
    r.acc[0].rgb = v.rgb;
    r.tau.x = v.a;
    r.trans = exp(-r.tau.x);
    r.done = VXR_SC_MODEL == VXR_MODEL_EMISSION_ABSORPTION && r.trans <= P.march.z;
  }
  return r;
}

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
  const uint width = P.control.y, height = P.control.z;
  uvec2 pix = gl_GlobalInvocationID.xy;
  uint first = p.control.z, last = p.control.z + p.control.w;
  const bool item_mode = (flags & VXR_BRICK_WORK_ITEMS) != 0u;
  if (item_mode) {
    const uvec4 item = items[p.pass.x + gl_WorkGroupID.x];
    pix = item.yz + gl_LocalInvocationID.xy;
    first = item.x;
    last = item.x + 1u;
  }
  if (pix.x >= width || pix.y >= height) return;

  vec2 ndc = (vec2(pix) + 0.5) / vec2(width, height) * 2.0 - 1.0;
  vec3 dir = normalize(P.forward.xyz + ndc.x * P.right.xyz - ndc.y * P.up.xyz);

  float t0, t1;
  // A work item's pixel that misses its brick leaves the accumulation alone.
  if (item_mode && !segment(first, dir, t0, t1)) return;

  VxrRay ray = vxr_begin(P);
  if ((flags & VXR_BRICK_LOAD_ACCUM) != 0u) ray = unpack_ray(imageLoad(accum_image, ivec2(pix)));
  if (item_mode && ray.done) return;  // terminated earlier: nothing to add
  uint taken = 0u;

  const bool tile_lists = (flags & VXR_BRICK_TILE_LISTS) != 0u;
  if (tile_lists) {
    const uvec4 list = items[gl_WorkGroupID.y * gl_NumWorkGroups.x + gl_WorkGroupID.x];
    first = list.x;
    last = list.x + list.y;
  }
  for (uint j = first; j < last && !ray.done; ++j) {
    const uint b = tile_lists ? items[j].x : j;
    if (!item_mode && !segment(b, dir, t0, t1)) continue;
    const vec3 e = bricks[b].eye.xyz;
    g_atlas_origin = bricks[b].atlas.xyz;
    const vec3 dl = dir * bricks[b].scale.xyz;
    const float dt = P.march.x / length(dl);  // one local step, in t units
    const float i0 = ceil(t0 / dt - 0.5);
    const int n = int(ceil(t1 / dt - 0.5) - i0);
    for (int k = 0; k < n && !ray.done; ++k) {
      // From the index: no drift. The segment is dt level-0 voxels long.
      vxr_step(ray, P, e, dl, (i0 + float(k) + 0.5) * dt, dt);
      ++taken;
    }
  }

  // One atomic per subgroup, not per ray: contended atomics cost on CPUs.
  const uint total = subgroupAdd(taken);
  if (subgroupElect() && total > 0u) {
    const uint old = atomicAdd(samples_lo, total);
    if (old + total < old) atomicAdd(samples_hi, 1u);
  }
  if ((flags & VXR_BRICK_STORE_ACCUM) != 0u) imageStore(accum_image, ivec2(pix), pack_ray(ray));
  if ((flags & VXR_BRICK_STORE_FINAL) != 0u) {
    vec4 c = vxr_finish(ray, P, vec3(0.0), dir);
    if ((flags & VXR_BRICK_OPAQUE) != 0u) c.a = 1.0;  // premultiplied over black
    // k / 255 converts to byte k under any rounding the conversion uses.
    if ((flags & VXR_BRICK_QUANTIZE) != 0u) c = floor(clamp(c, 0.0, 1.0) * 255.0 + 0.5) / 255.0;
    if ((flags & VXR_BRICK_FINAL_FLOAT) != 0u) imageStore(accum_image, ivec2(pix), c);
    else imageStore(out_image, ivec2(pix + p.control.xy), c);
  }
}
