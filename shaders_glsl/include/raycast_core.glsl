// The ray-casting core: classification (window, gamma, transfer function,
// depth colour, gradient-magnitude opacity), one compositing step per optical
// model, and the finished pixel. brick_raycast.comp includes it and decides
// where the samples are; nothing here knows how the volume is stored. The CPU
// reference (engine/render/reference_renderer.cpp) repeats it in double.
//
// The including shader defines, before or after including this file:
//   vec4 vxr_sample(vec3 p);              raw values of channels 0..3 at voxel-space
//                                         point p (voxel centres at i + 0.5; box [0, dims])
//                                         in texel units (UNORM 0..1, or data units for float)
//   vec4 vxr_transfer(int channel, float x);  transfer-function entry at x in 0..1:
//                                         rgb the colour, a the opacity (extinction scale);
//                                         vxr_transfer_index() below gives the two entries and weight
//   with VXR_SC_HUE_TABLES, where each channel's colour is a hue (0 or 1 a component) times a value:
//   vec2 vxr_transfer_value(int channel, float x);  that value and the opacity at x
//   vec3 vxr_hue(int channel);
//
// Numerics (../shared/design/numerics.md): sample positions come from the step
// index (never t += dt); opacity from accumulated optical depth, exp(-sum tau),
// exact for any step.
#ifndef VXR_RAYCAST_CORE_GLSL
#define VXR_RAYCAST_CORE_GLSL

#include "shared/raycast_params.h"

vec4 vxr_sample(vec3 p);
vec4 vxr_transfer(int channel, float x);
vec2 vxr_transfer_value(int channel, float x);
vec3 vxr_hue(int channel);

// Where depth-coded colour is measured: the position in the volume's voxel
// space (the box [0, dims] of P). The brick marcher samples in brick-local
// voxels and defines this to map the ray parameter t (level-0 voxels along
// the unit ray) back.
#ifndef VXR_DEPTH_POS
#define VXR_DEPTH_POS(pos, t) (pos)
#endif

// Specialization constants (ids 100..103, clear of an includer's own): the
// pipeline is built per model / channel count / feature set, so the dead
// branches never reach the driver's compiler (lavapipe compiles the whole
// shader with LLVM; the all-in-one variant is several times slower to build).
// They must agree with the same fields of RaycastParams.
layout(constant_id = 100) const uint VXR_SC_MODEL = 0;            // control.x
layout(constant_id = 101) const int VXR_SC_CHANNELS = 1;          // dims.w
layout(constant_id = 102) const bool VXR_SC_GRADIENT = false;     // gradient.x != 0
layout(constant_id = 103) const bool VXR_SC_DEPTH_COLOR = false;  // depth.x != OFF
// Off: no channel has a gamma other than 1 / the exact opacity is used. They
// only remove work (the pow, the log), never change a result; the default
// (unspecialised) is the general path.
layout(constant_id = 104) const bool VXR_SC_GAMMA = true;          // some window[c].z != 1
layout(constant_id = 105) const bool VXR_SC_NAIVE_OPACITY = true;  // control2.z != 0
layout(constant_id = 112) const uint VXR_SC_BLEND = VXR_BLEND_ADDITIVE;  // control2.x
// Every channel's colours are one hue times a value (TransferTable::hue): the
// includer's lookups read one texel (vxr_transfer_value), and additive E-A
// sums each channel's light as that value alone, in acc[c].a (.rgb stays 0),
// times the hue when the ray finishes or is packed: the same floats, since
// the hue's components are 0 or 1, for a third of the compositing's work.
layout(constant_id = 116) const bool VXR_SC_HUE_TABLES = false;
const bool kHueSums = VXR_SC_HUE_TABLES && VXR_SC_MODEL == VXR_MODEL_EMISSION_ABSORPTION &&
                      VXR_SC_BLEND == VXR_BLEND_ADDITIVE;

// Table lookup with the interpolation done by the includer (two loads + mix),
// so the CPU reference can repeat it exactly: entry i sits at x = i /
// (VXR_TF_SIZE - 1); x mixes entries i and i + 1 with weight f on i + 1.
void vxr_transfer_index(float x, out int i, out float f) {
  float u = clamp(x, 0.0, 1.0) * float(VXR_TF_SIZE - 1);
  i = min(int(u), VXR_TF_SIZE - 2);
  f = u - float(i);
}

// 1 - exp(-tau), with the series for small tau so faint tissue survives
// float32; `through`: exp(-tau), where the caller has it already.
float vxr_opacity(float tau, float through) { return tau < 1e-3 ? tau * (1.0 - 0.5 * tau) : 1.0 - through; }
float vxr_opacity(float tau) { return vxr_opacity(tau, exp(-tau)); }

// The naive linear opacity correction (settings.opacity_correction = false):
// a segment's opacity is its optical depth, clamped to 1. Returned as the
// optical depth with that opacity, so the compositing below is unchanged.
// Only `vxr bench accuracy` uses it, to show what the exact form buys.
float vxr_segment_depth(RaycastParams P, float tau) {
  if (!VXR_SC_NAIVE_OPACITY) return tau;
  return P.control2.z == 0u ? tau : -log(max(1.0 - min(tau, 1.0), 1e-30));
}

// Window (lo..hi -> 0..1, clamped; w.w is 1 / (hi - lo)) then gamma, per
// channel. Channels past the volume's count stay 0 (nothing reads them).
vec4 vxr_normalise(RaycastParams P, vec4 raw) {
  vec4 x = vec4(0.0);
  for (int c = 0; c < VXR_SC_CHANNELS; ++c) {
    vec4 w = P.window[c];
    float v = clamp((raw[c] - w.x) * w.w, 0.0, 1.0);
    if (VXR_SC_GAMMA) {
      if (w.z != 1.0) v = pow(v, w.z);
    }
    x[c] = v;
  }
  return x;
}

// Depth coordinate in 0..1 for depth-coded colour.
float vxr_depth_coord(RaycastParams P, vec3 pos) {
  int mode = int(P.depth.x);
  if (mode == VXR_DEPTH_COLOR_VIEW) {
    float d = dot(pos - P.eye.xyz, normalize(P.forward.xyz));
    return clamp((d - P.depth.y) / (P.depth.z - P.depth.y), 0.0, 1.0);
  }
  int axis = mode - VXR_DEPTH_COLOR_AXIS_X;
  return clamp(pos[axis] / P.dims[axis], 0.0, 1.0);
}

// Central differences of the normalised values over +-1 voxel: g{x,y,z}[c].
void vxr_gradients(RaycastParams P, vec3 pos, out vec4 gx, out vec4 gy, out vec4 gz) {
  gx = 0.5 * (vxr_normalise(P, vxr_sample(pos + vec3(1, 0, 0))) - vxr_normalise(P, vxr_sample(pos - vec3(1, 0, 0))));
  gy = 0.5 * (vxr_normalise(P, vxr_sample(pos + vec3(0, 1, 0))) - vxr_normalise(P, vxr_sample(pos - vec3(0, 1, 0))));
  gz = 0.5 * (vxr_normalise(P, vxr_sample(pos + vec3(0, 0, 1))) - vxr_normalise(P, vxr_sample(pos - vec3(0, 0, 1))));
}

// Everything a ray carries between steps (and between bricks).
struct VxrRay {
  vec4 acc[VXR_MAX_CHANNELS];  // colour accumulated per channel (composite blend: acc[0] only)
  vec4 tau;                    // optical depth so far per channel (composite: .x)
  vec4 reduce;                 // MIP max / MinIP min / average: integral of the normalised value
  vec4 reduce_depth;           // depth coordinate where the max / min was found
  float count;                 // length sampled (average) / samples taken
  float prev_value;            // isosurface: previous value of the iso channel (< 0: none yet)
  float prev_t;
  float hit_t;                 // isosurface: ray parameter of the first crossing (< 0: none)
  float trans;                 // one channel, additive EA: the transparency so far (exp(-tau.x) at a brick's start, then the steps' product)
  float density;               // extinction at TF opacity 1 per unit of t (vxr_ray_density)
  bool done;                   // early termination or surface found
};

// Extinction at TF opacity 1 per unit of t along the unit voxel-space
// direction `dir`: the density per voxel, or in world-unit opacity the
// density times the world length of one voxel of t along this ray.
// The CPU's ray_density (engine/render/raycast_setup.h) is the same rule.
float vxr_ray_density(RaycastParams P, vec3 dir) {
  if (P.world_opacity.xyz == vec3(0.0)) return P.march.y;
  return P.march.y * length(dir * P.world_opacity.xyz);
}

// `dir`: the ray's unit direction in (level-0) voxel space.
VxrRay vxr_begin(RaycastParams P, vec3 dir) {
  VxrRay r;
  r.density = vxr_ray_density(P, dir);
  for (int c = 0; c < VXR_MAX_CHANNELS; ++c) r.acc[c] = vec4(0.0);
  r.tau = vec4(0.0);
  // A statement, not a ?: on spec constants: glslang folds that into an
  // OpSpecConstantOp select, and on lavapipe 22.3 MinIP then started at 0.
  r.reduce = vec4(0.0);
  if (VXR_SC_MODEL == VXR_MODEL_MINIP) r.reduce = vec4(1.0);
  r.reduce_depth = vec4(0.0);
  r.count = 0.0;
  r.prev_value = -1.0;
  r.prev_t = 0.0;
  r.hit_t = -1.0;
  r.trans = 1.0;
  r.done = false;
  return r;
}

// One sample at ray parameter t covering a segment of length seg (voxels).
void vxr_step(inout VxrRay r, RaycastParams P, vec3 eye, vec3 dir, float t, float seg) {
  vec3 pos = eye + t * dir;
  vec4 x = vxr_normalise(P, vxr_sample(pos));
  const int n = VXR_SC_CHANNELS;
  const uint model = VXR_SC_MODEL;
  const bool depth_color = VXR_SC_DEPTH_COLOR;

  if (model == VXR_MODEL_MIP || model == VXR_MODEL_MINIP) {
    float dc = depth_color ? vxr_depth_coord(P, VXR_DEPTH_POS(pos, t)) : 0.0;
    for (int c = 0; c < n; ++c) {
      bool better = model == VXR_MODEL_MIP ? x[c] > r.reduce[c] : x[c] < r.reduce[c];
      if (better) {
        r.reduce[c] = x[c];
        r.reduce_depth[c] = dc;
      }
    }
    r.count += 1.0;
    return;
  }
  if (model == VXR_MODEL_AVERAGE) {
    // The length averaged over (count) is the marcher's: the ray's chord,
    // so samples it skips, whose windowed values are 0 exactly, change
    // nothing (brick_raycast.comp region_chord).
    r.reduce += x * seg;
    return;
  }
  if (model == VXR_MODEL_ISOSURFACE) {
    float v = x[P.control2.y];
    if (v >= P.iso.x) {
      r.hit_t = r.prev_value < 0.0 ? t : r.prev_t + (P.iso.x - r.prev_value) / (v - r.prev_value) * (t - r.prev_t);
      r.done = true;
    }
    r.prev_value = v;
    r.prev_t = t;
    return;
  }

  // Emission-only and emission-absorption.
  vec4 gfac = vec4(1.0);
  if (VXR_SC_GRADIENT) {
    vec4 gx, gy, gz;
    vxr_gradients(P, pos, gx, gy, gz);
    vec4 mag = sqrt(gx * gx + gy * gy + gz * gz);
    gfac = clamp((mag - P.gradient.y) / (P.gradient.z - P.gradient.y), 0.0, 1.0);
  }
  float dc = depth_color ? vxr_depth_coord(P, VXR_DEPTH_POS(pos, t)) : 0.0;
  float density = r.density;
  vec3 mix_color = vec3(0.0);
  float mix_tau = 0.0;
  for (int c = 0; c < n; ++c) {
    if (P.window[c].w == 0.0) continue;
    vec4 tf;
    vec3 color;  // kHueSums: the colour's value in .x
    if (kHueSums) {
      const vec2 value_opacity = vxr_transfer_value(c, x[c]);
      tf = vec4(0.0, 0.0, 0.0, value_opacity.y);
      color = vec3(depth_color ? vxr_transfer_value(c, dc).x : value_opacity.x, 0.0, 0.0);
    } else {
      tf = vxr_transfer(c, x[c]);
      color = depth_color ? vxr_transfer(c, dc).rgb : tf.rgb;
    }
    float tau = tf.a * gfac[c] * density * seg;
    if (model == VXR_MODEL_EMISSION) {
      r.acc[c].rgb += color * tau;
    } else if (VXR_SC_BLEND == VXR_BLEND_ADDITIVE) {
      tau = vxr_segment_depth(P, tau);
      // One channel: the transparency so far is r.trans, and this segment's
      // exp(-tau) both gives its opacity and carries r.trans on: one exp a
      // step, where exp(-tau so far) took a second (dense E-A frame on
      // lavapipe 138.5 -> 130.5 ms). The product is front-to-back
      // compositing's (1 - A); the brick marcher restarts it from tau at
      // each brick, and the pixel's alpha comes from tau, not from it.
      const float trans = n == 1 ? r.trans : exp(-r.tau[c]);
      const float through = exp(-tau);
      const float light = trans * vxr_opacity(tau, through);
      if (kHueSums) r.acc[c].a += light * color.x;
      else r.acc[c].rgb += light * color;
      r.tau[c] += tau;
      if (n == 1) r.trans = trans * through;
    } else {
      mix_color += tau * color;
      mix_tau += tau;
    }
  }
  if (model == VXR_MODEL_EMISSION) return;
  if (VXR_SC_BLEND == VXR_BLEND_COMPOSITE) {
    // One medium: extinctions add, emission is the extinction-weighted colour.
    const float seg_tau = vxr_segment_depth(P, mix_tau);
    if (mix_tau > 0.0) r.acc[0].rgb += exp(-r.tau.x) * vxr_opacity(seg_tau) * (mix_color / mix_tau);
    r.tau.x += seg_tau;
    r.done = exp(-r.tau.x) <= P.march.z;
  } else {
    if (n > 1) {
      float tmin = 1e30;
      for (int c = 0; c < n; ++c)
        if (P.window[c].w != 0.0) tmin = min(tmin, r.tau[c]);
      r.trans = exp(-tmin);
    }
    r.done = r.trans <= P.march.z;  // every channel is (nearly) opaque
  }
}

// The isosurface's colour at the crossing `pos` (ray parameter t): headlight
// Lambert + specular on the central-difference normal. `dir`: the ray's unit
// direction. A brick marcher calls it while the crossing's brick is bound.
vec4 vxr_iso_shade(RaycastParams P, vec3 pos, vec3 dir, float t) {
  int ic = int(P.control2.y);
  vec4 gx, gy, gz;
  vxr_gradients(P, pos, gx, gy, gz);
  vec3 g = vec3(gx[ic], gy[ic], gz[ic]);
  float ndl = dot(g, g) > 0.0 ? abs(dot(normalize(g), dir)) : 1.0;  // headlight
  vec3 base = vxr_transfer(ic, VXR_SC_DEPTH_COLOR ? vxr_depth_coord(P, VXR_DEPTH_POS(pos, t)) : P.iso.x).rgb;
  vec3 rgb = base * (P.iso.y + P.iso.z * ndl) + vec3(P.iso.w * pow(ndl, P.shading.x));
  return vec4(clamp(rgb, 0.0, 1.0), 1.0);
}

// The ray's premultiplied RGBA. `dir` is the ray's unit direction (for shading).
vec4 vxr_finish(VxrRay r, RaycastParams P, vec3 eye, vec3 dir) {
  const int n = VXR_SC_CHANNELS;
  const uint model = VXR_SC_MODEL;
  const bool depth_color = VXR_SC_DEPTH_COLOR;
  if (model == VXR_MODEL_EMISSION_ABSORPTION || model == VXR_MODEL_EMISSION) {
    vec3 rgb = vec3(0.0);
    float tau_sum = 0.0;
    for (int c = 0; c < n; ++c) {
      rgb += kHueSums ? vxr_hue(c) * r.acc[c].a : r.acc[c].rgb;
      tau_sum += r.tau[c];
    }
    if (model == VXR_MODEL_EMISSION) return vec4(clamp(rgb, 0.0, 1.0), 0.0);
    return vec4(clamp(rgb, 0.0, 1.0), vxr_opacity(tau_sum));
  }
  if (model == VXR_MODEL_ISOSURFACE) {
    if (r.hit_t < 0.0) return vec4(0.0);
    return vxr_iso_shade(P, eye + r.hit_t * dir, dir, r.hit_t);
  }
  // MIP, MinIP, average: the reduced value through the transfer function.
  if (r.count <= 0.0) return vec4(0.0);
  vec3 rgb = vec3(0.0);
  float transparency = 1.0;
  for (int c = 0; c < n; ++c) {
    if (P.window[c].w == 0.0) continue;
    float v = model == VXR_MODEL_AVERAGE ? r.reduce[c] / r.count : r.reduce[c];
    vec4 tf = vxr_transfer(c, v);
    vec3 color = depth_color && model != VXR_MODEL_AVERAGE ? vxr_transfer(c, r.reduce_depth[c]).rgb : tf.rgb;
    rgb += color * tf.a;
    transparency *= 1.0 - tf.a;
  }
  return vec4(clamp(rgb, 0.0, 1.0), 1.0 - transparency);
}

// Deterministic per-pixel jitter in [0, 1) (a 32-bit integer hash; the CPU
// reference repeats it bit for bit).
float vxr_jitter(uvec2 pix) {
  uint h = pix.x * 0x8da6b343u ^ pix.y * 0xd8163841u;
  h ^= h >> 16;
  h *= 0x7feb352du;
  h ^= h >> 15;
  h *= 0x846ca68bu;
  h ^= h >> 16;
  return float(h >> 8) * (1.0 / 16777216.0);
}

#endif
