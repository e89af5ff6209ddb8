// Shows what another target (the headset) is shown, in a desktop window:
// wraps the OpenXR target, hands its swapchain images to the renderer
// unchanged, and before each frame is submitted blits them side by side into
// the window (the paper's on-monitor mirror of the HMD view).
#pragma once

#include <memory>

#include "xr/desktop/desktop_target.h"

namespace vxr::xr {

class MirrorTarget : public FrameTarget {
 public:
  MirrorTarget(std::unique_ptr<FrameTarget> inner, std::unique_ptr<DesktopTarget> window)
      : inner_(std::move(inner)), window_(std::move(window)) {}

  std::string describe() const override { return inner_->describe() + ", mirrored to a " + window_->describe(); }
  Status prepare_context(gpu::ContextOptions& options) override;
  Status attach(gpu::Context& ctx) override;
  Result<FrameState> wait_frame() override;
  Result<TargetImage> acquire(size_t view) override;
  Status end_frame(const FrameState& frame, const FrameContent& content) override;
  void request_exit() override { inner_->request_exit(); }
  bool wants_restart() const override { return inner_->wants_restart(); }
  void haptic_pulse(Hand hand, double amplitude, double seconds) override {
    inner_->haptic_pulse(hand, amplitude, seconds);
  }
  void detach() override;

 private:
  std::unique_ptr<FrameTarget> inner_;
  std::unique_ptr<DesktopTarget> window_;
  std::vector<TargetImage> acquired_;
  bool shown_ = false;
};

}  // namespace vxr::xr
