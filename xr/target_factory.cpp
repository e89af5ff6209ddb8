#include "xr/target_factory.h"

namespace vxr::xr {

Result<TargetChoice> choose_target(const TargetRequest& request) {
  TargetChoice c;
  const HeadlessOptions headless = request.headless;
  c.kind = TargetKind::kHeadless;
  c.reason = "using headless";
  c.factory = [headless]() -> Result<std::unique_ptr<FrameTarget>> {
    return std::unique_ptr<FrameTarget>(new HeadlessTarget(headless));
  };
  return c;
}

}  // namespace vxr::xr
