#include "gpu/context.h"

#include <dlfcn.h>

#include <algorithm>
#include <atomic>
#include <cstdlib>
#include <cstring>
#include <mutex>

#include "core/log.h"
#include "gpu/pipeline_cache.h"
#include "gpu/vk_check.h"

namespace vxr::gpu {
namespace {

#if defined(__SANITIZE_ADDRESS__)
// LeakSanitizer reports at exit, when the Vulkan loader has already dlclosed
// the driver and the validation layer: their allocations would show up as
// "<unknown module>" and no suppression (tests/lsan.supp) could tell them from
// ours. Pinning them (RTLD_NODELETE) keeps them nameable. Sanitizer builds only.
void pin_vulkan_modules_for_leak_reports() {
  static const bool pinned = [] {
    for (const char* lib : {"libvulkan_lvp.so", "libVkLayer_khronos_validation.so", "libvulkan_radeon.so",
                            "libvulkan_intel.so"})
      (void)::dlopen(lib, RTLD_NOW | RTLD_NODELETE | RTLD_GLOBAL);
    return true;
  }();
  (void)pinned;
}
#else
void pin_vulkan_modules_for_leak_reports() {}
#endif

std::atomic<uint64_t> g_validation_messages{0};
std::mutex g_first_mutex;
std::string g_first_message;

VKAPI_ATTR VkBool32 VKAPI_CALL on_validation_message(VkDebugUtilsMessageSeverityFlagBitsEXT severity,
                                                     VkDebugUtilsMessageTypeFlagsEXT,
                                                     const VkDebugUtilsMessengerCallbackDataEXT* data,
                                                     void*) {
  if (severity < VK_DEBUG_UTILS_MESSAGE_SEVERITY_WARNING_BIT_EXT) return VK_FALSE;
  const std::string text = data && data->pMessage ? data->pMessage : "(no message)";
  ++g_validation_messages;
  {
    std::lock_guard<std::mutex> lock(g_first_mutex);
    if (g_first_message.empty()) g_first_message = text;
  }
  log_error("Vulkan validation: " + text);
  return VK_FALSE;
}

bool has_layer(const char* name) {
  uint32_t n = 0;
  vkEnumerateInstanceLayerProperties(&n, nullptr);
  std::vector<VkLayerProperties> layers(n);
  vkEnumerateInstanceLayerProperties(&n, layers.data());
  for (const auto& l : layers)
    if (!std::strcmp(l.layerName, name)) return true;
  return false;
}

int type_rank(VkPhysicalDeviceType t) {
  switch (t) {
    case VK_PHYSICAL_DEVICE_TYPE_DISCRETE_GPU: return 0;
    case VK_PHYSICAL_DEVICE_TYPE_INTEGRATED_GPU: return 1;
    case VK_PHYSICAL_DEVICE_TYPE_VIRTUAL_GPU: return 2;
    case VK_PHYSICAL_DEVICE_TYPE_CPU: return 3;
    default: return 4;
  }
}

std::string lower(std::string s) {
  for (char& c : s) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
  return s;
}

}  // namespace

uint64_t validation_message_count() { return g_validation_messages.load(); }
std::string first_validation_message() {
  std::lock_guard<std::mutex> lock(g_first_mutex);
  return g_first_message;
}
void reset_validation_messages() {
  g_validation_messages = 0;
  std::lock_guard<std::mutex> lock(g_first_mutex);
  g_first_message.clear();
}

std::string DeviceInfo::api_string() const {
  return "Vulkan " + std::to_string(VK_API_VERSION_MAJOR(api_version)) + "." +
         std::to_string(VK_API_VERSION_MINOR(api_version)) + "." +
         std::to_string(VK_API_VERSION_PATCH(api_version));
}

std::string DeviceInfo::fingerprint() const {
  std::string fp = name + " | " + driver_info;
  if (const char* perf = std::getenv("GALLIVM_PERF")) fp += std::string(" | GALLIVM_PERF=") + perf;
  return fp;
}

ContextOptions ContextOptions::from_env() {
  ContextOptions o;
  if (const char* v = std::getenv("VXR_VALIDATION")) o.validation = v[0] == '1';
  if (const char* d = std::getenv("VXR_DEVICE")) o.device_filter = d;
  return o;
}

Result<std::unique_ptr<Context>> Context::create(const ContextOptions& options) {
  std::unique_ptr<Context> ctx(new Context());
  Status s = ctx->init(options);
  if (!s.is_ok()) return s;
  return ctx;
}

Status Context::init(const ContextOptions& options) {
  pin_vulkan_modules_for_leak_reports();
  // The loader and lavapipe want a runtime dir; CI machines may not set one.
  if (!std::getenv("XDG_RUNTIME_DIR")) setenv("XDG_RUNTIME_DIR", "/tmp", 0);

  validation_ = options.validation;
  if (validation_ && !has_layer("VK_LAYER_KHRONOS_validation"))
    return unsupported(
        "VXR_VALIDATION=1 but VK_LAYER_KHRONOS_validation is not installed (apt-get install "
        "vulkan-validationlayers)");

  VkApplicationInfo app{VK_STRUCTURE_TYPE_APPLICATION_INFO};
  app.pApplicationName = "vxr";
  app.apiVersion = VK_API_VERSION_1_3;

  std::vector<const char*> extensions = options.instance_extensions;
  std::vector<const char*> layers;
  VkValidationFeaturesEXT features{VK_STRUCTURE_TYPE_VALIDATION_FEATURES_EXT};
  const VkValidationFeatureEnableEXT enables[] = {VK_VALIDATION_FEATURE_ENABLE_SYNCHRONIZATION_VALIDATION_EXT};
  VkDebugUtilsMessengerCreateInfoEXT messenger_info{VK_STRUCTURE_TYPE_DEBUG_UTILS_MESSENGER_CREATE_INFO_EXT};
  messenger_info.messageSeverity =
      VK_DEBUG_UTILS_MESSAGE_SEVERITY_WARNING_BIT_EXT | VK_DEBUG_UTILS_MESSAGE_SEVERITY_ERROR_BIT_EXT;
  messenger_info.messageType = VK_DEBUG_UTILS_MESSAGE_TYPE_GENERAL_BIT_EXT |
                               VK_DEBUG_UTILS_MESSAGE_TYPE_VALIDATION_BIT_EXT |
                               VK_DEBUG_UTILS_MESSAGE_TYPE_PERFORMANCE_BIT_EXT;
  messenger_info.pfnUserCallback = on_validation_message;

  VkInstanceCreateInfo ici{VK_STRUCTURE_TYPE_INSTANCE_CREATE_INFO};
  ici.pApplicationInfo = &app;
  if (validation_) {
    layers.push_back("VK_LAYER_KHRONOS_validation");
    extensions.push_back(VK_EXT_DEBUG_UTILS_EXTENSION_NAME);
    features.enabledValidationFeatureCount = 1;
    features.pEnabledValidationFeatures = enables;
    // The messenger in pNext also catches messages from instance creation itself.
    features.pNext = &messenger_info;
    ici.pNext = &features;
  }
  ici.enabledLayerCount = static_cast<uint32_t>(layers.size());
  ici.ppEnabledLayerNames = layers.data();
  ici.enabledExtensionCount = static_cast<uint32_t>(extensions.size());
  ici.ppEnabledExtensionNames = extensions.data();

  if (options.hooks.create_instance) {
    auto inst = options.hooks.create_instance(ici);
    if (!inst) return inst.status();
    instance_ = *inst;
  } else {
    VXR_VK_TRY(vkCreateInstance(&ici, nullptr, &instance_));
  }

  if (validation_) {
    auto create_messenger = reinterpret_cast<PFN_vkCreateDebugUtilsMessengerEXT>(
        vkGetInstanceProcAddr(instance_, "vkCreateDebugUtilsMessengerEXT"));
    if (!create_messenger) return gpu_error("vkCreateDebugUtilsMessengerEXT is missing");
    VXR_VK_TRY(create_messenger(instance_, &messenger_info, nullptr, &messenger_));
  }

  if (options.hooks.pick_physical_device) {
    auto pd = options.hooks.pick_physical_device(instance_);
    if (!pd) return pd.status();
    physical_device_ = *pd;
  } else {
    VXR_RETURN_IF_ERROR(pick_device(options));
  }

  vkGetPhysicalDeviceProperties(physical_device_, &properties_);
  vkGetPhysicalDeviceMemoryProperties(physical_device_, &memory_properties_);
  if (properties_.apiVersion < VK_API_VERSION_1_3)
    return unsupported(std::string(properties_.deviceName) + " supports only Vulkan " +
                       std::to_string(VK_API_VERSION_MAJOR(properties_.apiVersion)) + "." +
                       std::to_string(VK_API_VERSION_MINOR(properties_.apiVersion)) +
                       "; vxr needs Vulkan 1.3 (update the GPU driver)");

  VkPhysicalDeviceDriverProperties driver{VK_STRUCTURE_TYPE_PHYSICAL_DEVICE_DRIVER_PROPERTIES};
  VkPhysicalDeviceVulkan11Properties v11{VK_STRUCTURE_TYPE_PHYSICAL_DEVICE_VULKAN_1_1_PROPERTIES};
  driver.pNext = &v11;
  VkPhysicalDeviceProperties2 props2{VK_STRUCTURE_TYPE_PHYSICAL_DEVICE_PROPERTIES_2};
  props2.pNext = &driver;
  vkGetPhysicalDeviceProperties2(physical_device_, &props2);
  info_.name = properties_.deviceName;
  info_.driver_name = driver.driverName;
  info_.driver_info = driver.driverInfo;
  info_.api_version = properties_.apiVersion;
  info_.type = properties_.deviceType;
  info_.subgroup_size = v11.subgroupSize;

  // One queue that does graphics and compute (every desktop GPU and lavapipe has it).
  uint32_t nfam = 0;
  vkGetPhysicalDeviceQueueFamilyProperties(physical_device_, &nfam, nullptr);
  std::vector<VkQueueFamilyProperties> families(nfam);
  vkGetPhysicalDeviceQueueFamilyProperties(physical_device_, &nfam, families.data());
  bool found = false;
  for (uint32_t i = 0; i < nfam; ++i) {
    if ((families[i].queueFlags & VK_QUEUE_GRAPHICS_BIT) && (families[i].queueFlags & VK_QUEUE_COMPUTE_BIT)) {
      queue_family_ = i;
      found = true;
      if (families[i].timestampValidBits > 0)
        timestamp_period_ns_ = static_cast<double>(properties_.limits.timestampPeriod);
      break;
    }
  }
  if (!found) return unsupported(info_.name + " has no queue with graphics and compute");

  const float priority = 1.0f;
  VkDeviceQueueCreateInfo qci{VK_STRUCTURE_TYPE_DEVICE_QUEUE_CREATE_INFO};
  qci.queueFamilyIndex = queue_family_;
  qci.queueCount = 1;
  qci.pQueuePriorities = &priority;

  VkPhysicalDeviceVulkan13Features f13{VK_STRUCTURE_TYPE_PHYSICAL_DEVICE_VULKAN_1_3_FEATURES};
  f13.synchronization2 = VK_TRUE;
  f13.dynamicRendering = VK_TRUE;
  f13.maintenance4 = VK_TRUE;  // SPIR-V 1.6 from glslang uses LocalSizeId
  VkPhysicalDeviceVulkan12Features f12{VK_STRUCTURE_TYPE_PHYSICAL_DEVICE_VULKAN_1_2_FEATURES};
  f12.hostQueryReset = VK_TRUE;
  f12.pNext = &f13;
  VkPhysicalDeviceFeatures2 f2{VK_STRUCTURE_TYPE_PHYSICAL_DEVICE_FEATURES_2};
  f2.pNext = &f12;

  VkDeviceCreateInfo dci{VK_STRUCTURE_TYPE_DEVICE_CREATE_INFO};
  dci.pNext = &f2;
  dci.queueCreateInfoCount = 1;
  dci.pQueueCreateInfos = &qci;
  dci.enabledExtensionCount = static_cast<uint32_t>(options.device_extensions.size());
  dci.ppEnabledExtensionNames = options.device_extensions.data();
  if (options.hooks.create_device) {
    auto dev = options.hooks.create_device(physical_device_, dci);
    if (!dev) return dev.status();
    device_ = *dev;
  } else {
    VXR_VK_TRY(vkCreateDevice(physical_device_, &dci, nullptr, &device_));
  }
  vkGetDeviceQueue(device_, queue_family_, 0, &queue_);

  VkCommandPoolCreateInfo pci{VK_STRUCTURE_TYPE_COMMAND_POOL_CREATE_INFO};
  pci.flags = VK_COMMAND_POOL_CREATE_RESET_COMMAND_BUFFER_BIT | VK_COMMAND_POOL_CREATE_TRANSIENT_BIT;
  pci.queueFamilyIndex = queue_family_;
  VkCommandPool pool = VK_NULL_HANDLE;
  VXR_VK_TRY(vkCreateCommandPool(device_, &pci, nullptr, &pool));
  command_pool_ = Handle<VkCommandPool>(device_, pool);

  VkFenceCreateInfo fci{VK_STRUCTURE_TYPE_FENCE_CREATE_INFO};
  VkFence fence = VK_NULL_HANDLE;
  VXR_VK_TRY(vkCreateFence(device_, &fci, nullptr, &fence));
  fence_ = Handle<VkFence>(device_, fence);

  pipeline_cache_path_ = pipeline_cache_path();
  std::vector<uint8_t> seed;
  if (!pipeline_cache_path_.empty()) {
    auto data = read_pipeline_cache(pipeline_cache_path_, properties_);
    if (data) seed = std::move(data).value();
    else if (data.status().code() != ErrorCode::kNotFound) log_warn(data.status().message());
  }
  VkPipelineCacheCreateInfo pcci{VK_STRUCTURE_TYPE_PIPELINE_CACHE_CREATE_INFO};
  pcci.initialDataSize = seed.size();
  pcci.pInitialData = seed.empty() ? nullptr : seed.data();
  VXR_VK_TRY(vkCreatePipelineCache(device_, &pcci, nullptr, &pipeline_cache_));
  return Status::ok();
}

Status Context::pick_device(const ContextOptions& options) {
  uint32_t n = 0;
  VXR_VK_TRY(vkEnumeratePhysicalDevices(instance_, &n, nullptr));
  if (n == 0)
    return unsupported("no Vulkan device found (install mesa-vulkan-drivers for the CPU renderer)");
  std::vector<VkPhysicalDevice> devices(n);
  VXR_VK_TRY(vkEnumeratePhysicalDevices(instance_, &n, devices.data()));

  const std::string filter = lower(options.device_filter);
  VkPhysicalDevice best = VK_NULL_HANDLE;
  int best_rank = 1000;
  std::string names;
  for (VkPhysicalDevice d : devices) {
    VkPhysicalDeviceProperties p;
    vkGetPhysicalDeviceProperties(d, &p);
    names += std::string(names.empty() ? "" : ", ") + p.deviceName;
    if (!filter.empty() && lower(p.deviceName).find(filter) == std::string::npos) continue;
    const int rank = type_rank(p.deviceType);
    if (rank < best_rank) {
      best_rank = rank;
      best = d;
    }
  }
  if (!best)
    return not_found("VXR_DEVICE=" + options.device_filter + " matches no Vulkan device; devices: " + names);
  physical_device_ = best;
  return Status::ok();
}

Result<uint32_t> Context::find_memory_type(uint32_t type_bits, VkMemoryPropertyFlags required,
                                           VkMemoryPropertyFlags preferred) const {
  int fallback = -1;
  for (uint32_t i = 0; i < memory_properties_.memoryTypeCount; ++i) {
    if (!(type_bits & (1u << i))) continue;
    const VkMemoryPropertyFlags f = memory_properties_.memoryTypes[i].propertyFlags;
    if ((f & required) != required) continue;
    if ((f & preferred) == preferred) return i;
    if (fallback < 0) fallback = static_cast<int>(i);
  }
  if (fallback >= 0) return static_cast<uint32_t>(fallback);
  return gpu_error("no memory type with flags " + std::to_string(required));
}

Status Context::submit_and_wait(const std::function<void(VkCommandBuffer)>& record) {
  VkCommandBufferAllocateInfo ai{VK_STRUCTURE_TYPE_COMMAND_BUFFER_ALLOCATE_INFO};
  ai.commandPool = command_pool_;
  ai.level = VK_COMMAND_BUFFER_LEVEL_PRIMARY;
  ai.commandBufferCount = 1;
  VkCommandBuffer cmd = VK_NULL_HANDLE;
  VXR_VK_TRY(vkAllocateCommandBuffers(device_, &ai, &cmd));
  struct FreeCmd {
    VkDevice d;
    VkCommandPool p;
    VkCommandBuffer c;
    ~FreeCmd() { vkFreeCommandBuffers(d, p, 1, &c); }
  } free_cmd{device_, command_pool_, cmd};

  VkCommandBufferBeginInfo bi{VK_STRUCTURE_TYPE_COMMAND_BUFFER_BEGIN_INFO};
  bi.flags = VK_COMMAND_BUFFER_USAGE_ONE_TIME_SUBMIT_BIT;
  VXR_VK_TRY(vkBeginCommandBuffer(cmd, &bi));
  record(cmd);
  VXR_VK_TRY(vkEndCommandBuffer(cmd));

  VkCommandBufferSubmitInfo cbsi{VK_STRUCTURE_TYPE_COMMAND_BUFFER_SUBMIT_INFO};
  cbsi.commandBuffer = cmd;
  VkSubmitInfo2 si{VK_STRUCTURE_TYPE_SUBMIT_INFO_2};
  si.commandBufferInfoCount = 1;
  si.pCommandBufferInfos = &cbsi;
  VkFence fence = fence_;
  VXR_VK_TRY(vkResetFences(device_, 1, &fence));
  VXR_VK_TRY(vkQueueSubmit2(queue_, 1, &si, fence));
  VXR_VK_TRY(vkWaitForFences(device_, 1, &fence, VK_TRUE, UINT64_MAX));
  return Status::ok();
}

Context::~Context() {
  if (device_) vkDeviceWaitIdle(device_);
  if (pipeline_cache_) {
    size_t n = 0;
    std::vector<uint8_t> data;
    if (!pipeline_cache_path_.empty() && vkGetPipelineCacheData(device_, pipeline_cache_, &n, nullptr) == VK_SUCCESS) {
      data.resize(n);
      if (vkGetPipelineCacheData(device_, pipeline_cache_, &n, data.data()) == VK_SUCCESS) {
        data.resize(n);
        if (Status st = write_pipeline_cache(pipeline_cache_path_, properties_, data); !st) log_warn(st.message());
      }
    }
    vkDestroyPipelineCache(device_, pipeline_cache_, nullptr);
  }
  fence_.reset();
  command_pool_.reset();
  if (device_) vkDestroyDevice(device_, nullptr);
  if (messenger_) {
    auto destroy = reinterpret_cast<PFN_vkDestroyDebugUtilsMessengerEXT>(
        vkGetInstanceProcAddr(instance_, "vkDestroyDebugUtilsMessengerEXT"));
    if (destroy) destroy(instance_, messenger_, nullptr);
  }
  if (instance_) vkDestroyInstance(instance_, nullptr);
}

}  // namespace vxr::gpu
