// Move-only owner of one Vulkan object created from a VkDevice.
//
// Handle<VkBuffer> owns the buffer and destroys it with vkDestroyBuffer when it
// goes out of scope; nothing in vxr destroys Vulkan objects by hand.
#pragma once

#include <vulkan/vulkan.h>

#include <utility>

namespace vxr::gpu {

template <typename T>
struct Destroyer;

#define VXR_GPU_DESTROYER(Type, fn)                                             \
  template <>                                                                   \
  struct Destroyer<Type> {                                                      \
    static void destroy(VkDevice d, Type h) { fn(d, h, nullptr); }              \
  }

VXR_GPU_DESTROYER(VkBuffer, vkDestroyBuffer);
VXR_GPU_DESTROYER(VkBufferView, vkDestroyBufferView);
VXR_GPU_DESTROYER(VkImage, vkDestroyImage);
VXR_GPU_DESTROYER(VkImageView, vkDestroyImageView);
VXR_GPU_DESTROYER(VkSampler, vkDestroySampler);
VXR_GPU_DESTROYER(VkDeviceMemory, vkFreeMemory);
VXR_GPU_DESTROYER(VkShaderModule, vkDestroyShaderModule);
VXR_GPU_DESTROYER(VkPipeline, vkDestroyPipeline);
VXR_GPU_DESTROYER(VkPipelineLayout, vkDestroyPipelineLayout);
VXR_GPU_DESTROYER(VkDescriptorSetLayout, vkDestroyDescriptorSetLayout);
VXR_GPU_DESTROYER(VkDescriptorPool, vkDestroyDescriptorPool);
VXR_GPU_DESTROYER(VkCommandPool, vkDestroyCommandPool);
VXR_GPU_DESTROYER(VkFence, vkDestroyFence);
VXR_GPU_DESTROYER(VkSemaphore, vkDestroySemaphore);
VXR_GPU_DESTROYER(VkQueryPool, vkDestroyQueryPool);
VXR_GPU_DESTROYER(VkRenderPass, vkDestroyRenderPass);
VXR_GPU_DESTROYER(VkFramebuffer, vkDestroyFramebuffer);
VXR_GPU_DESTROYER(VkPipelineCache, vkDestroyPipelineCache);

#undef VXR_GPU_DESTROYER

template <typename T>
class Handle {
 public:
  Handle() = default;
  Handle(VkDevice device, T handle) : device_(device), handle_(handle) {}
  ~Handle() { reset(); }

  Handle(Handle&& o) noexcept : device_(o.device_), handle_(std::exchange(o.handle_, VK_NULL_HANDLE)) {}
  Handle& operator=(Handle&& o) noexcept {
    if (this != &o) {
      reset();
      device_ = o.device_;
      handle_ = std::exchange(o.handle_, VK_NULL_HANDLE);
    }
    return *this;
  }
  Handle(const Handle&) = delete;
  Handle& operator=(const Handle&) = delete;

  T get() const { return handle_; }
  operator T() const { return handle_; }  // NOLINT: handles pass straight into vk* calls
  explicit operator bool() const { return handle_ != VK_NULL_HANDLE; }

  void reset() {
    if (handle_ != VK_NULL_HANDLE) Destroyer<T>::destroy(device_, handle_);
    handle_ = VK_NULL_HANDLE;
  }

 private:
  VkDevice device_ = VK_NULL_HANDLE;
  T handle_ = VK_NULL_HANDLE;
};

}  // namespace vxr::gpu
