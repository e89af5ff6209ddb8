// Turning VkResult into Status at the call site, with the expression text.
#pragma once

#include <vulkan/vulkan.h>

#include <string>

#include "core/status.h"

namespace vxr::gpu {

const char* vk_result_name(VkResult r);

}  // namespace vxr::gpu

#define VXR_VK_STRINGIFY_INNER(x) #x
#define VXR_VK_STRINGIFY(x) VXR_VK_STRINGIFY_INNER(x)

// Returns a kGpu Status naming the call, result and file:line when expr fails.
#define VXR_VK_TRY(expr)                                                                     \
  do {                                                                                       \
    VkResult vxr_vk_r_ = (expr);                                                             \
    if (vxr_vk_r_ != VK_SUCCESS)                                                             \
      return ::vxr::gpu_error(std::string(#expr) + " -> " + ::vxr::gpu::vk_result_name(vxr_vk_r_) + \
                              " at " __FILE__ ":" VXR_VK_STRINGIFY(__LINE__));               \
  } while (0)
