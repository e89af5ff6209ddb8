#include "xr/target_factory.h"

#include "xr/desktop/desktop_target.h"
#include "xr/desktop/mirror_target.h"
#include "xr/openxr/openxr_target.h"

namespace vxr::xr {
namespace {

DesktopOptions desktop_options(const TargetRequest& r) {
  DesktopOptions o;
  o.width = r.headless.script.width;
  o.height = r.headless.script.height;
  o.fov = r.headless.script.fov;
  o.stereo = r.desktop_stereo;
  o.end_frame = r.headless.end_frame;
  o.screenshot_path = r.desktop_screenshot;
  o.viewer = r.viewer;
  return o;
}

TargetFactory openxr_factory(const TargetRequest& r) {
  OpenXrOptions o;
  o.max_eye_width = r.max_eye_width;
  o.max_eye_height = r.max_eye_height;
  const bool mirror = r.mirror;
  o.readable = mirror;
  DesktopOptions window = desktop_options(r);
  window.stereo = true;  // both eyes side by side
  window.srgb_swapchain = true;  // the headset's swapchains are sRGB when the runtime offers it
  window.end_frame = 0;
  window.viewer = nullptr;  // the mirror shows the headset's eyes as they are
  return [o, mirror, window]() -> Result<std::unique_ptr<FrameTarget>> {
    auto t = OpenXrTarget::create(o);
    if (!t) return t.status();
    if (!mirror) return std::unique_ptr<FrameTarget>(std::move(t).value());
    auto w = DesktopTarget::create(window);
    if (!w) return w.status();
    return std::unique_ptr<FrameTarget>(new MirrorTarget(std::move(t).value(), std::move(w).value()));
  };
}

TargetFactory desktop_factory(const TargetRequest& r) {
  const DesktopOptions o = desktop_options(r);
  return [o]() -> Result<std::unique_ptr<FrameTarget>> {
    auto t = DesktopTarget::create(o);
    if (!t) return t.status();
    return std::unique_ptr<FrameTarget>(std::move(t).value());
  };
}

TargetFactory headless_factory(const TargetRequest& r) {
  const HeadlessOptions o = r.headless;
  return [o]() -> Result<std::unique_ptr<FrameTarget>> { return std::unique_ptr<FrameTarget>(new HeadlessTarget(o)); };
}

}  // namespace

Result<TargetChoice> choose_target(const TargetRequest& r) {
  TargetChoice c;
  switch (r.kind) {
    case TargetKind::kOpenXr:
      return TargetChoice{TargetKind::kOpenXr, "using OpenXR (--xr)", openxr_factory(r)};
    case TargetKind::kDesktop: {
      if (Status s = desktop_available(); !s) return s;
      return TargetChoice{TargetKind::kDesktop, "using the desktop window (--desktop)", desktop_factory(r)};
    }
    case TargetKind::kHeadless:
      return TargetChoice{TargetKind::kHeadless, "using headless (--headless)", headless_factory(r)};
    case TargetKind::kAuto: break;
  }
  auto xr = probe_openxr();
  if (xr) return TargetChoice{TargetKind::kOpenXr, "using " + *xr, openxr_factory(r)};
  const std::string no_xr = "no OpenXR headset: " + xr.status().message();
  Status desk = desktop_available();
  if (desk) return TargetChoice{TargetKind::kDesktop, "using the desktop window (" + no_xr + ")", desktop_factory(r)};
  return TargetChoice{TargetKind::kHeadless, "using headless (" + no_xr + "; no desktop: " + desk.message() + ")",
                      headless_factory(r)};
}

}  // namespace vxr::xr
