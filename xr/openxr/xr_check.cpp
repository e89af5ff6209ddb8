#include "xr/openxr/xr_check.h"

#include <openxr/openxr_reflection.h>

#include <filesystem>

namespace vxr::xr {

const char* xr_result_name(XrResult r) {
  switch (r) {
#define VXR_XR_RESULT_CASE(name, value) \
  case name: return #name;
    XR_LIST_ENUM_XrResult(VXR_XR_RESULT_CASE)
#undef VXR_XR_RESULT_CASE
    default: return "XR_UNKNOWN_RESULT";
  }
}

Status XrErrors::fail(XrResult r, const char* function, const char* file, int line) {
  if (r == XR_ERROR_SESSION_LOST || r == XR_ERROR_INSTANCE_LOST || r == XR_SESSION_LOSS_PENDING) lost_ = true;
  std::string what = std::string("OpenXR: ") + function + " failed with " + xr_result_name(r) + " (" +
                     std::to_string(int(r)) + ") at " + std::filesystem::path(file).filename().string() + ":" +
                     std::to_string(line);
  if (r == XR_ERROR_RUNTIME_UNAVAILABLE)
    what += "; check that an OpenXR runtime is installed and running (XR_RUNTIME_JSON selects one)";
  else if (r == XR_ERROR_FORM_FACTOR_UNAVAILABLE)
    what += "; connect and switch on the headset";
  return Status(r == XR_ERROR_FORM_FACTOR_UNAVAILABLE || r == XR_ERROR_RUNTIME_UNAVAILABLE ? ErrorCode::kUnsupported
                                                                                             : ErrorCode::kGpu,
                what);
}

}  // namespace vxr::xr
