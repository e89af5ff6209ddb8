#include "xr/desktop/mirror_target.h"

namespace vxr::xr {

Status MirrorTarget::prepare_context(gpu::ContextOptions& options) {
  VXR_RETURN_IF_ERROR(inner_->prepare_context(options));
  return window_->prepare_context(options);  // surface extensions ride along in the runtime-made instance
}

Status MirrorTarget::attach(gpu::Context& ctx) {
  VXR_RETURN_IF_ERROR(inner_->attach(ctx));
  return window_->attach(ctx);
}

Result<FrameState> MirrorTarget::wait_frame() {
  if (!window_->poll()) inner_->request_exit();  // closing the mirror ends the session in order
  VXR_ASSIGN_OR_RETURN(FrameState f, inner_->wait_frame());
  if (f.exit && shown_) VXR_RETURN_IF_ERROR(window_->screenshot());
  acquired_.assign(f.views.size(), TargetImage{});
  return f;
}

Result<TargetImage> MirrorTarget::acquire(size_t view) {
  VXR_ASSIGN_OR_RETURN(TargetImage img, inner_->acquire(view));
  if (view < acquired_.size()) acquired_[view] = img;
  return img;
}

Status MirrorTarget::end_frame(const FrameState& frame, const FrameContent& content) {
  bool complete = frame.should_render && !acquired_.empty();
  for (const TargetImage& i : acquired_) complete = complete && i.image != VK_NULL_HANDLE;
  // Blit before the inner target releases the images to its compositor.
  if (complete) {
    VXR_RETURN_IF_ERROR(window_->present(acquired_));
    shown_ = true;
  }
  return inner_->end_frame(frame, content);
}

void MirrorTarget::detach() {
  window_->detach();
  inner_->detach();
}

}  // namespace vxr::xr
