// The Vulkan instance, the chosen device and its one queue.
//
// Device choice: discrete GPU, then integrated, then virtual, then CPU
// (lavapipe); VXR_DEVICE=<substring of the device name> overrides. Validation
// (VK_LAYER_KHRONOS_validation with synchronization validation) is on when
// VXR_VALIDATION=1; every warning or error it reports is counted and logged,
// and tests fail when the count is not zero.
#pragma once

#include <vulkan/vulkan.h>

#include <atomic>
#include <cstdint>
#include <functional>
#include <memory>
#include <string>
#include <vector>

#include "core/status.h"
#include "gpu/handle.h"

namespace vxr::gpu {

// Hooks that let OpenXR (XR_KHR_vulkan_enable2) create the instance and device:
// the runtime gets our create-infos and may add what it needs.
struct CreationHooks {
  std::function<Result<VkInstance>(const VkInstanceCreateInfo&)> create_instance;
  std::function<Result<VkPhysicalDevice>(VkInstance)> pick_physical_device;
  std::function<Result<VkDevice>(VkPhysicalDevice, const VkDeviceCreateInfo&)> create_device;
};

struct ContextOptions {
  bool validation = false;          // default: VXR_VALIDATION=1
  std::string device_filter;        // default: VXR_DEVICE
  std::vector<const char*> instance_extensions;
  std::vector<const char*> device_extensions;
  CreationHooks hooks;              // empty: we create everything ourselves
  static ContextOptions from_env();
};

struct DeviceInfo {
  std::string name;         // "llvmpipe (LLVM 15.0.6, 256 bits)"
  std::string driver_name;  // "llvmpipe"
  std::string driver_info;  // "Mesa 22.3.6 (LLVM 15.0.6)"
  uint32_t api_version = 0;
  VkPhysicalDeviceType type = VK_PHYSICAL_DEVICE_TYPE_OTHER;
  uint32_t subgroup_size = 0;  // the default subgroup size (lavapipe: its SIMD width in 32-bit lanes)
  bool is_cpu() const { return type == VK_PHYSICAL_DEVICE_TYPE_CPU; }
  // "Vulkan 1.3.230"
  std::string api_string() const;
  // Identifies everything that decides rounding (driver, version, CPU width,
  // relevant env); golden images are exact only when this matches.
  std::string fingerprint() const;
};

// Total validation warnings and errors reported in this process.
uint64_t validation_message_count();
// The first reported message (empty when none): tests print it on failure.
std::string first_validation_message();
// Tests that provoke a message on purpose reset the counter afterwards.
void reset_validation_messages();

class Context {
 public:
  static Result<std::unique_ptr<Context>> create(const ContextOptions& options);
  ~Context();
  Context(const Context&) = delete;
  Context& operator=(const Context&) = delete;

  VkInstance instance() const { return instance_; }
  VkPhysicalDevice physical_device() const { return physical_device_; }
  VkDevice device() const { return device_; }
  VkQueue queue() const { return queue_; }
  uint32_t queue_family() const { return queue_family_; }
  const DeviceInfo& info() const { return info_; }
  const VkPhysicalDeviceLimits& limits() const { return properties_.limits; }
  bool validation_enabled() const { return validation_; }
  // Nanoseconds per timestamp tick; 0 when the queue has no timestamps.
  double timestamp_period_ns() const { return timestamp_period_ns_; }

  // Index of a memory type allowed by type_bits with all of `required`;
  // prefers one that also has `preferred`. Fails if none exists.
  Result<uint32_t> find_memory_type(uint32_t type_bits, VkMemoryPropertyFlags required,
                                    VkMemoryPropertyFlags preferred = 0) const;

  // Records commands with `record` into a one-time command buffer, submits it
  // and waits for it to finish.
  Status submit_and_wait(const std::function<void(VkCommandBuffer)>& record);

  // Every pipeline is created through this cache, loaded from disk at
  // create() and written back when the context dies (gpu/pipeline_cache.h).
  VkPipelineCache pipeline_cache() const { return pipeline_cache_; }
  // Pipelines created on this context so far (the pipeline helpers count);
  // a frame loop checks that poses never add one.
  uint64_t pipelines_built() const { return pipelines_built_.load(); }
  void count_pipeline_built() const { ++pipelines_built_; }

 private:
  Context() = default;
  Status init(const ContextOptions& options);
  Status pick_device(const ContextOptions& options);

  bool validation_ = false;
  bool own_instance_ = true;
  VkInstance instance_ = VK_NULL_HANDLE;
  VkDebugUtilsMessengerEXT messenger_ = VK_NULL_HANDLE;
  VkPhysicalDevice physical_device_ = VK_NULL_HANDLE;
  VkPhysicalDeviceProperties properties_{};
  VkPhysicalDeviceMemoryProperties memory_properties_{};
  VkDevice device_ = VK_NULL_HANDLE;
  uint32_t queue_family_ = 0;
  VkQueue queue_ = VK_NULL_HANDLE;
  double timestamp_period_ns_ = 0.0;
  DeviceInfo info_;
  Handle<VkCommandPool> command_pool_;
  Handle<VkFence> fence_;
  VkPipelineCache pipeline_cache_ = VK_NULL_HANDLE;
  std::string pipeline_cache_path_;
  mutable std::atomic<uint64_t> pipelines_built_{0};
};

}  // namespace vxr::gpu
