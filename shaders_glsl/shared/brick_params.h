// Layouts of brick_raycast.comp, shared by GLSL and C++: the per-brick table
// (a storage buffer the CPU writes each frame) and the push constants.
// Only vec4/uvec4 members, so std430 and C++ agree on offsets.
#ifndef VXR_BRICK_PARAMS_H
#define VXR_BRICK_PARAMS_H

#ifdef __cplusplus
#include <glm/glm.hpp>
namespace vxr::shader {
using vec4 = glm::vec4;
using uvec4 = glm::uvec4;
#endif

// Empty-space cells (BrickCells) sit half a voxel off the voxel grid: cell k
// of an axis covers local [k * s - 0.5, (k + 1) * s - 0.5), from one voxel
// centre to another, so a sample inside it filters voxels k*s-1 .. (k+1)*s-1
// only (s + 1 a side; a grid on the voxel faces reaches s + 2). A cell's
// stored range also bounds every sample up to VXR_CELL_BAND voxels outside
// it, which absorbs rounding in the walk and in samples' positions.
#define VXR_CELL_BAND (1.0 / 64.0)
// The stored range is then widened by far more than a filter's rounding:
// each end by VXR_CELL_PAD_REL of its size plus VXR_CELL_PAD_ABS, so a
// stored maximum of at most VXR_CELL_PAD_ABS means no voxel above 0.
#define VXR_CELL_PAD_REL 1e-5
#define VXR_CELL_PAD_ABS 1e-7

// The transfer buffer (bindings 1 and 12): rows of VXR_TF_SIZE RGBA32F
// entries, three per channel c (VXR_MAX_CHANNELS channels):
//   row c: the transfer table (colour, opacity; TransferTable::rgba);
//   row VXR_TF_OPAQUE_ROWS + c: in .x the count of entries 0..i with non-zero opacity;
//   row VXR_TF_HUE_ROWS + c, where the channel's colours are one hue h times a
//   value s (TransferTable::hue): entry i < VXR_TF_SIZE - 1 holds (s, opacity)
//   of entries i and i + 1, so a lookup is one texel; the last entry holds h.
#define VXR_TF_OPAQUE_ROWS VXR_MAX_CHANNELS
#define VXR_TF_HUE_ROWS (2 * VXR_MAX_CHANNELS)
#define VXR_TF_ROWS (3 * VXR_MAX_CHANNELS)

// pass.z flags
#define VXR_BRICK_LOAD_ACCUM 1u   // continue the rays from the accumulation image
#define VXR_BRICK_STORE_ACCUM 2u  // write the rays' state to the accumulation image
#define VXR_BRICK_STORE_FINAL 4u  // write the finished premultiplied RGBA8 pixel
#define VXR_BRICK_WORK_ITEMS 8u   // workgroup i marches work item pass.x + i: (brick, tile x, tile y)
#define VXR_BRICK_TILE_LISTS 16u  // workgroup (x, y) marches its tile's list: items[y * tiles_x + x] = (first, count)
// Workgroup i takes the tile of entry pass.x + i: (tile index, x, y in pixels), not tile (x, y)
// of the grid; with TILE_LISTS it marches that tile's list. Tiled frames dispatch the tiles
// that some brick touches this way, and the others, where every ray is empty, with a pipeline
// without the brick loop (specialisation constant 110).
#define VXR_BRICK_TILE_SUBSET 4096u
// With TILE_LISTS, instead of TILE_SUBSET: subgroup s of workgroup i takes entry
// pass.x + i * subgroups + s, one 4x2 pixel block of a tile, (tile index, x, y in
// pixels), and marches that tile's list; entries past the image are padding. Only
// where subgroups are 8 invocations: tiled E-A and emission frames on lavapipe
// dispatch the blocks some entry can reach this way (build_tile_lists).
#define VXR_BRICK_BLOCK_SUBSET 8192u
#define VXR_BRICK_OPAQUE 32u      // final pixel over black: alpha 1 (display targets)
#define VXR_BRICK_QUANTIZE 64u    // final pixel rounded to 8 bits, v * 255 + 0.5 (UNORM targets: the one rounding rule)
#define VXR_BRICK_FINAL_FLOAT 128u  // final pixel into the accumulation image (float), for a blit into the target
#define VXR_BRICK_UNDERLAY 256u   // rays end at the underlay's depth (binding 9); its colour (binding 10) goes under the volume
// No rays: workgroup (x, y) classifies the empty-space cells of brick control.z + x for this
// view's settings, which the rays' cell test then reads (one load per cell): for MIP / MinIP
// 64 cells' keys (y * 64 ..) into binding 11, for the other models 64 words of emptiness
// bits (y * 64 ..) into binding 13.
#define VXR_BRICK_CLASSIFY 512u
// Binding 14's declared size (a uniform buffer over the start of this view's
// emptiness bits in binding 13, read where specialisation constant 109 says):
// 4096 uvec4, 64 KiB.
#define VXR_CELL_BITS_WINDOW_WORDS 16384u

// The rays' sample counters (binding 5): VXR_SAMPLE_COUNTERS (lo, hi) pairs
// of uints, VXR_SAMPLE_COUNTER_STRIDE uints (a cache line) apart, summed by
// the host. Each share of a dispatch's workgroups adds to its own: a CPU
// device gives each thread one contiguous share, so the threads' atomics
// do not pull one line back and forth.
#define VXR_SAMPLE_COUNTERS 16u
#define VXR_SAMPLE_COUNTER_STRIDE 16u

// What each sample does (specialisation constant 107, VXR_SC_SAMPLE_WORK):
// the optical model, or for `vxr bench roofline`'s split of an E-A frame's
// time the texture fetch alone or neither. The rays, bricks and walks stay
// the frame's, except that probe rays never terminate (and MIP / MinIP cell
// tests, which read the running value, would walk differently).
#define VXR_SAMPLE_SHADE 0u
#define VXR_SAMPLE_FETCH_ONLY 1u
#define VXR_SAMPLE_MARCH_ONLY 2u

// One brick to march, everything in its own local voxels (level-l voxels,
// origin at the brick's interior corner): the CPU computes these in double,
// so the GPU never sees a large coordinate.
struct BrickRecord {
  vec4 eye;     // xyz: eye position in local voxels
  vec4 scale;   // xyz: local voxels per level-0 voxel along each axis (1 / downsample)
  vec4 box_lo;  // xyz: where marching starts being allowed (0, or the ROI), local voxels;
                // w: 1 where every cell in the box is kept, so its rays march without a cell walk
  vec4 box_hi;  // xyz: the brick's extent clipped to the volume and the ROI;
                // w: 1 where no cell is kept: an average over whole bricks casts its rays, no sample
  vec4 atlas;   // xyz: atlas texel coordinate of the local origin; w: atlas slot (cell ranges), < 0: none
  vec4 plane;   // cut plane in local voxels: keep dot(xyz, p) + w >= 0; xyz = 0: none
};

// Push constants: which bricks or work items a dispatch marches. Everything
// else a ray needs (directions, image size, step, extinction, windows,
// optical model) is RaycastParams (shared/raycast_params.h, uniform buffer,
// binding 7), filled by plan_raycast/pack_params.
struct BrickCastParams {
  uvec4 control;   // xy: output pixel of the ray at (0, 0) (a rectangle of the target); z: first brick, w: brick count (single pass)
  uvec4 pass;      // x: work-item base with VXR_BRICK_WORK_ITEMS, y: empty-space cells per brick axis the rays walk (0: off),
                   // z: flags, w: the pool's cells per axis (cell ranges; y or 2y: a walked cell is 2x2x2 of them)
  vec4 atlas_inv;  // xyz: 1 / atlas size in texels, w: empty-space cell size in voxels
  uvec4 warp;      // lens warp (z > 1): x, y: rays across each outer band along x, y; z: pixels per ray there
  // The rays' own trilinear filter over the atlas's texel view
  // (specialisation constant 115): x, y: row and slice pitch in view elements; z:
  // the last texel along x and y (x | y << 16), w: along z.
  uvec4 texels;
  // x: the view's first brick record as a texel of binding 15 (the brick
  // table as RGBA32F texels, 6 a record), y: its work list's first entry as
  // a texel of binding 18 (specialisation constant 108).
  uvec4 records;
};

#ifdef __cplusplus
static_assert(sizeof(BrickRecord) == 96, "brick record layout");
static_assert(sizeof(BrickCastParams) == 96, "push constants must stay within 128 bytes");
}  // namespace vxr::shader
#endif

#endif
