#include "xr/headless/headless_target.h"

#include <cstdio>
#include <filesystem>

#include "core/image.h"
#include "xr/volume_transform.h"

namespace vxr::xr {

std::string HeadlessTarget::describe() const {
  return "headless (" + std::string(o_.stereo ? "stereo " : "mono ") + std::to_string(o_.script.width) + "x" +
         std::to_string(o_.script.height) + (o_.png_dir.empty() ? "" : ", PNGs in " + o_.png_dir) + ")";
}

Status HeadlessTarget::attach(gpu::Context& ctx) {
  ctx_ = &ctx;
  images_.clear();
  const int n = o_.stereo ? 2 : 1;
  for (int i = 0; i < n; ++i) {
    VXR_ASSIGN_OR_RETURN(gpu::Image img,
                         gpu::create_image(ctx, {VK_IMAGE_TYPE_2D, VK_FORMAT_R8G8B8A8_UNORM,
                                                 {o_.script.width, o_.script.height, 1},
                                                 VK_IMAGE_USAGE_TRANSFER_DST_BIT | VK_IMAGE_USAGE_TRANSFER_SRC_BIT |
                                                     VK_IMAGE_USAGE_SAMPLED_BIT | VK_IMAGE_USAGE_STORAGE_BIT,
                                                 "headless view"}));
    // Start in GENERAL so every frame hands out the same layout.
    VXR_RETURN_IF_ERROR(ctx.submit_and_wait([&](VkCommandBuffer cmd) {
      gpu::transition_image(cmd, img, VK_IMAGE_LAYOUT_GENERAL, VK_PIPELINE_STAGE_2_NONE, 0,
                            VK_PIPELINE_STAGE_2_ALL_COMMANDS_BIT,
                            VK_ACCESS_2_MEMORY_READ_BIT | VK_ACCESS_2_MEMORY_WRITE_BIT);
    }));
    images_.push_back(std::move(img));
  }
  return Status::ok();
}

Result<FrameState> HeadlessTarget::wait_frame() {
  FrameState f;
  const uint64_t end = o_.end_frame > 0 ? o_.end_frame : o_.script.last_key_frame() + 1;
  if (exit_requested_ || frame_ >= end) {
    if (!o_.png_every_frame && !o_.png_dir.empty() && frame_ > 0) VXR_RETURN_IF_ERROR(write_pngs("last"));
    f.exit = true;
    return f;
  }
  const ScriptFrame s = o_.script.at(frame_);
  f.should_render = true;
  f.display_time_ns = int64_t(frame_) * 11111111;  // 90 Hz
  if (o_.stereo) {
    f.views = stereo_views(s.head, o_.script.ipd_m, o_.script.fov, o_.script.width, o_.script.height);
  } else {
    f.views = {ViewSpec{s.head, o_.script.fov, o_.script.width, o_.script.height}};
  }
  for (ViewSpec& v : f.views) v.camera = o_.camera;
  for (int h = 0; h < 2; ++h) {
    const ScriptHand& sh = s.hands[h];
    HandInput& in = f.input.hands[h];
    in.tracked = sh.tracked;
    in.grip = sh.grip;
    in.aim = sh.aim;
    in.grab = sh.squeeze;
    in.trigger = sh.trigger;
    in.thumbstick = sh.thumbstick;
    in.menu = sh.menu;
    in.stick_click = sh.thumbstick_click;  // as an Oculus Touch pair (xr/script.h)
    in.primary = sh.a;
    in.secondary = sh.b;
  }
  return f;
}

Result<TargetImage> HeadlessTarget::acquire(size_t view) {
  if (view >= images_.size()) return out_of_range("headless target has " + std::to_string(images_.size()) + " views");
  const gpu::Image& img = images_[view];
  return TargetImage{img.image, img.format, {img.extent.width, img.extent.height}, VK_IMAGE_LAYOUT_GENERAL,
                     img.view};
}

Status HeadlessTarget::write_pngs(const std::string& tag) {
  std::error_code ec;
  std::filesystem::create_directories(o_.png_dir, ec);
  for (size_t v = 0; v < images_.size(); ++v) {
    ImageRgba8 img(images_[v].extent.width, images_[v].extent.height);
    images_[v].layout = VK_IMAGE_LAYOUT_GENERAL;
    VXR_RETURN_IF_ERROR(readback_.read(*ctx_, images_[v], img.pixels.data(), img.pixels.size()));
    const char* eye = images_.size() == 1 ? "view" : (v == 0 ? "left" : "right");
    const std::string path = (std::filesystem::path(o_.png_dir) / (tag + "_" + eye + ".png")).string();
    VXR_RETURN_IF_ERROR(write_png(path, img));
  }
  return Status::ok();
}

Status HeadlessTarget::end_frame(const FrameState& frame, const FrameContent&) {
  if (frame.should_render && o_.png_every_frame && !o_.png_dir.empty()) {
    char tag[32];
    std::snprintf(tag, sizeof tag, "frame%06llu", static_cast<unsigned long long>(frame_));
    VXR_RETURN_IF_ERROR(write_pngs(tag));
  }
  ++frame_;
  return Status::ok();
}

}  // namespace vxr::xr
