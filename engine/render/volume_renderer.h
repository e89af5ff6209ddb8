// VolumeRenderer: what a frame loop (vxr view: OpenXR, desktop, headless;
// tests; PNG output) drives. It RECORDS into the caller's command buffer and
// writes into the caller's image; nothing waits and nothing is read back
// inside a frame. The caller owns submission and pacing:
//
//   wait for the previous frame's fence
//   begin_frame(cmd)                       // bricks that arrived are copied in
//   record_view(cmd, camera, ..., target)  // per eye (or lens-warp tile)
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

#include <cstdint>

#include "core/status.h"
#include "render/camera.h"
#include "render/lod/lod_traversal.h"
#include "render/raycast_setup.h"
#include "scene/render_settings.h"

namespace vxr {

enum class BrickPassMode { kAuto, kSinglePass, kTiled, kMultipass };

struct BrickFrameSettings {
  LodSettings lod;
  uint64_t upload_budget_bytes = UINT64_MAX;  // per frame; at least one brick is uploaded
  BrickPassMode mode = BrickPassMode::kAuto;
  // With lod.skip_empty, rays also jump the empty cells inside drawn bricks
  // (BrickCells; same image). Off: brick-level skipping only (measurements).
  bool skip_cells = true;
};

struct BrickFrameStats {
  LodStats lod;
  uint64_t samples = 0;          // texture samples the rays took
  uint64_t bytes_uploaded = 0;
  uint32_t bricks_uploaded = 0;
  uint32_t evicted = 0;
  double hit_rate = 1.0;         // wanted bricks already resident / wanted bricks
  uint32_t dispatches = 0;
  double traverse_ms = 0.0;      // CPU octree traversal
  double render_ms = 0.0;        // ray-cast submission, wall clock
  double gpu_ms = 0.0;           // BrickRenderer::render: the frame's commands on the GPU (timestamps; 0: none)
};

// An image on the renderer's device that a view is drawn into.
struct RenderTarget {
  VkImage image = VK_NULL_HANDLE;
  VkImageView storage_view = VK_NULL_HANDLE;  // a view with STORAGE usage, if the image has one
  VkFormat format = VK_FORMAT_UNDEFINED;
  VkExtent2D extent{0, 0};
  // The layout the image is in before the recorded commands and is left in
  // after them (UNDEFINED: contents discarded, left in GENERAL).
  VkImageLayout layout = VK_IMAGE_LAYOUT_UNDEFINED;
  VkRect2D rect{{0, 0}, {0, 0}};  // the pixels drawn; extent 0: the whole image
  bool opaque = false;            // composite over black, alpha 1 (display targets)
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
