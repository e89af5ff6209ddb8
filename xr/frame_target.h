// FrameTarget: where rendered views go and where input comes from.
//
// One small interface per axis of variation (hello_xr's shape): the OpenXR
// session (xr/openxr), a desktop window (xr/desktop) and a headless target
// that reads poses from a script and writes PNGs (xr/headless) all answer the
// same questions each frame: which views to render (pose, fov, size), which
// images to render them into, and how to hand them back. The frame loop that
// drives a target, with its outer restart loop, is xr/view_session.h.
#pragma once

#include <vulkan/vulkan.h>

#include <cstdint>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "core/status.h"
#include "gpu/context.h"
#include "render/camera.h"
#include "xr/pose.h"

namespace vxr {
struct RenderSettings;  // scene/render_settings.h (not included: its VolumeTransform is not xr's)
class ChunkCache;
class ChunkSource;
}

namespace vxr::xr {

// One view to render this frame. The pose is in the target's reference space
// (OpenXR STAGE or LOCAL, metres, +y up, the eye looks along -z).
struct ViewSpec {
  Pose pose;
  Fov fov;
  uint32_t width = 0, height = 0;
  // The ray caster's camera (volume frame) when the target knows it exactly:
  // a restored card (headless). It overrides pose, fov and the volume
  // transform, so the view draws what `vxr render --card` draws.
  std::optional<Camera> camera;
};

// An image the target owns (a swapchain image, a window's buffer, a headless
// texture) on the shared VkDevice. It is in `layout` when handed out and must
// be left in `layout` when the frame ends.
struct TargetImage {
  VkImage image = VK_NULL_HANDLE;
  VkFormat format = VK_FORMAT_UNDEFINED;
  VkExtent2D extent{0, 0};
  VkImageLayout layout = VK_IMAGE_LAYOUT_UNDEFINED;
  // A view with STORAGE usage when the target made the image with it: the
  // ray caster then writes RGBA8 UNORM pixels directly (else through a blit).
  VkImageView storage_view = VK_NULL_HANDLE;
};

struct FrameState {
  bool should_render = false;   // false: end the frame without images (session not visible yet)
  bool exit = false;            // the target has ended in order (session exited, window closed)
  int64_t display_time_ns = 0;  // predicted display time (OpenXR) or a steady clock
  std::vector<ViewSpec> views;  // filled when should_render
  InputState input;
  // A target with its own controls (the desktop viewer's panels) says what to
  // draw this frame (settings and timepoint); empty: the session's.
  std::shared_ptr<const RenderSettings> settings;
  uint32_t timepoint = 0;
  // Added to the frame's LOD bias (log2 voxels per pixel): the desktop viewer
  // draws coarser while the user moves the view. 0: as the session says.
  double lod_bias_offset = 0.0;
};

// Semaphores the frame's one submission waits on and signals, for targets
// that record into their own images after the views (a window's swapchain).
struct FrameSubmit {
  std::vector<VkSemaphore> wait;
  std::vector<VkSemaphore> signal;
};

// What the frame showed, for targets that hand depth to a compositor.
struct FrameContent {
  glm::dvec3 focus_point{0.0};  // reference-space point at the volume's centre
};

class FrameTarget {
 public:
  virtual ~FrameTarget() = default;

  // "OpenXR (runtime ..., system ...)", "desktop window 256x128", "headless".
  virtual std::string describe() const = 0;

  // Adds instance/device extensions or creation hooks before the Vulkan
  // context exists (OpenXR creates the instance and device itself).
  virtual Status prepare_context(gpu::ContextOptions& options) {
    (void)options;
    return Status::ok();
  }
  // Creates what needs the device: session, swapchains, window surface.
  virtual Status attach(gpu::Context& ctx) = 0;

  // Polls events and waits for the next frame.
  virtual Result<FrameState> wait_frame() = 0;
  // The image to render view `view` of the current frame into.
  virtual Result<TargetImage> acquire(size_t view) = 0;
  // Records what the target draws after every view into the frame's one
  // command buffer (the desktop window: eyes blitted into the swapchain
  // image, then its panels) and adds the semaphores that submission needs.
  virtual Status record_after_views(VkCommandBuffer cmd, FrameSubmit& submit) {
    (void)cmd, (void)submit;
    return Status::ok();
  }
  // Releases the images and submits or presents the frame.
  virtual Status end_frame(const FrameState& frame, const FrameContent& content) = 0;

  // Starts an orderly stop; wait_frame() reports exit once it is done.
  virtual void request_exit() = 0;
  // After an error: true when rebuilding target and device may recover it
  // (OpenXR session or instance lost).
  virtual bool wants_restart() const { return false; }
  virtual void haptic_pulse(Hand hand, double amplitude, double seconds) {
    (void)hand, (void)amplitude, (void)seconds;
  }
  // Destroys everything tied to the device; called before the context dies.
  virtual void detach() = 0;
  // The chunk cache the renderer streams from (null: gone) and its source;
  // the desktop viewer prefetches the timepoints playback needs next into it.
  virtual void use_chunk_cache(ChunkCache* cache, const ChunkSource* source) { (void)cache, (void)source; }
};

}  // namespace vxr::xr
