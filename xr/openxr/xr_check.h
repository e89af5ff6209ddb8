// OpenXR error handling (hello_xr's CHECK_XRCMD, as values): every xr* call
// goes through VXR_XR_CALL, which turns a failure into a Status naming the
// function, the XrResult and the source line, and remembers whether the
// session or instance was lost (the restart loop's cue).
#pragma once

#define XR_USE_GRAPHICS_API_VULKAN
#include <vulkan/vulkan.h>
#include <openxr/openxr.h>
#include <openxr/openxr_platform.h>

#include <string>

#include "core/status.h"

namespace vxr::xr {

// "XR_ERROR_SESSION_LOST", or the number for codes this header does not know.
const char* xr_result_name(XrResult r);

class XrErrors {
 public:
  Status fail(XrResult r, const char* function, const char* file, int line);
  // The session or instance is gone: rebuilding may recover.
  bool lost() const { return lost_; }
  void mark_lost() { lost_ = true; }

 private:
  bool lost_ = false;
};

}  // namespace vxr::xr

// Calls fn args; on failure (or XR_SESSION_LOSS_PENDING) returns the Status.
#define VXR_XR_CALL(errors, fn, args)                                                     \
  do {                                                                                    \
    const XrResult vxr_xr_r_ = fn args;                                                   \
    if (XR_FAILED(vxr_xr_r_) || vxr_xr_r_ == XR_SESSION_LOSS_PENDING)                     \
      return (errors).fail(vxr_xr_r_, #fn, __FILE__, __LINE__);                           \
  } while (0)
