// The OpenXR FrameTarget: any OpenXR runtime (a headset's, or the test
// runtime in xr/test_runtime) through the Khronos loader.
//
// XR_KHR_vulkan_enable2: the runtime creates (or approves) our Vulkan instance
// and device through gpu::CreationHooks. PRIMARY_STEREO view configuration,
// one colour swapchain per eye, and a depth swapchain per eye handed over with
// XR_KHR_composition_layer_depth when the runtime offers it. STAGE reference
// space, LOCAL when there is no STAGE. The session state machine (IDLE, READY,
// SYNCHRONIZED, VISIBLE, FOCUSED, STOPPING, LOSS_PENDING, EXITING) is driven
// from wait_frame(); a lost session or instance makes wants_restart() true and
// the caller's restart loop rebuilds target and device.
//
// Ownership: the target owns the XrInstance (destroyed last, in the
// destructor) and, between attach() and detach(), the session, spaces and
// swapchains. The swapchain VkImages belong to the runtime.
#pragma once

#include <memory>
#include <string>
#include <vector>

#include "xr/frame_target.h"
#include "xr/openxr/actions.h"
#include "xr/openxr/xr_check.h"

namespace vxr::xr {

struct OpenXrOptions {
  uint32_t max_eye_width = 0, max_eye_height = 0;  // clamp the runtime's recommended size; 0: no clamp
  bool use_depth = true;                           // depth swapchains when the runtime offers them
  bool readable = false;                           // colour images may be copied from (desktop mirror)
};

class OpenXrTarget : public FrameTarget {
 public:
  // Creates the instance and finds the head-mounted system; fails (with what
  // is missing) when no runtime or no headset answers.
  static Result<std::unique_ptr<OpenXrTarget>> create(const OpenXrOptions& options);
  ~OpenXrTarget() override;

  std::string describe() const override;
  Status prepare_context(gpu::ContextOptions& options) override;
  Status attach(gpu::Context& ctx) override;
  Result<FrameState> wait_frame() override;
  Result<TargetImage> acquire(size_t view) override;
  Status end_frame(const FrameState& frame, const FrameContent& content) override;
  void request_exit() override;
  bool wants_restart() const override { return errors_.lost(); }
  void haptic_pulse(Hand hand, double amplitude, double seconds) override;
  void detach() override;

  XrSessionState state() const { return state_; }
  bool has_depth() const { return depth_enabled_; }
  XrReferenceSpaceType space_type() const { return space_type_; }

 private:
  struct Swapchain {
    XrSwapchain handle = XR_NULL_HANDLE;
    VkFormat format = VK_FORMAT_UNDEFINED;
    uint32_t width = 0, height = 0;
    std::vector<VkImage> images;
    uint32_t acquired = UINT32_MAX;  // index acquired this frame
  };

  explicit OpenXrTarget(const OpenXrOptions& o) : o_(o) {}
  Status init_instance();
  Status create_swapchains();
  Status handle_event(const XrEventDataBuffer& event);
  Status poll_events();
  Status clear_depth(Swapchain& sc, const ViewSpec& view, const glm::dvec3& focus);
  template <typename T>
  T proc(const char* name);

  OpenXrOptions o_;
  XrErrors errors_;
  XrInstance instance_ = XR_NULL_HANDLE;
  XrSystemId system_ = XR_NULL_SYSTEM_ID;
  std::string runtime_name_, system_name_;
  bool depth_extension_ = false;
  bool depth_enabled_ = false;
  XrActions actions_;
  bool actions_created_ = false;

  gpu::Context* ctx_ = nullptr;
  XrSession session_ = XR_NULL_HANDLE;
  XrSpace space_ = XR_NULL_HANDLE;
  XrReferenceSpaceType space_type_ = XR_REFERENCE_SPACE_TYPE_STAGE;
  XrSessionState state_ = XR_SESSION_STATE_UNKNOWN;
  bool running_ = false;
  bool exit_ = false;
  bool exit_requested_ = false;
  std::vector<XrViewConfigurationView> config_views_;
  std::vector<Swapchain> color_, depth_;
  XrFrameState frame_state_{XR_TYPE_FRAME_STATE};
  bool frame_begun_ = false;
  std::vector<XrView> views_;
  std::string profile_;
};

// Whether an OpenXR runtime with a head-mounted display answers; the error
// says what is missing. Creates and destroys an instance.
Result<std::string> probe_openxr();

}  // namespace vxr::xr
