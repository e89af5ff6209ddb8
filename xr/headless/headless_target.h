// A target with no display: views come from a pose script (or a fixed head
// pose), images are textures on the device, and each finished frame can be
// written as PNGs. Used by tests, benchmarks and movie export.
#pragma once

#include <memory>
#include <string>

#include "gpu/resources.h"
#include "xr/frame_target.h"
#include "xr/script.h"

namespace vxr::xr {

struct HeadlessOptions {
  Script script;            // poses, controller input, view size and fov
  bool stereo = true;       // two eyes, else one view from the head
  std::string png_dir;      // empty: no PNGs
  bool png_every_frame = false;  // else only the last frame before exit
  uint64_t end_frame = 0;   // stop after this many frames; 0: after the script's last key + 1
  // Every view drawn with this camera (volume frame; ViewSpec::camera), e.g.
  // a restored card's, instead of the script's poses.
  std::optional<Camera> camera;
};

class HeadlessTarget : public FrameTarget {
 public:
  explicit HeadlessTarget(HeadlessOptions options) : o_(std::move(options)) {}
  std::string describe() const override;
  Status attach(gpu::Context& ctx) override;
  Result<FrameState> wait_frame() override;
  Result<TargetImage> acquire(size_t view) override;
  Status end_frame(const FrameState& frame, const FrameContent& content) override;
  void request_exit() override { exit_requested_ = true; }
  void detach() override {
    images_.clear();
    readback_ = {};
  }

 private:
  Status write_pngs(const std::string& tag);
  HeadlessOptions o_;
  gpu::Context* ctx_ = nullptr;
  std::vector<gpu::Image> images_;
  gpu::ImageReadback readback_;  // write_pngs()' staging, kept between frames
  uint64_t frame_ = 0;
  bool exit_requested_ = false;
};

}  // namespace vxr::xr
