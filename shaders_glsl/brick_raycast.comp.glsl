#version 450
// Brick ray caster: each ray marches a front-to-back list of bricks from the
// LOD traversal, restarting in each brick's local voxel coordinates at its
// entry. Samples sit on a per-level grid anchored at the eye,
// t_i = (i + o) * dt, so bricks of one level continue each other exactly
// and one brick covering the whole volume (the monolithic path) gives the same
// samples as its pieces. o is the settings' sample offset (0.5: midpoints) or,
// with jitter, the core's per-pixel hash: one value per ray, so a jittered ray
// still continues across brick seams. One dispatch can march all bricks (single pass), or
// a wave of (brick, 8x8 tile) work items whose bricks do not overlap on
// screen, continuing from the accumulation image (the paper's multipass,
// batched); see engine/render/lod/brick_renderer.h.
//
// Classification and compositing are the shared core's
// (include/raycast_core.glsl: vxr_step, vxr_finish), with RaycastParams
// (shared/raycast_params.h) and the CPU reference's rules: every model, 1-4 channels,
// gradient opacity, depth colour. This file only decides where the samples
// are and carries a ray's state between passes. Gradients (gradient opacity,
// the isosurface normal) read +-1 voxel around a sample: the atlas slots carry
// an apron of 2 voxels for them (BrickPool).
#extension GL_GOOGLE_include_directive : require
#extension GL_KHR_shader_subgroup_arithmetic : require
#extension GL_KHR_shader_subgroup_basic : require
#extension GL_KHR_shader_subgroup_ballot : require
#extension GL_KHR_shader_subgroup_vote : require

#include "shared/brick_params.h"
#include "shared/raycast_params.h"

layout(local_size_x = 8, local_size_y = 8) in;

// One atlas per channel, all with the same slot layout (BrickPool); slots past
// the volume's channel count are bound to channel 0's atlas and never read.
layout(binding = 0) uniform sampler3D atlas_tex[VXR_MAX_CHANNELS];
// The transfer buffer's rows (VXR_TF_ROWS, shared/brick_params.h): the
// table, the opaque counts and the single-hue pairs per channel. A buffer,
// not a texture: on lavapipe a texelFetch goes through the sampler's code, a
// buffer load is one load (the same floats either way).
layout(std430, binding = 1) readonly buffer Transfer { vec4 transfer_table[]; };
layout(binding = 2, rgba8) uniform writeonly image2D out_image;
layout(binding = 3, rgba32f) uniform image2D accum_image;
layout(std430, binding = 4) readonly buffer Bricks { BrickRecord bricks[]; };
layout(std430, binding = 5) buffer Counters { uint sample_counters[]; };  // see VXR_SAMPLE_COUNTERS
layout(std430, binding = 6) readonly buffer Items { uvec4 items[]; };  // x: brick, y/z: tile origin in pixels
layout(std140, binding = 7) uniform Params { RaycastParams view_params; };
// Per atlas slot and channel, (min, max) texel value of each empty-space cell (BrickPool cell ranges).
layout(std430, binding = 8) readonly buffer Cells { vec2 cell_range[]; };
// The underlay (VXR_BRICK_UNDERLAY; engine/render/volume_renderer.h
// ViewUnderlay): annotations drawn first, at the view's full size. Rays end at
// its view depth; its premultiplied colour goes under the volume.
layout(binding = 9, r32f) uniform readonly image2D under_depth;
layout(binding = 10, rgba8) uniform readonly image2D under_color;
// Each walked cell (p.pass.y per axis) classified for this view's settings
// by a VXR_BRICK_CLASSIFY pass (see cell_key). MIP / MinIP: per atlas slot,
// channel and cell, the key the ray's running value is tested against. E-A
// and emission: per brick record, one bit per cell (set: empty), cell_words() words.
layout(std430, binding = 11) buffer CellKeys { float cell_keys[]; };
// Binding 11 again as R32F texels, for the rays' key tests: lavapipe loads a
// storage buffer at per-ray offsets lane by lane behind a branch each. A
// storage texel view, as binding 12.
layout(binding = 16, r32f) uniform readonly imageBuffer cell_key_texels;
layout(std430, binding = 13) buffer CellBits { uint cell_bits[]; };
// Binding 1 again as RGBA32F texels, for the rays' table lookups, which
// lavapipe (Mesa 22) loads whole per ray; a uniform buffer at
// per-ray offsets loads component by component, a storage buffer ray by
// ray with a branch each (same floats). A storage texel view: its imageLoad
// is inlined, where a uniform one's texelFetch is a call to the sampler's
// code (lit MRI 200 against 205 ms).
layout(binding = 12, rgba32f) uniform readonly imageBuffer transfer_rows;
// The start of binding 13 again, as a uniform buffer (specialisation constant
// 109): lavapipe loads a uint at per-ray offsets there without a branch per
// ray (a storage buffer has one): the MRI's E-A frame at step 0.5 took 172 ->
// 158 ms (`vxr bench peer`).
layout(std140, binding = 14) uniform CellBitsWindow { uvec4 cell_bits_window[VXR_CELL_BITS_WINDOW_WORDS / 4u]; };
// The brick table (binding 4, every view's records) again as RGBA32F texels,
// 6 a record, this view's from p.records.x (specialisation constant 108; see
// brick_record).
layout(binding = 15, rgba32f) uniform readonly imageBuffer record_texels;

// Each atlas's texel words (BrickPool write_texel_words, 32 bits) for the
// rays' own trilinear filter (specialisation constant 115); without views,
// and past the channel count, a stand-in that is never read.
layout(binding = 17, r32ui) uniform readonly uimageBuffer atlas_texels[VXR_MAX_CHANNELS];

// The whole work-list buffer (binding 6 is the view's part) as RGBA32UI
// texels, this view's list from p.records.y (specialisation constant 108;
// see work_item).
layout(binding = 18, rgba32ui) uniform readonly uimageBuffer item_texels;

layout(push_constant) uniform Push { BrickCastParams pass_params; };
// The two blocks' copies, made before main's first branch: in a branch or a
// loop lavapipe (Mesa 22) reads a uniform as a gather, lane by lane behind a
// bounds check, even at a constant offset; at the top, once, as a scalar.
RaycastParams P;
BrickCastParams p;

// Off: no dispatch of this pipeline has empty-space cells (p.pass.y is 0), so
// the walks and the grouped runs compile away and a frame with skipping off
// marches as if they did not exist. The default (unspecialised) is the general path.
layout(constant_id = 106) const bool VXR_SC_CELLS = true;
// VXR_SAMPLE_*: anything but SHADE is a benchmark's probe (shared/brick_params.h);
// its pixels show what the probe summed, not an image.
layout(constant_id = 107) const uint VXR_SC_SAMPLE_WORK = VXR_SAMPLE_SHADE;
// The brick records and work items as texels (bindings 15, 18), set where
// the device's texel buffers hold the table and the list: on lavapipe a
// storage buffer load loops over the lanes with a branch per lane and
// component, a uniform buffer's in a loop gathers each component lane by
// lane, a texel load takes a whole vec4 per lane (MRI E-A at step 1: 39.8
// ms against 41.1 through a uniform buffer, docs/skipping-perf.md, twelfth
// round). A constant, not a flag: lavapipe runs both sides of a branch on a flag.
layout(constant_id = 108) const bool VXR_SC_RECORD_TEXELS = false;
// The cell tests' emptiness bits through their uniform window (binding 14),
// set where the view's bits fit it (a flag cost 1-2%: both sides ran).
layout(constant_id = 109) const bool VXR_SC_CELL_BITS_UNIFORM = false;
// No brick loop: the pipeline of a tiled frame's tiles that no brick
// touches, whose rays all finish empty. On lavapipe an invocation of the
// full shader costs about 30 ns more than one of this, even when its loop
// runs no brick (a nearly empty 1024x1024 frame: 17.6 ms against 41.6).
layout(constant_id = 110) const bool VXR_SC_NO_BRICKS = false;
// MIP / MinIP keys as texels (binding 16), where the device's texel buffers
// hold them all: MRI MIP at step 1 65.6 ms against 69.8 from binding 11.
layout(constant_id = 111) const bool VXR_SC_KEY_TEXELS = false;
// Off: no dispatch of this pipeline carries rays between passes (multipass
// waves: work items, the accumulation image's state loaded and stored), so
// a tiled frame's invocations skip that code; lavapipe runs both sides of
// a branch on a flag (MRI E-A at step 4: 31.7-33.1 ms against 33.2-34.4).
layout(constant_id = 113) const bool VXR_SC_WAVES = true;
// Whether this pipeline runs the VXR_BRICK_CLASSIFY pass. The pass has a
// pipeline of its own, so the rays' pipelines carry none of its code, which
// lavapipe would run masked in every ray's invocation.
layout(constant_id = 114) const bool VXR_SC_CLASSIFY = true;

// 0: the rays sample the atlases (binding 0). 1 or 2: the atlas texels'
// bytes (R8 UNORM in quads, R16 UNORM in pairs), and the rays filter their
// texel views (binding 17) by hand: on lavapipe each sampler call is a function call costing
// several times the loads and arithmetic of the filter below
// (docs/skipping-perf.md, tenth round).
layout(constant_id = 115) const uint VXR_SC_TEXEL_BYTES = 0u;

// Brick b's record, read once per brick a ray enters.
BrickRecord brick_record(uint b) {
  if (!VXR_SC_RECORD_TEXELS) return bricks[b];
  const int at = int(p.records.x + b * 6u);
  BrickRecord r;
  r.eye = imageLoad(record_texels, at);
  r.scale = imageLoad(record_texels, at + 1);
  r.box_lo = imageLoad(record_texels, at + 2);
  r.box_hi = imageLoad(record_texels, at + 3);
  r.atlas = imageLoad(record_texels, at + 4);
  r.plane = imageLoad(record_texels, at + 5);
  return r;
}

// Entry i of the view's work list. On lavapipe a storage buffer load loops
// over the lanes with a bounds check and a branch per lane even where every
// lane reads the same entry: the list's loads took 13% of the sparse
// vessels' frame at step 1000 (a perf profile of the shader's code).
uvec4 work_item(uint i) {
  if (!VXR_SC_RECORD_TEXELS) return items[i];
  return imageLoad(item_texels, int(p.records.y + i));
}

// The ray's unit direction in level-0 voxels: samples are taken in the brick's
// local voxels, depth colour is measured along the whole ray from P.eye.
vec3 g_dir;
#define VXR_DEPTH_POS(pos, t) (P.eye.xyz + (t) * g_dir)

#include "include/raycast_core.glsl"

// The brick being marched: vxr_sample reads its atlas slot.
vec3 g_atlas_origin;
// The same slot for the rays' own filter (atlas_corners): its origin's
// word in the texel view, and the atlas's clamps relative to the origin.
int g_slot_word;
ivec3 g_slot_lo, g_slot_hi;
vec2 g_slot_clamp;

void set_atlas_slot(vec3 origin) {
  g_atlas_origin = origin;
  if (VXR_SC_TEXEL_BYTES == 0u) return;
  const ivec3 o = ivec3(origin);  // whole texels (BrickPool::slot_origin)
  const ivec3 last = ivec3(p.texels.z & 0xffffu, p.texels.z >> 16u, p.texels.w);
  g_slot_word = o.z * int(p.texels.y) + o.y * int(p.texels.x) + o.x;
  g_slot_lo = -o;
  g_slot_hi = last - o;
  g_slot_clamp = 0.5 - origin.xy;
}
// Where the ray ends (t units): the underlay's depth, +inf without one.
float g_t_limit = 1.0 / 0.0;
vec2 g_chord = vec2(0.0);  // average: the ray's chord through the region (region_chord)
// A probe's sum (VXR_SC_SAMPLE_WORK): stored as the pixel, so its work is kept.
float g_probe = 0.0;

// Where the sampler's linear filter with clamp-to-edge reads for texel
// coordinate `a` of the marched brick's slot (texel centres at + 0.5; the
// slot's interior origin at 0): the words (below) of its low-x corners in
// the texel view (along rows, then slices), and the weights. Taken relative
// to the slot, not the atlas, so a sample's weights round alike in every
// slot: the picture does not depend on where the pool put a brick (which
// depends on what a session loaded and evicted before).
struct AtlasCorners {
  int t000, t010, t001, t011;
  vec3 f;
};

AtlasCorners atlas_corners(vec3 a) {
  // Texel words (below) hold x and x + 1 (u8: and the same of y + 1): left
  // of the atlas's first texel centre the coordinate is clamped to it
  // (weight 0 on the word's neighbours), which is what the clamped indices give.
  if (VXR_SC_TEXEL_BYTES != 0u) a.x = max(a.x, g_slot_clamp.x);
  if (VXR_SC_TEXEL_BYTES == 1u) a.y = max(a.y, g_slot_clamp.y);
  const vec3 lo = floor(a - 0.5);
  const ivec3 i0 = clamp(ivec3(lo), g_slot_lo, g_slot_hi), i1 = clamp(ivec3(lo) + 1, g_slot_lo, g_slot_hi);
  const int row = int(p.texels.x), slice = int(p.texels.y);
  const int x0 = g_slot_word + i0.x, y0 = i0.y * row, y1 = i1.y * row, z0 = i0.z * slice, z1 = i1.z * slice;
  AtlasCorners k;
  k.t000 = z0 + y0 + x0;
  k.t010 = z0 + y1 + x0;
  k.t001 = z1 + y0 + x0;
  k.t011 = z1 + y1 + x0;
  k.f = a - 0.5 - lo;
  return k;
}

// Texel words (BrickPool write_texel_words; IMG a literal element of the
// binding: arrays of texel buffers take constant indices only), filtered
// x first, then y, then z, as the sampler does. u8: word t holds texels
// (x, y), (x + 1, y), (x, y + 1), (x + 1, y + 1) from its low byte, so a
// sample is 2 loads; lavapipe loads a 32-bit element for 8 rays with one
// gather, a 16-bit one lane by lane (MRI MIP at step 0.5: 34.7-36.8 ms
// against 43.7-47.2 with 4 loads of u8 pairs, docs/skipping-perf.md,
// twenty-second round).
float vxr_quad(uint q, vec2 f) {
  return mix(mix(float(q & 0xffu), float((q >> 8u) & 0xffu), f.x),
             mix(float((q >> 16u) & 0xffu), float(q >> 24u), f.x), f.y);
}
#define VXR_QUADS_FILTERED(IMG, k) \
  mix(vxr_quad(imageLoad(IMG, k.t000).r, k.f.xy), vxr_quad(imageLoad(IMG, k.t001).r, k.f.xy), k.f.z)
// u16: word t holds texel (x, y) and (x + 1, y) from its low half: a row of the filter is one load.
float vxr_pair_row(uint pair, float fx) { return mix(float(pair & 0xffffu), float(pair >> 16u), fx); }
#define VXR_PAIR_ROW(IMG, t, k) vxr_pair_row(imageLoad(IMG, t).r, k.f.x)
#define VXR_PAIRS_FILTERED(IMG, k)                                                                   \
  mix(mix(VXR_PAIR_ROW(IMG, k.t000, k), VXR_PAIR_ROW(IMG, k.t010, k), k.f.y),                       \
      mix(VXR_PAIR_ROW(IMG, k.t001, k), VXR_PAIR_ROW(IMG, k.t011, k), k.f.y), k.f.z)

// v.x .. v.w (up to the channel count) = FILTER over each channel's view.
#define VXR_EACH_CHANNEL(v, FILTER, k)                       \
  v.x = FILTER(atlas_texels[0], k);                          \
  if (VXR_SC_CHANNELS > 1) v.y = FILTER(atlas_texels[1], k); \
  if (VXR_SC_CHANNELS > 2) v.z = FILTER(atlas_texels[2], k); \
  if (VXR_SC_CHANNELS > 3) v.w = FILTER(atlas_texels[3], k);

vec4 vxr_sample(vec3 pos) {
  const int n = VXR_SC_CHANNELS;
  const uint b = VXR_SC_TEXEL_BYTES;
  if (b != 0u) {
    // UNORM: the stored integers filtered, then scaled once.
    const AtlasCorners k = atlas_corners(pos);
    vec4 v = vec4(0.0);
    if (b == 1u) {
      VXR_EACH_CHANNEL(v, VXR_QUADS_FILTERED, k)
    } else {
      VXR_EACH_CHANNEL(v, VXR_PAIRS_FILTERED, k)
    }
    return v * (b == 2u ? 1.0 / 65535.0 : 1.0 / 255.0);
  }
  const vec3 uvw = (g_atlas_origin + pos) * p.atlas_inv.xyz;
  // Constant indices only: dynamic indexing of sampler arrays needs a feature.
  vec4 v = vec4(textureLod(atlas_tex[0], uvw, 0.0).r, 0.0, 0.0, 0.0);
  if (n > 1) v.y = textureLod(atlas_tex[1], uvw, 0.0).r;
  if (n > 2) v.z = textureLod(atlas_tex[2], uvw, 0.0).r;
  if (n > 3) v.w = textureLod(atlas_tex[3], uvw, 0.0).r;
  return v;
}

// Each channel's hue (VXR_SC_HUE_TABLES), read once per invocation.
vec3 g_hue[VXR_MAX_CHANNELS];

vec3 vxr_hue(int channel) { return g_hue[channel]; }

// VXR_SC_HUE_TABLES: one texel of the channel's hue row holds the value and
// opacity of entries i and i + 1, where the table itself takes two (MRI E-A
// at step 0.5 in gray: 47.1-55.0 ms against 49.1-57.5 over 5 rounds,
// docs/skipping-perf.md, twentieth round).
vec2 vxr_transfer_value(int channel, float x) {
  int i;
  float f;
  vxr_transfer_index(x, i, f);
  const vec4 pair = imageLoad(transfer_rows, (VXR_TF_HUE_ROWS + channel) * VXR_TF_SIZE + i);
  return mix(pair.xy, pair.zw, f);
}

vec4 vxr_transfer(int channel, float x) {
  if (VXR_SC_HUE_TABLES) {
    const vec2 value_opacity = vxr_transfer_value(channel, x);
    return vec4(g_hue[channel] * value_opacity.x, value_opacity.y);
  }
  int i;
  float f;
  vxr_transfer_index(x, i, f);
  const int row = channel * VXR_TF_SIZE + i;
  return mix(imageLoad(transfer_rows, row), imageLoad(transfer_rows, row + 1), f);
}

// A ray's state between passes in one RGBA32F texel. The CPU sends only
// variants whose state fits to the multipass waves (brick_state_fits_texel);
// the others march in one dispatch (tiled or single pass) and never get here.
//   EA (one channel, or composite): colour and optical depth (kHueSums: the
//   value times the hue, and back).
//   emission: the colour summed over channels (the finish sums them anyway).
//   MIP/MinIP, one channel: the extreme value, its depth coordinate, count.
//   average, <= 3 channels: the length-weighted sums and the length.
//   iso: before the crossing the previous sample and its t (alpha 0), after
//   it the shaded colour (alpha 1).
vec4 pack_ray(VxrRay r) {
  const uint m = VXR_SC_MODEL;
  if (m == VXR_MODEL_MIP || m == VXR_MODEL_MINIP) return vec4(r.reduce.x, r.reduce_depth.x, r.count, 0.0);
  if (m == VXR_MODEL_AVERAGE) return vec4(r.reduce.xyz, r.count);
  if (m == VXR_MODEL_ISOSURFACE) return r.done ? r.acc[0] : vec4(r.prev_value, r.prev_t, 0.0, 0.0);
  if (m == VXR_MODEL_EMISSION) return vec4(r.acc[0].rgb + r.acc[1].rgb + r.acc[2].rgb + r.acc[3].rgb, 0.0);
  return vec4(kHueSums ? g_hue[0] * r.acc[0].a : r.acc[0].rgb, r.tau.x);
}

VxrRay unpack_ray(vec4 v) {
  VxrRay r = vxr_begin(P, g_dir);
  const uint m = VXR_SC_MODEL;
  if (m == VXR_MODEL_MIP || m == VXR_MODEL_MINIP) {
    r.reduce.x = v.x;
    r.reduce_depth.x = v.y;
    r.count = v.z;
  } else if (m == VXR_MODEL_AVERAGE) {
    r.reduce.xyz = v.xyz;
    r.count = v.w;
  } else if (m == VXR_MODEL_ISOSURFACE) {
    r.done = v.a > 0.5;
    if (r.done) {
      r.acc[0] = v;
      r.hit_t = 0.0;
    } else {
      r.prev_value = v.x;
      r.prev_t = v.y;
    }
  } else if (m == VXR_MODEL_EMISSION) {
    r.acc[0].rgb = v.rgb;
  } else {
    // kHueSums: the packed colour is the hue times the value; its largest component is the value.
    if (kHueSums) r.acc[0].a = max(max(v.r, v.g), v.b);
    else r.acc[0].rgb = v.rgb;
    r.tau.x = v.a;
    r.trans = exp(-r.tau.x);
    r.done = r.trans <= P.march.z;
  }
  return r;
}

// The finished pixel: the core's, except the isosurface, whose colour was
// shaded while the crossing's brick was bound.
vec4 finish_ray(VxrRay r) {
  if (VXR_SC_MODEL == VXR_MODEL_ISOSURFACE) return r.done ? r.acc[0] : vec4(0.0);
  return vxr_finish(r, P, vec3(0.0), g_dir);
}

// Empty-space cells (p.pass.y cells per brick axis, p.atlas_inv.w voxels each,
// half a voxel off the voxel grid: shared/brick_params.h; 0 cells: off). A
// cell may be jumped only when no sample in it can change the ray: the
// shader keeps the samples' grid, so the image is bit-identical with
// skipping off. The stored ranges bound every sample within VXR_CELL_BAND of
// the cell, so rounding in a sample's position or in the jump's exit is
// absorbed.
float opaque_entries_upto(int c, int i) { return transfer_table[(VXR_TF_OPAQUE_ROWS + c) * VXR_TF_SIZE + i].x; }

// What the cell test needs of a cell's range under the view's window and
// transfer function, computed once per frame and cell (VXR_BRICK_CLASSIFY)
// rather than per ray and cell. Per model, with x0, x1 the windowed ends:
//   mip: x1 (plus a margin): the cell is empty for a ray whose maximum is at least that;
//   minip: x0 (minus a margin): empty for a ray whose minimum is at most that;
//   average: 0 where every sample windows to 0 (average_cell_clear), else 1;
//   others: how many table entries the lookup can reach have non-zero opacity (0: empty).
// The range of walked cell `cell` (p.pass.y per axis) from the pool's cells
// (p.pass.w per axis, as many or twice as many): the union of those it covers.
vec2 walk_cell_range(uint slot, int cell, int c) {
  const uint n = p.pass.y, fine = p.pass.w;
  const uint base = (slot * uint(VXR_SC_CHANNELS) + uint(c)) * fine * fine * fine;
  if (fine == n) return cell_range[base + uint(cell)];
  const uvec3 c3 = uvec3(uint(cell) % n, (uint(cell) / n) % n, uint(cell) / (n * n)) * 2u;
  vec2 r = vec2(1.0 / 0.0, -1.0 / 0.0);
  for (uint i = 0u; i < 8u; ++i) {
    const uvec3 f = c3 + uvec3(i & 1u, (i >> 1u) & 1u, i >> 2u);
    if (all(lessThan(f, uvec3(fine)))) {
      const vec2 q = cell_range[base + (f.z * fine + f.y) * fine + f.x];
      r = vec2(min(r.x, q.x), max(r.y, q.y));
    }
  }
  return r;
}

// Average: whether every sample of a cell windows to 0 exactly, so adds
// nothing to the sums (CellOpacity on the CPU: the same rule). A filter's
// weights are non-negative: voxels at or below 0 (a stored maximum within
// the padding of 0, shared/brick_params.h) filter to at most 0, which a
// window starting at or above 0 clamps to 0; otherwise the maximum lies
// clearly (1e-4 of the window) below the window's low end, far more than a
// filter's rounding.
bool average_cell_clear(vec2 range, vec4 w) {
  return (range.y <= float(VXR_CELL_PAD_ABS) && w.x >= 0.0) || (range.y - w.x) * w.w < -1e-4;
}

float cell_key(uint slot, int cell, int c) {
  const uint m = VXR_SC_MODEL;
  const vec2 range = walk_cell_range(slot, cell, c);
  // Windowing (and gamma) is monotonic: the range's ends bound every sample's value.
  const float x0 = vxr_normalise(P, vec4(range.x))[c], x1 = vxr_normalise(P, vec4(range.y))[c];
  // MIP / MinIP: a gamma's pow may not be monotonic in the last ulp, so
  // inside the window a bound must clear the running value by a margin;
  // outside it (0 or 1 exactly) it is exact.
  if (m == VXR_MODEL_MIP) return x1 + (VXR_SC_GAMMA && x1 > 0.0 ? 1e-5 : 0.0);
  if (m == VXR_MODEL_MINIP) return x0 - (VXR_SC_GAMMA && x0 < 1.0 ? 1e-5 : 0.0);
  if (m == VXR_MODEL_AVERAGE) return average_cell_clear(range, P.window[c]) ? 0.0 : 1.0;
  // Every table entry the lookup can mix has zero opacity: a value at u = x * 255
  // mixes entries floor(u) and, with a non-zero weight, floor(u) + 1, so the
  // range's entries are floor(u0) .. ceil(u1) (x = 0 or 1 exactly, outside the
  // window, reaches one entry). The stored range is wider than any sample's
  // by far more than rounding; gamma's pow may not be monotonic in the last
  // ulp: one entry more each side.
  const float u0 = x0 * float(VXR_TF_SIZE - 1), u1 = x1 * float(VXR_TF_SIZE - 1);
  const int pad = VXR_SC_GAMMA ? 1 : 0;
  const int i0 = clamp(int(floor(u0)) - pad, 0, VXR_TF_SIZE - 1);
  const int i1 = clamp(int(ceil(u1)) + pad, 0, VXR_TF_SIZE - 1);
  return opaque_entries_upto(c, i1) - (i0 > 0 ? opaque_entries_upto(c, i0 - 1) : 0.0);
}

// Isosurface: a cell whose iso-channel maximum lies below the iso value
// holds no sample that reaches it (windowing is monotonic; gamma's pow may
// not be in the last ulp: a margin). Its samples change nothing that is
// kept: the crossing is refined against a sample read again (iso_crossing).
bool iso_cell_below(uint slot, int cell) {
  const int c = int(P.control2.y);
  const float x1 = vxr_normalise(P, vec4(walk_cell_range(slot, cell, c).y))[c];
  return x1 + (VXR_SC_GAMMA && x1 > 0.0 ? 1e-5 : 0.0) < P.iso.x;
}

const bool kReduceModel = VXR_SC_MODEL == VXR_MODEL_MIP || VXR_SC_MODEL == VXR_MODEL_MINIP;

// MIP / MinIP: per channel, whether the table's entry a ray that took nothing
// shows (0 for MIP, 255 for MinIP) is opaque. Read once per ray, not in every
// cell test: the table is a storage buffer, which lavapipe loads lane by lane
// behind a branch (vessels MinIP at step 0.5, 512x512: 302 ms with the loads
// in each test).
bool g_end_opaque[VXR_MAX_CHANNELS];
void set_end_opaque() {
  for (int c = 0; c < VXR_SC_CHANNELS; ++c)
    g_end_opaque[c] = VXR_SC_MODEL == VXR_MODEL_MIP
                          ? opaque_entries_upto(c, 0) > 0.0
                          : opaque_entries_upto(c, VXR_TF_SIZE - 1) - opaque_entries_upto(c, VXR_TF_SIZE - 2) > 0.0;
}
// The brick loop searches the list for an entry with a run (see main).
const bool kHeadSearch = VXR_SC_CELLS && !kReduceModel;

uint cell_count() { return p.pass.y * p.pass.y * p.pass.y; }
uint cell_words() { return (cell_count() + 31u) / 32u; }

// The VXR_BRICK_CLASSIFY pass, one brick per workgroup column. MIP / MinIP:
// cell_key of 64 cells of the brick's slot, every enabled channel. E-A,
// emission and average: 64 words of 32 cells each, a bit set where every
// enabled channel's key says empty (iso: where its channel is below the value).
void classify_cells() {
  const uint b = p.control.z + gl_WorkGroupID.x;
  const uint index = gl_WorkGroupID.y * 64u + gl_LocalInvocationIndex;
  const uint count = cell_count();
  if (b >= p.control.z + p.control.w || bricks[b].atlas.w < 0.0) return;
  const uint slot = uint(bricks[b].atlas.w);
  if (kReduceModel) {
    if (index >= count) return;
    for (int c = 0; c < VXR_SC_CHANNELS; ++c)
      if (P.window[c].w != 0.0) cell_keys[(slot * uint(VXR_SC_CHANNELS) + uint(c)) * count + index] = cell_key(slot, int(index), c);
    return;
  }
  if (index >= cell_words()) return;
  uint word = 0u;
  for (uint i = 0u, cell = index * 32u; i < 32u && cell < count; ++i, ++cell) {
    bool empty = true;
    if (VXR_SC_MODEL == VXR_MODEL_ISOSURFACE) {
      empty = iso_cell_below(slot, int(cell));
    } else {
      for (int c = 0; c < VXR_SC_CHANNELS; ++c)
        if (P.window[c].w != 0.0 && !(cell_key(slot, int(cell), c) <= 0.0)) empty = false;
    }
    if (empty) word |= 1u << i;
  }
  cell_bits[b * cell_words() + index] = word;
}

// `base`: the brick's first key (MIP / MinIP: slot * channels * cell_count())
// or first bits word (E-A, emission: record * cell_words()).
bool cell_is_empty(uint base, int cell, VxrRay r) {
  const uint m = VXR_SC_MODEL;
  if (!kReduceModel) {
    const uint w = base + uint(cell) / 32u;
    const uint word = VXR_SC_CELL_BITS_UNIFORM ? cell_bits_window[w / 4u][w % 4u] : cell_bits[w];
    return (word & (1u << (uint(cell) % 32u))) != 0u;
  }
  const uint count = cell_count();
  for (int c = 0; c < VXR_SC_CHANNELS; ++c) {
    if (P.window[c].w == 0.0) continue;
    const uint at = base + uint(c) * count + uint(cell);
    const float key = VXR_SC_KEY_TEXELS ? imageLoad(cell_key_texels, int(at)).r : cell_keys[at];
    if (m == VXR_MODEL_MIP) {
      // Not above the running maximum: the maximum stays. Nothing taken yet: entry 0 must be clear.
      if (!(key <= r.reduce[c]) || (r.count == 0.0 && g_end_opaque[c])) return false;
    } else if (!(key >= r.reduce[c]) || (r.count == 0.0 && g_end_opaque[c])) {
      return false;
    }
  }
  return true;
}

// Where the ray leaves cell `cell` grown by `grow` voxels, in sample
// indices before the shift (`inv`: 1 / the step's displacement in local voxels).
float cell_exit(ivec3 cell, vec3 e, vec3 inv, float grow) {
  const float s = p.atlas_inv.w;
  const vec3 lo = vec3(cell) * s - 0.5 - grow, hi = vec3(cell + 1) * s - 0.5 + grow;
  // The ray is inside the box: a zero direction component gives +-inf, never 0 * inf.
  const vec3 tmax = max((lo - e) * inv, (hi - e) * inv);
  return min(min(tmax.x, tmax.y), tmax.z);
}

// A walk through the cells (a 3D DDA): the cell, and per axis the sample
// index (before the shift) where the ray crosses into the next cell.
struct CellWalk {
  ivec3 cell;
  vec3 exits;
};

// The walk moves into the neighbour across the nearest face. Exactly one
// axis steps, even with a NaN exit (the walk then still leaves the grid).
CellWalk walk_next(CellWalk w, ivec3 step_cell, vec3 per_cell) {
  const bool x = w.exits.x <= w.exits.y && w.exits.x <= w.exits.z, y = !x && w.exits.y <= w.exits.z;
  const bvec3 across = bvec3(x, y, !x && !y);
  w.cell += ivec3(across) * step_cell;
  w.exits += mix(vec3(0.0), per_cell, across);
  return w;
}

// Where the walk leaves its cell: the nearest exit, chosen by walk_next's
// comparisons (the same as a min; lavapipe's min also tests for NaN).
float walk_exit(CellWalk w) {
  const bool x = w.exits.x <= w.exits.y && w.exits.x <= w.exits.z, y = !x && w.exits.y <= w.exits.z;
  return x ? w.exits.x : y ? w.exits.y : w.exits.z;
}

// Unsigned: a cell before the grid (negative) compares as past it.
bool walk_inside(CellWalk w) { return all(lessThan(uvec3(w.cell), uvec3(p.pass.y))); }

int walk_cell_index(ivec3 c) {
  const ivec3 q = ivec3(min(uvec3(c), uvec3(p.pass.y - 1u)));  // a cell off the grid is never used
  return (q.z * int(p.pass.y) + q.y) * int(p.pass.y) + q.x;
}

// What a walk found: empty cells first (the last one), then a run of
// occupied ones (where it ends, in sample indices before the shift).
struct WalkFound {
  bool skipped, occupied;
  ivec3 last_empty;
  float run_exit;
};

// Takes the walk's cell into `f` where `live`; false where the walk ends:
// an empty cell after the run, the run's one cell for MIP / MinIP (`extend`
// false), or the last cell with samples of this brick (n of them). Selects,
// not branches: lavapipe runs a branch as masks over both sides.
bool walk_take(inout WalkFound f, CellWalk w, bool empty, bool extend, int n, bool live) {
  const bool take = live && !(empty && f.occupied);  // the run ends here; the next walk starts in this cell
  const float exit = walk_exit(w);
  f.last_empty = mix(f.last_empty, w.cell, bvec3(take && empty));
  f.skipped = f.skipped || (take && empty);
  f.run_exit = take && !empty ? exit : f.run_exit;
  f.occupied = f.occupied || (take && !empty);
  return take && (empty || extend) && exit < float(n);
}

// Walks the cells from sample k of a ray whose run has ended: past the
// empty ones (k moves on) and through the occupied ones after them (run_end:
// where the run of samples ends), or to the end of its samples (k >= n). A
// walk that stops at the grid's edge with samples left (rounding) walks on.
void walk_to_run(inout int k, inout int run_end, vec3 e, vec3 dl, float i0, float offset, float dt, vec3 inv_step,
                 uint cell_base, int n, VxrRay ray) {
  const float inv_cell = 1.0 / p.atlas_inv.w;
  const float shift = i0 + offset;  // sample k of the brick is at e + (k + shift) * step
  const bool extend = !kReduceModel;  // MIP / MinIP runs are one cell
  for (;;) {
    // A 3D DDA from sample k's cell: a step is compares and adds, where
    // finding each cell from a sample's position and computing its exit
    // cost about twice as much. Two cells a step: the second cell's test
    // does not wait for the first's (MRI E-A at step 0.5: 125-130 ms
    // against 130-134 a cell a step and 130-141 before the DDA). One
    // break per two cells, their bookkeeping by selects (walk_take): the
    // MRI's E-A frame at step 1 (`vxr render --step 1 --window 75,200`)
    // 48.2 ms against 52.4 with a break per test (medians of 5).
    const float t = (i0 + float(k) + offset) * dt;  // from the index: no drift
    const float s = p.atlas_inv.w;
    CellWalk w;
    w.cell = clamp(ivec3(floor((e + t * dl + 0.5) * inv_cell)), ivec3(0), ivec3(int(p.pass.y) - 1));
    // An axis the ray does not move along never bounds it (+inf, never 0 * inf).
    w.exits = mix(vec3(1.0 / 0.0),
                  (vec3(w.cell + ivec3(greaterThan(dl, vec3(0.0)))) * s - 0.5 - e) * inv_step - shift,
                  notEqual(dl, vec3(0.0)));
    const ivec3 step_cell = ivec3(sign(dl));
    const vec3 per_cell = s * abs(inv_step);
    WalkFound f = WalkFound(false, false, w.cell, 0.0);
    for (;;) {
      const CellWalk w2 = walk_next(w, step_cell, per_cell);
      const bool empty = cell_is_empty(cell_base, walk_cell_index(w.cell), ray);
      const bool empty2 = cell_is_empty(cell_base, walk_cell_index(w2.cell), ray);
      const bool go = walk_take(f, w, empty, extend, n, true) && walk_inside(w2);
      const bool go2 = walk_take(f, w2, empty2, extend, n, go);
      w = walk_next(w2, step_cell, per_cell);
      if (!go2 || !walk_inside(w)) break;
    }
    // The empty cells before the run: jump to the first sample at or past
    // the exit of the last one grown by half the band; the samples before
    // it lie within the band the empty cells' ranges cover.
    const float grow = 0.5 * VXR_CELL_BAND;
    const int past_empty = max(k + 1, int(ceil(cell_exit(f.last_empty, e, inv_step, grow) - shift)));
    k = f.skipped ? past_empty : k;
    // Taking samples is always right: the run needs no margin.
    run_end = f.occupied ? min(max(k + 1, int(ceil(f.run_exit))), n) : k;
    if (k >= n || f.occupied) break;
  }
}

// Where a ray crosses the isosurface when its sample at index i of the
// marched brick (t, value v) is its first at or above the iso value
// (P.control2.w): refined against the sample one step back, read again here
// from this brick's slot (its apron of 2 voxels holds it for steps up to
// BrickRenderer's kIsoBackStep), not carried from whatever the ray sampled
// last. So the crossing is the same whether the cells or bricks before it
// were marched or skipped. No sample back there (behind the eye, outside the
// volume, the ROI or the cut): the sample itself, as in the CPU reference.
float iso_crossing(vec3 e, vec3 dl, vec4 plane, float i, float offset, float dt, float t, float v) {
  const float tb = (i - 1.0 + offset) * dt;  // sample i - 1's t, as the march computes it
  const vec3 q = P.eye.xyz + tb * g_dir, lb = e + tb * dl;
  const bool back = tb >= 0.0 && all(greaterThanEqual(q, P.region_lo.xyz)) && all(lessThanEqual(q, P.region_hi.xyz)) &&
                    (plane.xyz == vec3(0.0) || dot(plane.xyz, lb) + plane.w >= 0.0);
  if (!back) return t;
  const float vb = vxr_normalise(P, vxr_sample(lb))[int(P.control2.y)];
  return vb < P.iso.x ? tb + (P.iso.x - vb) / (v - vb) * (t - tb) : t;
}

// The ray e + t d inside the box [lo, hi) and in front of `plane` (keep
// dot(xyz, p) + w >= 0; xyz = 0: none), short of the underlay's depth, as
// [t0, t1) from t = 0. False when it misses.
bool box_chord(vec3 e, vec3 d, vec3 lo, vec3 hi, vec4 plane, out float t0, out float t1) {
  // Slab test, the three axes at once (an axis loop indexes its vectors
  // lane by lane on lavapipe). A ray parallel to a slab lies in it when
  // lo <= e < hi: a face plane belongs to the box whose low face it is (as in
  // the CPU reference), so of two neighbouring bricks exactly one marches a
  // ray lying in their shared face; that axis then does not bound t (its
  // 0 * inf is selected away, never used).
  const bvec3 parallel = equal(d, vec3(0.0));
  const uvec3 outside = uvec3(lessThan(e, lo)) | uvec3(greaterThanEqual(e, hi));
  if (any(bvec3(uvec3(parallel) & outside))) return false;
  const vec3 inv = 1.0 / d;
  const vec3 ta = (lo - e) * inv, tb = (hi - e) * inv;
  const vec3 tmin = mix(min(ta, tb), vec3(-1.0 / 0.0), parallel);
  const vec3 tmax = mix(max(ta, tb), vec3(1.0 / 0.0), parallel);
  t0 = max(max(tmin.x, tmin.y), max(tmin.z, 0.0));
  t1 = min(min(min(tmax.x, tmax.y), tmax.z), g_t_limit);
  if (plane.xyz != vec3(0.0)) {
    const float num = dot(plane.xyz, e) + plane.w, den = dot(plane.xyz, d);
    if (den > 0.0) t0 = max(t0, -num / den);
    else if (den < 0.0) t1 = min(t1, -num / den);
    else if (num < 0.0) return false;
  }
  return t1 > t0;
}

// The ray's segment [t0, t1) inside brick b (its clip box and cut plane), in
// t units (level-0 voxels along dir). False when it misses.
bool segment(BrickRecord br, vec3 dir, out float t0, out float t1) {
  const vec3 dl = dir * br.scale.xyz;  // local voxels per unit t
  if (VXR_SC_MODEL != VXR_MODEL_AVERAGE) return box_chord(br.eye.xyz, dl, br.box_lo.xyz, br.box_hi.xyz, br.plane, t0, t1);
  // Average: within the ray's chord (which holds the cut), so every sample taken is counted in its length.
  if (!box_chord(br.eye.xyz, dl, br.box_lo.xyz, br.box_hi.xyz, vec4(0.0), t0, t1)) return false;
  t0 = max(t0, g_chord.x);
  t1 = min(t1, g_chord.y);
  return t1 > t0;
}

// Average: the ray's chord through the region (the volume within the ROI,
// in front of the cut, short of the underlay's depth), as [t0, t1) (empty:
// (0, 0)). Its bricks march only within it (segment), and the length it
// averages over is the samples of its level-0 grid there times the step
// (chord_length), as the CPU reference counts them: a length that does not
// depend on which bricks or cells are marched or skipped, so samples that
// window to 0 can be skipped without changing a bit.
vec2 region_chord(vec3 dir) {
  float t0, t1;
  if (!box_chord(P.eye.xyz, dir, P.region_lo.xyz, P.region_hi.xyz, P.cut, t0, t1)) return vec2(0.0);
  return vec2(t0, t1);
}

float chord_length(vec2 chord, vec3 dir, float offset) {
  if (!(chord.y > chord.x)) return 0.0;
  const float dt = P.march.x / length(dir);  // a level-0 brick's step (scale 1)
  return max(ceil(chord.y / dt - offset) - ceil(chord.x / dt - offset), 0.0) * dt;
}

// Lens warp, one axis: warped pixel coordinate q (n rays, `edge` per outer
// band at `step` pixels each) -> coordinate in the full image; xr/lens_warp.h.
float unwarp(float q, float edge, float n, float stride) {
  const float centre = n - 2.0 * edge;
  if (q < edge) return q * stride;
  if (q < edge + centre) return edge * stride + (q - edge);
  return edge * stride + centre + (q - edge - centre) * stride;
}

void main() {
  P = view_params;
  p = pass_params;
  const uint flags = p.pass.z;
  if (VXR_SC_CLASSIFY && (flags & VXR_BRICK_CLASSIFY) != 0u) {
    classify_cells();
    return;
  }
  if (VXR_SC_HUE_TABLES)
    for (int c = 0; c < VXR_SC_CHANNELS; ++c)
      g_hue[c] = imageLoad(transfer_rows, (VXR_TF_HUE_ROWS + c + 1) * VXR_TF_SIZE - 1).rgb;
  if (VXR_SC_CELLS && kReduceModel) set_end_opaque();
  const uint width = P.control.y, height = P.control.z;
  // Each run of 8 invocations (lavapipe's SIMD group) takes a 4x2 pixel
  // block, not a row of 8: closer rays, which skip and end more alike.
  const uint li = gl_LocalInvocationIndex;
  const uvec2 local = uvec2((li & 3u) | ((li >> 1u) & 4u), ((li >> 2u) & 1u) | ((li >> 3u) & 6u));
  uvec2 pix = gl_WorkGroupID.xy * 8u + local;
  uint tile = gl_WorkGroupID.y * gl_NumWorkGroups.x + gl_WorkGroupID.x;
  if ((flags & VXR_BRICK_TILE_SUBSET) != 0u) {
    const uvec4 entry = work_item(p.pass.x + gl_WorkGroupID.x);
    tile = entry.x;
    pix = entry.yz + local;
  }
  if ((flags & VXR_BRICK_BLOCK_SUBSET) != 0u) {
    // One 4x2 block per subgroup of 8, the subgroup's own lanes across it.
    const uvec4 entry = work_item(p.pass.x + gl_WorkGroupID.x * gl_NumSubgroups + gl_SubgroupID);
    tile = entry.x;
    pix = entry.yz + uvec2(gl_SubgroupInvocationID & 3u, gl_SubgroupInvocationID >> 2u);
  }
  uint first = p.control.z, last = p.control.z + p.control.w;
  const bool item_mode = VXR_SC_WAVES && (flags & VXR_BRICK_WORK_ITEMS) != 0u;
  if (item_mode) {
    const uvec4 item = work_item(p.pass.x + gl_WorkGroupID.x);
    pix = item.yz + local;
    first = item.x;
    last = item.x + 1u;
  }
  if (pix.x >= width || pix.y >= height) return;

  vec2 ndc = (vec2(pix) + 0.5) / vec2(width, height) * 2.0 - 1.0;
  ivec2 full_pix = ivec2(pix);  // the pixel of the full image the ray goes through (the underlay's)
  if (p.warp.z > 1u) {
    const vec2 n = vec2(width, height), e = vec2(p.warp.xy);
    const float s = float(p.warp.z);
    const vec2 full = n + 2.0 * e * (s - 1.0);
    const vec2 q = vec2(unwarp(float(pix.x) + 0.5, e.x, n.x, s), unwarp(float(pix.y) + 0.5, e.y, n.y, s));
    ndc = q / full * 2.0 - 1.0;
    full_pix = ivec2(floor(q));
  }
  const vec3 raw_dir = P.forward.xyz + ndc.x * P.right.xyz - ndc.y * P.up.xyz;
  vec3 dir = normalize(raw_dir);
  const float ray_len = length(raw_dir);  // t units per unit of view depth
  g_dir = dir;
  const bool underlay = (flags & VXR_BRICK_UNDERLAY) != 0u;
  // A view depth z lies at t = z * |raw_dir| (raw_dir has unit view depth), as in the CPU reference.
  if (underlay) g_t_limit = imageLoad(under_depth, full_pix).r * length(raw_dir);
  if (VXR_SC_MODEL == VXR_MODEL_AVERAGE) g_chord = region_chord(dir);

  // Where samples sit in their step (P.march.w < 0: jitter), as in the CPU reference.
  const float offset = P.march.w < 0.0 ? vxr_jitter(uvec2(full_pix)) : P.march.w;

  float t0, t1;
  // A work item's pixel that misses its brick leaves the accumulation alone.
  if (item_mode && !segment(brick_record(first), dir, t0, t1)) return;

  VxrRay ray = vxr_begin(P, dir);
  if (VXR_SC_WAVES && (flags & VXR_BRICK_LOAD_ACCUM) != 0u) {
    const vec4 state = imageLoad(accum_image, ivec2(pix));
    if (VXR_SC_SAMPLE_WORK == VXR_SAMPLE_SHADE) ray = unpack_ray(state);
    else g_probe = state.x;
  }
  if (item_mode && ray.done) return;  // terminated earlier: nothing to add
  // Average: the length once per ray, where it starts or first loads its state (region_chord).
  if (VXR_SC_MODEL == VXR_MODEL_AVERAGE && ray.count == 0.0) ray.count = chord_length(g_chord, dir, offset);
  uint taken = 0u;

  const bool tile_lists = (flags & VXR_BRICK_TILE_LISTS) != 0u;
  if (tile_lists) {
    const uvec4 list = work_item(tile);
    first = list.x;
    last = list.x + list.y;
  }
  // The loops over bricks, runs and walks test their exit last, behind an
  // `if` for the first pass: lavapipe (Mesa 22.3) runs a loop's body
  // once more, every lane masked, when the exit is tested first, since only a
  // loop's back edge branches (MRI E-A at step 1: 38.7 -> 35.7 ms, the same
  // samples and image).
  uint j = first;
  if (!VXR_SC_NO_BRICKS && j < last && !ray.done) for (;;) {
    // The brick's head: its record, the ray's segment and, with cells, the
    // first walk. Samples k .. n - 1 of the brick are left to march; a lane
    // that misses the brick has none.
    vec3 e = vec3(0.0), dl = vec3(0.0), inv_step = vec3(0.0);
    vec4 plane = vec4(0.0);  // the brick's cut plane, for an iso crossing's sample back
    float dt = 1.0, i0 = 0.0;
    int n = 0, k = 0, run_end = 0;
    bool cells = false;
    uint cell_base = 0u;
    // E-A with cells: the heads of the list's entries in a loop of their
    // own, which moves on while no lane's first walk finds a run. lavapipe
    // runs a loop's body once even with no lane active, so an entry no lane
    // samples would otherwise cost its SIMD group a masked pass through the
    // runs and walks below (the sparse vessels: about a third of the SIMD
    // groups' entries, docs/skipping-perf.md, twenty-first round). A loop's
    // back edge is the only branch lavapipe takes (`vxr bench roofline`,
    // vessels E-A: 0.46-0.49 of the ceiling against 0.42-0.43; MRI E-A
    // unchanged: twenty-second round). Not for MIP / MinIP, whose one-cell
    // runs are found on nearly every entry (the MRI's MIP frame took 33 ms
    // against 29 with it: eighteenth round).
    for (;;) {
      // Every active lane of a subgroup is at the same j (the list is its
      // tile's, and a ray that ends leaves the loop): the broadcast says
      // so, for compilers that then load the record once per subgroup (GPUs'
      // scalar loads; lavapipe still gathers, see brick_record).
      // The entries whose segment no ray of the group meets, passed by in a
      // loop of their own before the first walk, whose masked pass would
      // cost each one as much again.
      uint b;
      BrickRecord br;
      bool hit;
      for (;;) {
        const uvec4 entry = tile_lists ? work_item(j) : uvec4(j, 0u, 0u, 0u);
        b = subgroupBroadcastFirst(entry.x);
        br = brick_record(b);
        hit = item_mode || segment(br, dir, t0, t1);
        if (hit && tile_lists) {
          // The view depths where this tile's rays can meet the brick's kept cells (build_tile_lists).
          t0 = max(t0, uintBitsToFloat(entry.y) * ray_len);
          t1 = min(t1, uintBitsToFloat(entry.z) * ray_len);
          hit = t1 > t0;
        }
        if (!kHeadSearch || j + 1u >= last || subgroupAny(hit)) break;
        ++j;
      }
      n = 0;
      k = 0;
      if (hit) {
        // One-channel E-A carries its transparency as a product within a brick;
        // each brick starts it again from the optical depth, as a multipass
        // wave's ray does (unpack_ray), so every dispatch mode gives one image.
        if (VXR_SC_CHANNELS == 1 && VXR_SC_MODEL == VXR_MODEL_EMISSION_ABSORPTION) ray.trans = exp(-ray.tau.x);
        e = br.eye.xyz;
        plane = br.plane;
        set_atlas_slot(br.atlas.xyz);
        dl = dir * br.scale.xyz;
        dt = P.march.x / length(dl);  // one local step, in t units
        i0 = ceil(t0 / dt - offset);
        n = int(ceil(t1 / dt - offset) - i0);
        // Average: a brick with no kept cell (box_hi.w) is listed only so its rays are cast.
        if (VXR_SC_MODEL == VXR_MODEL_AVERAGE && br.box_hi.w != 0.0) n = 0;
        // Cells: this brick's slot (atlas.w, < 0: none, the monolithic texture),
        // unless no cell of its box is empty (box_lo.w): then a walk finds nothing.
        cells = VXR_SC_CELLS && p.pass.y != 0u && br.atlas.w >= 0.0 && br.box_lo.w == 0.0;
        cell_base = !cells ? 0u
                    : kReduceModel ? uint(br.atlas.w) * uint(VXR_SC_CHANNELS) * cell_count()
                                   : b * cell_words();
        // The walk in sample indices: sample k of this brick is at e + (k + i0 + offset) * step.
        inv_step = 1.0 / (dl * dt);
        // Runs: a ray marches samples [k, run_end) without a test; where a run
        // ends, it jumps the empty cells ahead and finds the next run's end by
        // walking the occupied cells (cell tests only, in a CellWalk). The rays of a SIMD group
        // (lavapipe runs 8 in lockstep) then pay for a walk only where one of
        // them ends a run, not on nearly every sample as when each sample tested
        // its own cell. MIP / MinIP runs are one cell: their test depends on the
        // running value.
        run_end = cells ? 0 : n;
        // The first walk before the loop, each next one after a run: a brick's
        // last walk, which finds no run, then ends the loop without a masked
        // pass through the run's samples. `cells` first: without constant 106
        // the walks compile out (lavapipe runs an if's code even where no lane
        // takes it).
        if (cells) walk_to_run(k, run_end, e, dl, i0, offset, dt, inv_step, cell_base, n, ray);
      }
      if (!kHeadSearch || subgroupAny(k < n)) break;
      ++j;
      if (j >= last) break;
    }
    const bool group_runs = cells;  // see the run loop below
    if (k < n) for (;;) {
      // A run's samples in a loop of their own, with no run-end test inside:
      // on lavapipe the MRI's E-A frame took 190 -> 170 ms with skipping, 330
      // -> 270 without (`vxr bench peer`). With cells, a lane whose run ends
      // first keeps taking its samples while another lane's run goes on,
      // instead of waiting masked: the iteration is paid anyway, a sample in
      // an empty cell changes nothing (nor one that cannot pass a MIP /
      // MinIP running value: the value only moves away from it), and the
      // lane's next walk starts further on (MRI E-A at step 0.5: SIMD
      // iterations 2.10M -> 1.88M for 7% more samples taken; MRI MIP at step
      // 0.75: 62.4 ms against 72.7, 5% more samples). The group's iterations are counted
      // once, by the longest run left: a vote each sample (until no lane is in
      // its run) costs lavapipe a loop over the lanes. A lane that ends or
      // leaves the brick drops out; the others go on.
      const int left = k < run_end && !ray.done ? run_end - k : 0;
      const int iterations = group_runs ? subgroupMax(left) : left;
      const int stop = k + min(iterations, n - k);
      if (iterations > 0) for (;;) {
        // From the index: no drift. The segment is dt level-0 voxels long.
        const float t = (i0 + float(k) + offset) * dt;
        if (VXR_SC_SAMPLE_WORK == VXR_SAMPLE_SHADE) vxr_step(ray, P, e, dl, t, dt);
        else g_probe += VXR_SC_SAMPLE_WORK == VXR_SAMPLE_FETCH_ONLY ? vxr_sample(e + t * dl).x : t;
        ++taken;
        // The crossing's normal needs its brick's voxels: shade it now.
        if (VXR_SC_MODEL == VXR_MODEL_ISOSURFACE && ray.done) {
          if (P.control2.w != 0u) ray.hit_t = iso_crossing(e, dl, plane, i0 + float(k), offset, dt, t, ray.prev_value);
          ray.acc[0] = vxr_iso_shade(P, e + ray.hit_t * dl, dir, ray.hit_t);
        }
        ++k;
        if (k >= stop || ray.done) break;
      }
      if (k >= n || ray.done) break;
      if (cells && k >= run_end) walk_to_run(k, run_end, e, dl, i0, offset, dt, inv_step, cell_base, n, ray);
      if (k >= n) break;
    }
    ++j;
    if (j >= last || ray.done) break;
  }

  // One atomic per subgroup, not per ray: contended atomics cost on CPUs.
  const uint total = subgroupAdd(taken);
  if (subgroupElect() && total > 0u) {
    const uint groups = gl_NumWorkGroups.x * gl_NumWorkGroups.y;
    const uint group = gl_WorkGroupID.y * gl_NumWorkGroups.x + gl_WorkGroupID.x;
    const uint share = (groups + VXR_SAMPLE_COUNTERS - 1u) / VXR_SAMPLE_COUNTERS;
    const uint at = min(group / share, VXR_SAMPLE_COUNTERS - 1u) * VXR_SAMPLE_COUNTER_STRIDE;
    const uint old = atomicAdd(sample_counters[at], total);
    if (old + total < old) atomicAdd(sample_counters[at + 1u], 1u);
  }
  const bool probe = VXR_SC_SAMPLE_WORK != VXR_SAMPLE_SHADE;
  if (VXR_SC_WAVES && (flags & VXR_BRICK_STORE_ACCUM) != 0u) imageStore(accum_image, ivec2(pix), probe ? vec4(g_probe) : pack_ray(ray));
  if ((flags & VXR_BRICK_STORE_FINAL) != 0u) {
    vec4 c = probe ? vec4(fract(g_probe)) : finish_ray(ray);
    // The underlay under the volume (premultiplied): composite_volume_over's rule.
    if (underlay) c += (1.0 - clamp(c.a, 0.0, 1.0)) * imageLoad(under_color, full_pix);
    if ((flags & VXR_BRICK_OPAQUE) != 0u) c.a = 1.0;  // premultiplied over black
    // k / 255 converts to byte k under any rounding the conversion uses.
    if ((flags & VXR_BRICK_QUANTIZE) != 0u) c = floor(clamp(c, 0.0, 1.0) * 255.0 + 0.5) / 255.0;
    if ((flags & VXR_BRICK_FINAL_FLOAT) != 0u) imageStore(accum_image, ivec2(pix), c);
    else imageStore(out_image, ivec2(pix + p.control.xy), c);
  }
}
