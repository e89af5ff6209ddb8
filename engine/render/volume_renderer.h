// VolumeRenderer: what a frame loop (vxr view: OpenXR, desktop, headless;
// tests; PNG output) drives. It RECORDS into the caller's command buffer and
// writes into the caller's image; nothing waits and nothing is read back
// inside a frame. The caller owns submission and pacing:
//
//   wait for the previous frame's fence
//   begin_frame(cmd)                       // bricks that arrived are copied in
//   record_view(cmd, camera, ..., target)  // per eye
//   submit cmd; the next begin_frame waits for it
//
// The out-of-core BrickRenderer (render/lod/brick_renderer.h) implements it;
// a small volume is its one-brick case.
//
// Output format: the target's. 8-bit UNORM targets get round-to-nearest bytes
// (v * 255 + 0.5, clamped: to_rgba8's rule); _SRGB targets get linear values
// that the format encodes; RGBA8_UNORM images with a storage view are written
// by the ray caster directly, every other format through one blit.
#pragma once

#include <vulkan/vulkan.h>

#include <array>
#include <cstdint>

#include "core/status.h"
#include "render/camera.h"
#include "render/lod/lod_traversal.h"
#include "render/raycast_setup.h"
#include "scene/render_settings.h"

namespace vxr {

enum class BrickPassMode { kAuto, kSinglePass, kTiled, kMultipass };
enum class SampleWork { kShade, kFetchOnly, kMarchOnly };  // VXR_SAMPLE_* (shared/brick_params.h)

struct BrickFrameSettings {
  LodSettings lod;
  uint64_t upload_budget_bytes = UINT64_MAX;  // per frame; at least one brick is uploaded
  BrickPassMode mode = BrickPassMode::kAuto;
  // With lod.skip_empty, rays also jump the empty cells inside drawn bricks
  // (BrickCells; same image). Off: brick-level skipping only (measurements).
  bool skip_cells = true;
  // What each sample does: the optical model, or (`vxr bench roofline`'s
  // split of a frame's time) the fetch alone or neither; probes draw no image.
  SampleWork sample_work = SampleWork::kShade;
};

// The settings' clipping (volume fractions, scene/render_settings.h) as the
// traversal's cut plane and ROI in level-0 voxels of a volume `dims` voxels
// large: a fraction f is the voxel point f * dims.
inline void apply_clip(const ClipSettings& clip, const std::array<uint64_t, 3>& dims, LodSettings& lod) {
  const glm::dvec3 d{double(dims[0]), double(dims[1]), double(dims[2])};
  lod.cut.enabled = clip.cut;
  lod.cut.normal = glm::dvec3(clip.cut_normal[0], clip.cut_normal[1], clip.cut_normal[2]) / d;
  lod.cut.offset = clip.cut_offset;
  lod.roi.enabled = clip.roi;
  lod.roi.lo = glm::dvec3(clip.roi_lo[0], clip.roi_lo[1], clip.roi_lo[2]) * d;
  lod.roi.hi = glm::dvec3(clip.roi_hi[0], clip.roi_hi[1], clip.roi_hi[2]) * d;
}

struct BrickFrameStats {
  LodStats lod;
  uint64_t samples = 0;          // texture samples the rays took
  uint64_t bytes_uploaded = 0;
  uint32_t bricks_uploaded = 0;
  uint32_t evicted = 0;
  double hit_rate = 1.0;         // wanted bricks already resident / wanted bricks
  uint32_t dispatches = 0;
  uint32_t classify_passes = 0;  // of those, cell classifications (none where a view's inputs did not change)
  uint32_t bricks_walked = 0;    // drawn bricks whose rays walk empty-space cells (the others keep every cell)
  uint32_t tile_entries = 0;     // tiled frames: brick entries on the tile lists
  uint32_t tile_blocks = 0;      // of the walked bricks' kept-cell blocks, those projected for the tiles' depths
  uint32_t tiles_plain = 0;      // tiled frames: tiles whose bricks all march without a walk (a variant without cell code)
  uint32_t tiles_empty = 0;      // tiled frames: tiles no brick touches (the variant without a brick loop)
  uint32_t groups_marched = 0;   // tiled frames by 4x2 blocks (group_lists): the marched tiles' blocks dispatched; 0: whole tiles
  bool hue_lookups = false;      // the rays looked colours up in the single-hue rows (BrickRendererOptions::hue_tables)
  double traverse_ms = 0.0;      // CPU octree traversal
  double render_ms = 0.0;        // ray-cast submission, wall clock
  double gpu_ms = 0.0;           // BrickRenderer::render: the frame's commands on the GPU (timestamps; 0: none)
};

// One axis of a ray grid denser at the centre (the lens warp, xr/lens_warp.h),
// in pixels: the middle `centre` pixels of the full image get one ray each,
// each outer band of `edge_full` pixels gets one ray per `step` pixels. The
// warp is piecewise linear, so the grid is one view whose rays follow it.
struct WarpAxis {
  uint32_t full = 0;         // output pixels
  uint32_t edge_full = 0;    // output pixels in each outer band
  uint32_t centre = 0;       // output (= warped) pixels in the centre band
  uint32_t edge_warped = 0;  // rays across each outer band
  uint32_t step = 1;
  uint32_t warped() const { return centre + 2 * edge_warped; }
  bool active() const { return edge_warped > 0 && step > 1; }
  // Continuous warped coordinate of continuous output coordinate p (both in
  // pixels, 0 at the first pixel's left edge), and its inverse.
  double to_warped(double p) const {
    const double e = edge_full, s = step;
    if (p < e) return p / s;
    if (p < e + centre) return edge_warped + (p - e);
    return edge_warped + centre + (p - e - centre) / s;
  }
  double from_warped(double q) const {
    const double e = edge_warped, s = step;
    if (q < e) return q * s;
    if (q < e + centre) return edge_full + (q - e);
    return edge_full + centre + (q - e - centre) * s;
  }
};

// No warp: one ray per pixel of `pixels`.
inline WarpAxis identity_warp(uint32_t pixels) { return {pixels, 0, pixels, 0, 1}; }

// What a view's volume is drawn over (AnnotationRenderer::record: markers,
// skeletons, meshes), two images of the view's full size (warp_x.full x
// warp_y.full) in GENERAL layout, written before the volume's commands: rays
// end at `depth` (R32F view depth, world units along the camera's forward
// axis, +inf where nothing is; the samples whose midpoints lie in front of it
// are taken) and `color` (RGBA8, premultiplied) is composited under the
// volume: out = volume + (1 - volume.a) * color, in float, rounded once.
struct ViewUnderlay {
  VkImageView depth = VK_NULL_HANDLE;
  VkImageView color = VK_NULL_HANDLE;
  VkExtent2D extent{0, 0};
  bool present() const { return depth != VK_NULL_HANDLE; }
};

// An image on the renderer's device that a view is drawn into.
struct RenderTarget {
  VkImage image = VK_NULL_HANDLE;
  // A view with STORAGE usage, if the image has one. The image then also
  // needs TRANSFER_DST usage: the brick renderer may clear it.
  VkImageView storage_view = VK_NULL_HANDLE;
  VkFormat format = VK_FORMAT_UNDEFINED;
  VkExtent2D extent{0, 0};
  // The layout the image is in before the recorded commands and is left in
  // after them (UNDEFINED: contents discarded, left in GENERAL).
  VkImageLayout layout = VK_IMAGE_LAYOUT_UNDEFINED;
  VkRect2D rect{{0, 0}, {0, 0}};  // the pixels drawn; extent 0: the whole image
  bool opaque = false;            // composite over black, alpha 1 (display targets)
  // Lens warp (both active, or neither): the rect is the warped grid
  // (warp_x.warped() x warp_y.warped() rays) over the camera's whole frustum.
  WarpAxis warp_x, warp_y;
  ViewUnderlay under;  // none by default
};

// True for the 8-bit UNORM colour formats (the rounding rule applies).
bool is_unorm8(VkFormat format);

class VolumeRenderer {
 public:
  virtual ~VolumeRenderer() = default;

  // Starts a frame recorded into `cmd`. Everything the previous frame's
  // command buffer used may be reused: the caller has waited for it.
  // Streaming renderers record the brick uploads that have arrived here.
  virtual Status begin_frame(VkCommandBuffer cmd, const BrickFrameSettings& frame) = 0;

  // Records one view of `camera` into `target.rect`: the CPU part (LOD
  // traversal, brick lists) runs now, the rays run when `cmd` does. The
  // camera's frustum spans the rectangle. Poses and settings are data: no
  // call for a new pose builds a pipeline.
  virtual Status record_view(VkCommandBuffer cmd, const Camera& camera, const RenderSettings& settings,
                             const BrickFrameSettings& frame, const RenderTarget& target,
                             BrickFrameStats* stats = nullptr) = 0;

  virtual VolumePlacement placement() const = 0;
};

}  // namespace vxr
