// The test runtime (see runtime.h for what it does and how to drive it).
// Every entry point lives in namespace rt and is hidden: the only exported
// symbol is xrNegotiateLoaderRuntimeInterface, so nothing here can bind to
// the loader's own xr* symbols.
#include "xr/test_runtime/runtime.h"

#define XR_USE_GRAPHICS_API_VULKAN
#define XR_NO_PROTOTYPES  // our entry points share the API names (in namespace rt)
#include <vulkan/vulkan.h>
#include <openxr/openxr.h>
#include <openxr/openxr_platform.h>
#include <openxr/openxr_reflection.h>

#include <cmath>
#include <cstdlib>
#include <cstring>
#include <deque>
#include <filesystem>
#include <fstream>
#include <map>
#include <memory>
#include <set>
#include <sstream>
#include <string>
#include <vector>

#include "core/image.h"
#include "xr/script.h"

// The loader/runtime negotiation structures (loader_interfaces.h in the
// OpenXR SDK; Debian's libopenxr-dev 1.0.20 does not install it).
extern "C" {
enum XrLoaderInterfaceStructs {
  XR_LOADER_INTERFACE_STRUCT_UNINTIALIZED = 0,
  XR_LOADER_INTERFACE_STRUCT_LOADER_INFO,
  XR_LOADER_INTERFACE_STRUCT_API_LAYER_REQUEST,
  XR_LOADER_INTERFACE_STRUCT_RUNTIME_REQUEST,
  XR_LOADER_INTERFACE_STRUCT_API_LAYER_CREATE_INFO,
  XR_LOADER_INTERFACE_STRUCT_API_LAYER_NEXT_INFO,
};
struct XrNegotiateLoaderInfo {
  XrLoaderInterfaceStructs structType;
  uint32_t structVersion;
  size_t structSize;
  uint32_t minInterfaceVersion;
  uint32_t maxInterfaceVersion;
  XrVersion minApiVersion;
  XrVersion maxApiVersion;
};
struct XrNegotiateRuntimeRequest {
  XrLoaderInterfaceStructs structType;
  uint32_t structVersion;
  size_t structSize;
  uint32_t runtimeInterfaceVersion;
  XrVersion runtimeApiVersion;
  PFN_xrGetInstanceProcAddr getInstanceProcAddr;
};
__attribute__((visibility("default"))) XrResult xrNegotiateLoaderRuntimeInterface(
    const XrNegotiateLoaderInfo* loaderInfo, XrNegotiateRuntimeRequest* runtimeRequest);
}

namespace rt {

using vxr::xr::Pose;
using vxr::xr::Script;
using vxr::xr::ScriptFrame;
using vxr::xr::ScriptHand;

constexpr XrTime kFirstDisplayTime = 1000000000;  // 1 s
constexpr XrDuration kPeriod = 11111111;          // 90 Hz
constexpr XrSystemId kSystem = 0x5678;

// ---------------------------------------------------------------- configuration

struct FailSpec {
  std::string function;
  long call = 1;
  XrResult result = XR_ERROR_RUNTIME_FAILURE;
};

XrResult result_from_name(const std::string& name) {
#define RT_RESULT(n, v) \
  if (name == #n) return n;
  XR_LIST_ENUM_XrResult(RT_RESULT)
#undef RT_RESULT
  return XR_ERROR_RUNTIME_FAILURE;
}

const char* result_name(XrResult r) {
  switch (r) {
#define RT_RESULT(n, v) \
  case n: return #n;
    XR_LIST_ENUM_XrResult(RT_RESULT)
#undef RT_RESULT
    default: return "XR_UNKNOWN_RESULT";
  }
}

struct Config {
  Script script;
  std::vector<FailSpec> fails;
  long loss_frame = -1;
  bool no_headset = false, no_stage = false, no_depth = false, no_srgb = false;
  std::string profile;
  std::set<long> dump_frames;
  std::string dump_dir, report_path, call_log;
  std::string error;  // script problem, reported at xrCreateInstance
};

Config load_config() {
  Config c;
  if (const char* p = std::getenv("VXR_TEST_RUNTIME_SCRIPT"); p && *p) {
    std::string err;
    if (!vxr::xr::load_script(p, c.script, err)) c.error = err;
    const auto& j = c.script.raw;
    try {
      if (j.contains("session_loss_at_frame")) c.loss_frame = j["session_loss_at_frame"].get<long>();
      if (j.contains("no_headset")) c.no_headset = j["no_headset"].get<bool>();
      if (j.contains("no_stage")) c.no_stage = j["no_stage"].get<bool>();
      if (j.contains("no_depth")) c.no_depth = j["no_depth"].get<bool>();
      if (j.contains("no_srgb")) c.no_srgb = j["no_srgb"].get<bool>();
      if (j.contains("profile")) c.profile = j["profile"].get<std::string>();
      if (j.contains("dump_frames"))
        for (const auto& f : j["dump_frames"]) c.dump_frames.insert(f.get<long>());
      if (j.contains("fail"))
        for (const auto& f : j["fail"])
          c.fails.push_back({f.at("function").get<std::string>(), f.value("call", 1L),
                             result_from_name(f.value("result", std::string("XR_ERROR_RUNTIME_FAILURE")))});
    } catch (const std::exception& e) {
      c.error = std::string(p) + ": " + e.what();
    }
  }
  // VXR_TEST_RUNTIME_FAIL=fn:k:RESULT[,fn:k:RESULT...]
  if (const char* f = std::getenv("VXR_TEST_RUNTIME_FAIL"); f && *f) {
    std::stringstream ss(f);
    std::string item;
    while (std::getline(ss, item, ',')) {
      FailSpec s;
      const size_t a = item.find(':'), b = item.find(':', a == std::string::npos ? a : a + 1);
      s.function = item.substr(0, a);
      if (a != std::string::npos) s.call = std::atol(item.substr(a + 1, b - a - 1).c_str());
      if (b != std::string::npos) s.result = result_from_name(item.substr(b + 1));
      c.fails.push_back(s);
    }
  }
  if (const char* d = std::getenv("VXR_TEST_RUNTIME_DUMP_DIR")) c.dump_dir = d;
  if (const char* r = std::getenv("VXR_TEST_RUNTIME_REPORT")) c.report_path = r;
  if (const char* l = std::getenv("VXR_TEST_RUNTIME_CALL_LOG")) c.call_log = l;
  if (const char* h = std::getenv("VXR_TEST_RUNTIME_NO_HEADSET")) c.no_headset = h[0] == '1';
  return c;
}

Config g_config;
bool g_config_loaded = false;

// Re-read while no instance exists: the loader may keep this library loaded
// between instances, and a new instance must see the current environment.
Config& config() {
  if (!g_config_loaded) {
    g_config = load_config();
    g_config_loaded = true;
  }
  return g_config;
}

// Process-wide counter in an environment variable (survives the loader
// unloading and reloading this library between instances).
long bump_env(const std::string& key) {
  const char* v = std::getenv(key.c_str());
  const long n = (v ? std::atol(v) : 0) + 1;
  setenv(key.c_str(), std::to_string(n).c_str(), 1);
  return n;
}

struct Instance;
extern Instance* g_instance;

XrResult enter(const char* fn) {
  if (!g_instance) g_config_loaded = false;
  Config& c = config();
  if (!c.call_log.empty()) {
    static std::set<std::string> logged;
    if (logged.insert(fn).second) std::ofstream(c.call_log, std::ios::app) << fn << "\n";
  }
  long call = 0;  // this call's number, counted only for functions that have a failure planned
  for (const FailSpec& f : c.fails) {
    if (f.function != fn) continue;
    if (call == 0) call = bump_env(std::string("VXR_TEST_RUNTIME_CALLS_") + fn);
    if (call == f.call) return f.result;
  }
  return XR_SUCCESS;
}

#define RT_ENTER()                                            \
  do {                                                        \
    if (XrResult rt_r_ = enter(__func__); rt_r_ != XR_SUCCESS) \
      return rt_r_;                                           \
  } while (0)

// ---------------------------------------------------------------- objects

struct Session;

struct Action {
  struct ActionSet* set;
  std::string name;
  XrActionType type;
  std::vector<XrPath> subactions;
};

struct ActionSet {
  std::string name;
  std::vector<std::unique_ptr<Action>> actions;
  bool attached = false;
};

struct Space {
  Session* session;
  enum Kind { kReference, kAction } kind;
  XrReferenceSpaceType ref = XR_REFERENCE_SPACE_TYPE_STAGE;
  Action* action = nullptr;
  XrPath subaction = XR_NULL_PATH;
  Pose offset;
};

struct SwapImage {
  VkImage image = VK_NULL_HANDLE;
  VkDeviceMemory memory = VK_NULL_HANDLE;
};

struct Swapchain {
  Session* session;
  XrSwapchainCreateInfo info;
  bool depth = false;
  std::vector<SwapImage> images;
  uint32_t next = 0;
  std::deque<uint32_t> acquired;  // acquired, not yet released
  bool waited = false;
  long last_released = -1;
};

struct Instance {
  bool depth_enabled = false;
  std::vector<std::string> paths{""};  // XrPath = index (0 = XR_NULL_PATH)
  std::map<std::string, XrPath> path_ids;
  std::vector<std::unique_ptr<ActionSet>> action_sets;
  // profile path -> (action, binding path)
  std::map<std::string, std::vector<std::pair<Action*, std::string>>> suggested;
  std::deque<XrEventDataBuffer> events;
  bool requirements_called = false;
  VkInstance vk_instance = VK_NULL_HANDLE;  // made by xrCreateVulkanInstanceKHR
  Session* session = nullptr;
};

struct Session {
  Instance* inst;
  VkInstance vk_instance;
  VkPhysicalDevice physical;
  VkDevice device;
  VkQueue queue;
  uint32_t queue_family;
  VkCommandPool pool = VK_NULL_HANDLE;
  XrSessionState state = XR_SESSION_STATE_UNKNOWN;
  bool running = false, exit_requested = false, lost = false;
  long frame = 0;          // index of the frame being waited/begun
  bool waited = false, begun = false;
  long synced_frame = -1;  // input snapshot
  std::string profile;
  std::vector<std::unique_ptr<Space>> spaces;
  std::vector<std::unique_ptr<Swapchain>> swapchains;
  // report
  long frames_ended = 0, frames_with_layers = 0, frames_with_depth = 0, haptics = 0;
  std::vector<std::string> states;
  std::string layer_space;
};

Instance* g_instance = nullptr;  // one instance at a time

Instance* as_instance(XrInstance h) {
  return reinterpret_cast<Instance*>(h) == g_instance && g_instance ? g_instance : nullptr;
}
Session* as_session(XrSession h) {
  Session* s = reinterpret_cast<Session*>(h);
  return g_instance && g_instance->session == s && s ? s : nullptr;
}

const char* state_name(XrSessionState s) {
  switch (s) {
    case XR_SESSION_STATE_IDLE: return "IDLE";
    case XR_SESSION_STATE_READY: return "READY";
    case XR_SESSION_STATE_SYNCHRONIZED: return "SYNCHRONIZED";
    case XR_SESSION_STATE_VISIBLE: return "VISIBLE";
    case XR_SESSION_STATE_FOCUSED: return "FOCUSED";
    case XR_SESSION_STATE_STOPPING: return "STOPPING";
    case XR_SESSION_STATE_LOSS_PENDING: return "LOSS_PENDING";
    case XR_SESSION_STATE_EXITING: return "EXITING";
    default: return "UNKNOWN";
  }
}

void push_state(Session* s, XrSessionState state) {
  s->state = state;
  s->states.push_back(state_name(state));
  XrEventDataBuffer buf{XR_TYPE_EVENT_DATA_BUFFER};
  auto* e = reinterpret_cast<XrEventDataSessionStateChanged*>(&buf);
  e->type = XR_TYPE_EVENT_DATA_SESSION_STATE_CHANGED;
  e->next = nullptr;
  e->session = reinterpret_cast<XrSession>(s);
  e->state = state;
  e->time = kFirstDisplayTime + s->frame * kPeriod;
  s->inst->events.push_back(buf);
}

template <typename T>
XrResult two_call(uint32_t capacity, uint32_t* count, T* out, const std::vector<T>& values) {
  if (!count) return XR_ERROR_VALIDATION_FAILURE;
  *count = static_cast<uint32_t>(values.size());
  if (capacity == 0) return XR_SUCCESS;
  if (capacity < values.size()) return XR_ERROR_SIZE_INSUFFICIENT;
  if (!out) return XR_ERROR_VALIDATION_FAILURE;
  for (size_t i = 0; i < values.size(); ++i) out[i] = values[i];
  return XR_SUCCESS;
}

XrPosef to_xr(const Pose& p) {
  XrPosef x;
  x.orientation = {float(p.orientation.x), float(p.orientation.y), float(p.orientation.z), float(p.orientation.w)};
  x.position = {float(p.position.x), float(p.position.y), float(p.position.z)};
  return x;
}
Pose from_xr(const XrPosef& p) {
  return {glm::dquat(p.orientation.w, p.orientation.x, p.orientation.y, p.orientation.z),
          glm::dvec3(p.position.x, p.position.y, p.position.z)};
}

long frame_at(XrTime t) { return t <= kFirstDisplayTime ? 0 : long((t - kFirstDisplayTime + kPeriod / 2) / kPeriod); }

ScriptFrame script_at(long frame) { return config().script.at(uint64_t(std::max(0L, frame))); }

// ---------------------------------------------------------------- instance

XrResult xrGetInstanceProcAddr(XrInstance instance, const char* name, PFN_xrVoidFunction* function);

XrResult xrEnumerateInstanceExtensionProperties(const char* layerName, uint32_t capacity, uint32_t* count,
                                                XrExtensionProperties* props) {
  RT_ENTER();
  (void)layerName;
  std::vector<XrExtensionProperties> v;
  XrExtensionProperties e{XR_TYPE_EXTENSION_PROPERTIES};
  std::strcpy(e.extensionName, XR_KHR_VULKAN_ENABLE2_EXTENSION_NAME);
  e.extensionVersion = XR_KHR_vulkan_enable2_SPEC_VERSION;
  v.push_back(e);
  if (!config().no_depth) {
    std::strcpy(e.extensionName, XR_KHR_COMPOSITION_LAYER_DEPTH_EXTENSION_NAME);
    e.extensionVersion = XR_KHR_composition_layer_depth_SPEC_VERSION;
    v.push_back(e);
  }
  if (!count) return XR_ERROR_VALIDATION_FAILURE;
  *count = uint32_t(v.size());
  if (capacity == 0) return XR_SUCCESS;
  if (capacity < v.size()) return XR_ERROR_SIZE_INSUFFICIENT;
  for (size_t i = 0; i < v.size(); ++i) {
    std::strcpy(props[i].extensionName, v[i].extensionName);
    props[i].extensionVersion = v[i].extensionVersion;
  }
  return XR_SUCCESS;
}

XrResult xrCreateInstance(const XrInstanceCreateInfo* ci, XrInstance* out) {
  RT_ENTER();
  if (!ci || !out) return XR_ERROR_VALIDATION_FAILURE;
  if (!config().error.empty()) {
    std::fprintf(stderr, "vxr test runtime: %s\n", config().error.c_str());
    return XR_ERROR_INITIALIZATION_FAILED;
  }
  if (g_instance) return XR_ERROR_LIMIT_REACHED;
  auto* inst = new Instance();
  for (uint32_t i = 0; i < ci->enabledExtensionCount; ++i) {
    const std::string e = ci->enabledExtensionNames[i];
    if (e == XR_KHR_COMPOSITION_LAYER_DEPTH_EXTENSION_NAME && !config().no_depth) {
      inst->depth_enabled = true;
    } else if (e != XR_KHR_VULKAN_ENABLE2_EXTENSION_NAME) {
      delete inst;
      return XR_ERROR_EXTENSION_NOT_PRESENT;
    }
  }
  g_instance = inst;
  *out = reinterpret_cast<XrInstance>(inst);
  return XR_SUCCESS;
}

XrResult xrDestroySession(XrSession session);

XrResult xrDestroyInstance(XrInstance instance) {
  RT_ENTER();
  Instance* inst = as_instance(instance);
  if (!inst) return XR_ERROR_HANDLE_INVALID;
  if (inst->session) xrDestroySession(reinterpret_cast<XrSession>(inst->session));
  delete inst;
  g_instance = nullptr;
  return XR_SUCCESS;
}

XrResult xrGetInstanceProperties(XrInstance instance, XrInstanceProperties* p) {
  RT_ENTER();
  if (!as_instance(instance)) return XR_ERROR_HANDLE_INVALID;
  p->runtimeVersion = XR_MAKE_VERSION(0, 1, 0);
  std::strcpy(p->runtimeName, "vxr test runtime");
  return XR_SUCCESS;
}

XrResult xrPollEvent(XrInstance instance, XrEventDataBuffer* event) {
  RT_ENTER();
  Instance* inst = as_instance(instance);
  if (!inst) return XR_ERROR_HANDLE_INVALID;
  if (inst->events.empty()) return XR_EVENT_UNAVAILABLE;
  *event = inst->events.front();
  inst->events.pop_front();
  return XR_SUCCESS;
}

XrResult xrResultToString(XrInstance, XrResult value, char buffer[XR_MAX_RESULT_STRING_SIZE]) {
  RT_ENTER();
  std::snprintf(buffer, XR_MAX_RESULT_STRING_SIZE, "%s", result_name(value));
  return XR_SUCCESS;
}

XrResult xrStructureTypeToString(XrInstance, XrStructureType value, char buffer[XR_MAX_STRUCTURE_NAME_SIZE]) {
  RT_ENTER();
  std::snprintf(buffer, XR_MAX_STRUCTURE_NAME_SIZE, "XrStructureType(%d)", int(value));
  return XR_SUCCESS;
}

XrResult xrStringToPath(XrInstance instance, const char* str, XrPath* path) {
  RT_ENTER();
  Instance* inst = as_instance(instance);
  if (!inst) return XR_ERROR_HANDLE_INVALID;
  if (!str || str[0] != '/') return XR_ERROR_PATH_FORMAT_INVALID;
  auto it = inst->path_ids.find(str);
  if (it != inst->path_ids.end()) {
    *path = it->second;
    return XR_SUCCESS;
  }
  inst->paths.push_back(str);
  *path = inst->paths.size() - 1;
  inst->path_ids[str] = *path;
  return XR_SUCCESS;
}

XrResult xrPathToString(XrInstance instance, XrPath path, uint32_t capacity, uint32_t* count, char* buffer) {
  RT_ENTER();
  Instance* inst = as_instance(instance);
  if (!inst) return XR_ERROR_HANDLE_INVALID;
  if (path == XR_NULL_PATH || path >= inst->paths.size()) return XR_ERROR_PATH_INVALID;
  const std::string& s = inst->paths[path];
  *count = uint32_t(s.size() + 1);
  if (capacity == 0) return XR_SUCCESS;
  if (capacity < s.size() + 1) return XR_ERROR_SIZE_INSUFFICIENT;
  std::memcpy(buffer, s.c_str(), s.size() + 1);
  return XR_SUCCESS;
}

// ---------------------------------------------------------------- system

XrResult xrGetSystem(XrInstance instance, const XrSystemGetInfo* info, XrSystemId* system) {
  RT_ENTER();
  if (!as_instance(instance)) return XR_ERROR_HANDLE_INVALID;
  if (info->formFactor != XR_FORM_FACTOR_HEAD_MOUNTED_DISPLAY) return XR_ERROR_FORM_FACTOR_UNSUPPORTED;
  if (config().no_headset) return XR_ERROR_FORM_FACTOR_UNAVAILABLE;
  *system = kSystem;
  return XR_SUCCESS;
}

XrResult xrGetSystemProperties(XrInstance instance, XrSystemId system, XrSystemProperties* p) {
  RT_ENTER();
  if (!as_instance(instance)) return XR_ERROR_HANDLE_INVALID;
  if (system != kSystem) return XR_ERROR_SYSTEM_INVALID;
  p->systemId = kSystem;
  p->vendorId = 0x7678;
  std::strcpy(p->systemName, "scripted headset");
  p->graphicsProperties.maxSwapchainImageWidth = 4096;
  p->graphicsProperties.maxSwapchainImageHeight = 4096;
  p->graphicsProperties.maxLayerCount = 16;
  p->trackingProperties.orientationTracking = XR_TRUE;
  p->trackingProperties.positionTracking = XR_TRUE;
  return XR_SUCCESS;
}

XrResult xrEnumerateViewConfigurations(XrInstance instance, XrSystemId system, uint32_t capacity, uint32_t* count,
                                       XrViewConfigurationType* types) {
  RT_ENTER();
  if (!as_instance(instance)) return XR_ERROR_HANDLE_INVALID;
  if (system != kSystem) return XR_ERROR_SYSTEM_INVALID;
  return two_call(capacity, count, types, {XR_VIEW_CONFIGURATION_TYPE_PRIMARY_STEREO});
}

XrResult xrGetViewConfigurationProperties(XrInstance instance, XrSystemId system, XrViewConfigurationType type,
                                          XrViewConfigurationProperties* p) {
  RT_ENTER();
  if (!as_instance(instance)) return XR_ERROR_HANDLE_INVALID;
  if (system != kSystem) return XR_ERROR_SYSTEM_INVALID;
  if (type != XR_VIEW_CONFIGURATION_TYPE_PRIMARY_STEREO) return XR_ERROR_VIEW_CONFIGURATION_TYPE_UNSUPPORTED;
  p->viewConfigurationType = type;
  p->fovMutable = XR_FALSE;
  return XR_SUCCESS;
}

XrResult xrEnumerateViewConfigurationViews(XrInstance instance, XrSystemId system, XrViewConfigurationType type,
                                           uint32_t capacity, uint32_t* count, XrViewConfigurationView* views) {
  RT_ENTER();
  if (!as_instance(instance)) return XR_ERROR_HANDLE_INVALID;
  if (system != kSystem) return XR_ERROR_SYSTEM_INVALID;
  if (type != XR_VIEW_CONFIGURATION_TYPE_PRIMARY_STEREO) return XR_ERROR_VIEW_CONFIGURATION_TYPE_UNSUPPORTED;
  *count = 2;
  if (capacity == 0) return XR_SUCCESS;
  if (capacity < 2) return XR_ERROR_SIZE_INSUFFICIENT;
  for (int i = 0; i < 2; ++i) {
    views[i].recommendedImageRectWidth = config().script.width;
    views[i].recommendedImageRectHeight = config().script.height;
    views[i].maxImageRectWidth = 4096;
    views[i].maxImageRectHeight = 4096;
    views[i].recommendedSwapchainSampleCount = 1;
    views[i].maxSwapchainSampleCount = 1;
  }
  return XR_SUCCESS;
}

XrResult xrEnumerateEnvironmentBlendModes(XrInstance instance, XrSystemId system, XrViewConfigurationType,
                                          uint32_t capacity, uint32_t* count, XrEnvironmentBlendMode* modes) {
  RT_ENTER();
  if (!as_instance(instance)) return XR_ERROR_HANDLE_INVALID;
  if (system != kSystem) return XR_ERROR_SYSTEM_INVALID;
  return two_call(capacity, count, modes, {XR_ENVIRONMENT_BLEND_MODE_OPAQUE});
}

// ---------------------------------------------------------------- Vulkan (XR_KHR_vulkan_enable2)

XrResult xrGetVulkanGraphicsRequirements2KHR(XrInstance instance, XrSystemId system,
                                             XrGraphicsRequirementsVulkanKHR* req) {
  RT_ENTER();
  Instance* inst = as_instance(instance);
  if (!inst) return XR_ERROR_HANDLE_INVALID;
  if (system != kSystem) return XR_ERROR_SYSTEM_INVALID;
  req->minApiVersionSupported = XR_MAKE_VERSION(1, 0, 0);
  req->maxApiVersionSupported = XR_MAKE_VERSION(1, 3, 0);
  inst->requirements_called = true;
  return XR_SUCCESS;
}

XrResult xrCreateVulkanInstanceKHR(XrInstance instance, const XrVulkanInstanceCreateInfoKHR* ci, VkInstance* out,
                                   VkResult* vr) {
  RT_ENTER();
  Instance* inst = as_instance(instance);
  if (!inst) return XR_ERROR_HANDLE_INVALID;
  if (ci->systemId != kSystem) return XR_ERROR_SYSTEM_INVALID;
  auto create = reinterpret_cast<PFN_vkCreateInstance>(ci->pfnGetInstanceProcAddr(nullptr, "vkCreateInstance"));
  if (!create) return XR_ERROR_RUNTIME_FAILURE;
  *vr = create(ci->vulkanCreateInfo, ci->vulkanAllocator, out);
  if (*vr == VK_SUCCESS) inst->vk_instance = *out;
  return XR_SUCCESS;
}

XrResult xrGetVulkanGraphicsDevice2KHR(XrInstance instance, const XrVulkanGraphicsDeviceGetInfoKHR* gi,
                                       VkPhysicalDevice* out) {
  RT_ENTER();
  if (!as_instance(instance)) return XR_ERROR_HANDLE_INVALID;
  if (gi->systemId != kSystem) return XR_ERROR_SYSTEM_INVALID;
  uint32_t n = 0;
  if (vkEnumeratePhysicalDevices(gi->vulkanInstance, &n, nullptr) != VK_SUCCESS || n == 0)
    return XR_ERROR_RUNTIME_FAILURE;
  std::vector<VkPhysicalDevice> devices(n);
  vkEnumeratePhysicalDevices(gi->vulkanInstance, &n, devices.data());
  // The "headset" is driven by the CPU device (lavapipe) when there is one: deterministic images.
  *out = devices[0];
  for (VkPhysicalDevice d : devices) {
    VkPhysicalDeviceProperties p;
    vkGetPhysicalDeviceProperties(d, &p);
    if (p.deviceType == VK_PHYSICAL_DEVICE_TYPE_CPU) {
      *out = d;
      break;
    }
  }
  return XR_SUCCESS;
}

XrResult xrCreateVulkanDeviceKHR(XrInstance instance, const XrVulkanDeviceCreateInfoKHR* ci, VkDevice* out,
                                 VkResult* vr) {
  RT_ENTER();
  Instance* inst = as_instance(instance);
  if (!inst) return XR_ERROR_HANDLE_INVALID;
  if (ci->systemId != kSystem) return XR_ERROR_SYSTEM_INVALID;
  // vkCreateDevice is an instance-level command: look it up on the instance we made.
  auto create = inst->vk_instance ? reinterpret_cast<PFN_vkCreateDevice>(
                                        ci->pfnGetInstanceProcAddr(inst->vk_instance, "vkCreateDevice"))
                                  : &vkCreateDevice;
  if (!create) return XR_ERROR_RUNTIME_FAILURE;
  *vr = create(ci->vulkanPhysicalDevice, ci->vulkanCreateInfo, ci->vulkanAllocator, out);
  return XR_SUCCESS;
}

// ---------------------------------------------------------------- session

// Records and submits one command buffer on the session's queue, and waits.
template <typename F>
bool run_commands(Session* s, F&& record) {
  VkCommandBufferAllocateInfo ai{VK_STRUCTURE_TYPE_COMMAND_BUFFER_ALLOCATE_INFO};
  ai.commandPool = s->pool;
  ai.level = VK_COMMAND_BUFFER_LEVEL_PRIMARY;
  ai.commandBufferCount = 1;
  VkCommandBuffer cmd;
  if (vkAllocateCommandBuffers(s->device, &ai, &cmd) != VK_SUCCESS) return false;
  VkCommandBufferBeginInfo bi{VK_STRUCTURE_TYPE_COMMAND_BUFFER_BEGIN_INFO};
  bi.flags = VK_COMMAND_BUFFER_USAGE_ONE_TIME_SUBMIT_BIT;
  vkBeginCommandBuffer(cmd, &bi);
  record(cmd);
  vkEndCommandBuffer(cmd);
  VkSubmitInfo si{VK_STRUCTURE_TYPE_SUBMIT_INFO};
  si.commandBufferCount = 1;
  si.pCommandBuffers = &cmd;
  const bool ok = vkQueueSubmit(s->queue, 1, &si, VK_NULL_HANDLE) == VK_SUCCESS && vkQueueWaitIdle(s->queue) == VK_SUCCESS;
  vkFreeCommandBuffers(s->device, s->pool, 1, &cmd);
  return ok;
}

void barrier(VkCommandBuffer cmd, VkImage image, VkImageAspectFlags aspect, VkImageLayout from, VkImageLayout to) {
  VkImageMemoryBarrier b{VK_STRUCTURE_TYPE_IMAGE_MEMORY_BARRIER};
  b.srcAccessMask = VK_ACCESS_MEMORY_READ_BIT | VK_ACCESS_MEMORY_WRITE_BIT;
  b.dstAccessMask = VK_ACCESS_MEMORY_READ_BIT | VK_ACCESS_MEMORY_WRITE_BIT;
  b.oldLayout = from;
  b.newLayout = to;
  b.srcQueueFamilyIndex = b.dstQueueFamilyIndex = VK_QUEUE_FAMILY_IGNORED;
  b.image = image;
  b.subresourceRange = {aspect, 0, 1, 0, 1};
  vkCmdPipelineBarrier(cmd, VK_PIPELINE_STAGE_ALL_COMMANDS_BIT, VK_PIPELINE_STAGE_ALL_COMMANDS_BIT, 0, 0, nullptr, 0,
                       nullptr, 1, &b);
}

XrResult xrCreateSession(XrInstance instance, const XrSessionCreateInfo* ci, XrSession* out) {
  RT_ENTER();
  Instance* inst = as_instance(instance);
  if (!inst) return XR_ERROR_HANDLE_INVALID;
  if (ci->systemId != kSystem) return XR_ERROR_SYSTEM_INVALID;
  if (!inst->requirements_called) return XR_ERROR_GRAPHICS_REQUIREMENTS_CALL_MISSING;
  if (inst->session) return XR_ERROR_LIMIT_REACHED;
  const XrGraphicsBindingVulkan2KHR* binding = nullptr;
  for (auto* n = static_cast<const XrBaseInStructure*>(ci->next); n; n = n->next)
    if (n->type == XR_TYPE_GRAPHICS_BINDING_VULKAN2_KHR) binding = reinterpret_cast<const XrGraphicsBindingVulkan2KHR*>(n);
  if (!binding) return XR_ERROR_GRAPHICS_DEVICE_INVALID;
  auto s = std::make_unique<Session>();
  s->inst = inst;
  s->vk_instance = binding->instance;
  s->physical = binding->physicalDevice;
  s->device = binding->device;
  s->queue_family = binding->queueFamilyIndex;
  vkGetDeviceQueue(s->device, binding->queueFamilyIndex, binding->queueIndex, &s->queue);
  VkCommandPoolCreateInfo pci{VK_STRUCTURE_TYPE_COMMAND_POOL_CREATE_INFO};
  pci.flags = VK_COMMAND_POOL_CREATE_TRANSIENT_BIT;
  pci.queueFamilyIndex = binding->queueFamilyIndex;
  if (vkCreateCommandPool(s->device, &pci, nullptr, &s->pool) != VK_SUCCESS) return XR_ERROR_RUNTIME_FAILURE;
  Session* raw = s.release();
  inst->session = raw;
  push_state(raw, XR_SESSION_STATE_IDLE);
  push_state(raw, XR_SESSION_STATE_READY);
  *out = reinterpret_cast<XrSession>(raw);
  return XR_SUCCESS;
}

void write_report(Session* s) {
  const std::string& path = config().report_path;
  if (path.empty()) return;
  nlohmann::json all = nlohmann::json::array();
  {
    std::ifstream in(path);
    if (in) try {
        all = nlohmann::json::parse(in);
      } catch (...) {
        all = nlohmann::json::array();
      }
  }
  nlohmann::json j;
  j["frames_ended"] = s->frames_ended;
  j["frames_with_layers"] = s->frames_with_layers;
  j["frames_with_depth"] = s->frames_with_depth;
  j["haptic_pulses"] = s->haptics;
  j["states"] = s->states;
  j["profile"] = s->profile;
  j["layer_space"] = s->layer_space;
  j["lost"] = s->lost;
  all.push_back(j);
  std::ofstream(path) << all.dump(2) << "\n";
}

XrResult xrDestroySwapchain(XrSwapchain swapchain);
XrResult xrDestroySpace(XrSpace space);

XrResult xrDestroySession(XrSession session) {
  RT_ENTER();
  Session* s = as_session(session);
  if (!s) return XR_ERROR_HANDLE_INVALID;
  while (!s->swapchains.empty()) xrDestroySwapchain(reinterpret_cast<XrSwapchain>(s->swapchains.back().get()));
  s->spaces.clear();
  if (s->pool) vkDestroyCommandPool(s->device, s->pool, nullptr);
  write_report(s);
  s->inst->session = nullptr;
  delete s;
  return XR_SUCCESS;
}

XrResult xrBeginSession(XrSession session, const XrSessionBeginInfo* bi) {
  RT_ENTER();
  Session* s = as_session(session);
  if (!s) return XR_ERROR_HANDLE_INVALID;
  if (s->lost) return XR_ERROR_SESSION_LOST;
  if (bi->primaryViewConfigurationType != XR_VIEW_CONFIGURATION_TYPE_PRIMARY_STEREO)
    return XR_ERROR_VIEW_CONFIGURATION_TYPE_UNSUPPORTED;
  if (s->running) return XR_ERROR_SESSION_RUNNING;
  if (s->state != XR_SESSION_STATE_READY) return XR_ERROR_SESSION_NOT_READY;
  s->running = true;
  return XR_SUCCESS;
}

XrResult xrEndSession(XrSession session) {
  RT_ENTER();
  Session* s = as_session(session);
  if (!s) return XR_ERROR_HANDLE_INVALID;
  if (s->lost) return XR_ERROR_SESSION_LOST;
  if (!s->running) return XR_ERROR_SESSION_NOT_RUNNING;
  if (s->state != XR_SESSION_STATE_STOPPING) return XR_ERROR_SESSION_NOT_STOPPING;
  s->running = false;
  push_state(s, XR_SESSION_STATE_IDLE);
  push_state(s, XR_SESSION_STATE_EXITING);
  return XR_SUCCESS;
}

XrResult xrRequestExitSession(XrSession session) {
  RT_ENTER();
  Session* s = as_session(session);
  if (!s) return XR_ERROR_HANDLE_INVALID;
  if (s->lost) return XR_ERROR_SESSION_LOST;
  if (!s->running) return XR_ERROR_SESSION_NOT_RUNNING;
  if (s->state == XR_SESSION_STATE_FOCUSED) push_state(s, XR_SESSION_STATE_VISIBLE);
  if (s->state == XR_SESSION_STATE_VISIBLE) push_state(s, XR_SESSION_STATE_SYNCHRONIZED);
  push_state(s, XR_SESSION_STATE_STOPPING);
  s->exit_requested = true;
  return XR_SUCCESS;
}

// ---------------------------------------------------------------- spaces

XrResult xrEnumerateReferenceSpaces(XrSession session, uint32_t capacity, uint32_t* count,
                                    XrReferenceSpaceType* spaces) {
  RT_ENTER();
  if (!as_session(session)) return XR_ERROR_HANDLE_INVALID;
  std::vector<XrReferenceSpaceType> v = {XR_REFERENCE_SPACE_TYPE_VIEW, XR_REFERENCE_SPACE_TYPE_LOCAL};
  if (!config().no_stage) v.push_back(XR_REFERENCE_SPACE_TYPE_STAGE);
  return two_call(capacity, count, spaces, v);
}

XrResult xrCreateReferenceSpace(XrSession session, const XrReferenceSpaceCreateInfo* ci, XrSpace* out) {
  RT_ENTER();
  Session* s = as_session(session);
  if (!s) return XR_ERROR_HANDLE_INVALID;
  if (s->lost) return XR_ERROR_SESSION_LOST;
  if (ci->referenceSpaceType == XR_REFERENCE_SPACE_TYPE_STAGE && config().no_stage)
    return XR_ERROR_REFERENCE_SPACE_UNSUPPORTED;
  auto sp = std::make_unique<Space>();
  sp->session = s;
  sp->kind = Space::kReference;
  sp->ref = ci->referenceSpaceType;
  sp->offset = from_xr(ci->poseInReferenceSpace);
  *out = reinterpret_cast<XrSpace>(sp.get());
  s->spaces.push_back(std::move(sp));
  return XR_SUCCESS;
}

XrResult xrCreateActionSpace(XrSession session, const XrActionSpaceCreateInfo* ci, XrSpace* out) {
  RT_ENTER();
  Session* s = as_session(session);
  if (!s) return XR_ERROR_HANDLE_INVALID;
  if (s->lost) return XR_ERROR_SESSION_LOST;
  auto* action = reinterpret_cast<Action*>(ci->action);
  if (!action || action->type != XR_ACTION_TYPE_POSE_INPUT) return XR_ERROR_ACTION_TYPE_MISMATCH;
  auto sp = std::make_unique<Space>();
  sp->session = s;
  sp->kind = Space::kAction;
  sp->action = action;
  sp->subaction = ci->subactionPath;
  sp->offset = from_xr(ci->poseInActionSpace);
  *out = reinterpret_cast<XrSpace>(sp.get());
  s->spaces.push_back(std::move(sp));
  return XR_SUCCESS;
}

XrResult xrDestroySpace(XrSpace space) {
  RT_ENTER();
  auto* sp = reinterpret_cast<Space*>(space);
  if (!g_instance || !g_instance->session) return XR_ERROR_HANDLE_INVALID;
  auto& list = g_instance->session->spaces;
  for (auto it = list.begin(); it != list.end(); ++it)
    if (it->get() == sp) {
      list.erase(it);
      return XR_SUCCESS;
    }
  return XR_ERROR_HANDLE_INVALID;
}

// The binding path (under /user/hand/X) the current profile gives `action` for `hand`, or "".
std::string bound_path(Session* s, const Action* action, int hand) {
  auto it = s->inst->suggested.find(s->profile);
  if (it == s->inst->suggested.end()) return "";
  const std::string prefix = hand == 0 ? "/user/hand/left" : "/user/hand/right";
  for (const auto& [a, path] : it->second)
    if (a == action && path.rfind(prefix, 0) == 0) return path.substr(prefix.size());
  return "";
}

int hand_of(Session* s, XrPath subaction) {
  if (subaction == XR_NULL_PATH) return -1;
  const std::string& p = s->inst->paths[subaction];
  if (p == "/user/hand/left") return 0;
  if (p == "/user/hand/right") return 1;
  return -2;
}

// Pose of a space in the STAGE frame at `frame`; false when not tracked.
bool space_pose(const Space* sp, long frame, Pose& out) {
  const ScriptFrame f = script_at(frame);
  Pose root;
  if (sp->kind == Space::kReference) {
    if (sp->ref == XR_REFERENCE_SPACE_TYPE_VIEW) root = f.head;
    if (sp->ref == XR_REFERENCE_SPACE_TYPE_LOCAL) root.position = {0.0, 1.6, 0.0};
  } else {
    const int h = hand_of(sp->session, sp->subaction);
    if (h < 0) return false;
    const std::string path = bound_path(sp->session, sp->action, h);
    const ScriptHand& hand = f.hands[h];
    if (!hand.tracked || path.empty()) return false;
    root = path.find("/aim/") != std::string::npos ? hand.aim : hand.grip;
  }
  out = root * sp->offset;
  return true;
}

XrResult xrLocateSpace(XrSpace space, XrSpace base, XrTime time, XrSpaceLocation* loc) {
  RT_ENTER();
  auto* a = reinterpret_cast<Space*>(space);
  auto* b = reinterpret_cast<Space*>(base);
  if (!a || !b) return XR_ERROR_HANDLE_INVALID;
  if (a->session->lost) return XR_ERROR_SESSION_LOST;
  if (time <= 0) return XR_ERROR_TIME_INVALID;
  Pose pa, pb;
  const long frame = frame_at(time);
  if (!space_pose(a, frame, pa) || !space_pose(b, frame, pb)) {
    loc->locationFlags = 0;
    return XR_SUCCESS;
  }
  loc->pose = to_xr(pb.inverse() * pa);
  loc->locationFlags = XR_SPACE_LOCATION_ORIENTATION_VALID_BIT | XR_SPACE_LOCATION_POSITION_VALID_BIT |
                       XR_SPACE_LOCATION_ORIENTATION_TRACKED_BIT | XR_SPACE_LOCATION_POSITION_TRACKED_BIT;
  return XR_SUCCESS;
}

XrResult xrGetReferenceSpaceBoundsRect(XrSession session, XrReferenceSpaceType, XrExtent2Df* bounds) {
  RT_ENTER();
  if (!as_session(session)) return XR_ERROR_HANDLE_INVALID;
  bounds->width = bounds->height = 0;
  return XR_SPACE_BOUNDS_UNAVAILABLE;
}

XrResult xrLocateViews(XrSession session, const XrViewLocateInfo* li, XrViewState* state, uint32_t capacity,
                       uint32_t* count, XrView* views) {
  RT_ENTER();
  Session* s = as_session(session);
  if (!s) return XR_ERROR_HANDLE_INVALID;
  if (s->lost) return XR_ERROR_SESSION_LOST;
  if (li->viewConfigurationType != XR_VIEW_CONFIGURATION_TYPE_PRIMARY_STEREO)
    return XR_ERROR_VIEW_CONFIGURATION_TYPE_UNSUPPORTED;
  if (li->displayTime <= 0) return XR_ERROR_TIME_INVALID;
  *count = 2;
  if (capacity == 0) return XR_SUCCESS;
  if (capacity < 2) return XR_ERROR_SIZE_INSUFFICIENT;
  const long frame = frame_at(li->displayTime);
  Pose base;
  if (!space_pose(reinterpret_cast<Space*>(li->space), frame, base)) {
    state->viewStateFlags = 0;
    return XR_SUCCESS;
  }
  const ScriptFrame f = script_at(frame);
  const Script& sc = config().script;
  for (int i = 0; i < 2; ++i) {
    Pose eye;
    eye.position.x = (i == 0 ? -0.5 : 0.5) * sc.ipd_m;
    views[i].pose = to_xr(base.inverse() * (f.head * eye));
    views[i].fov = {float(sc.fov.left), float(sc.fov.right), float(sc.fov.up), float(sc.fov.down)};
  }
  state->viewStateFlags = XR_VIEW_STATE_ORIENTATION_VALID_BIT | XR_VIEW_STATE_POSITION_VALID_BIT |
                          XR_VIEW_STATE_ORIENTATION_TRACKED_BIT | XR_VIEW_STATE_POSITION_TRACKED_BIT;
  return XR_SUCCESS;
}

// ---------------------------------------------------------------- swapchains

XrResult xrEnumerateSwapchainFormats(XrSession session, uint32_t capacity, uint32_t* count, int64_t* formats) {
  RT_ENTER();
  if (!as_session(session)) return XR_ERROR_HANDLE_INVALID;
  std::vector<int64_t> offered = {VK_FORMAT_R8G8B8A8_UNORM, VK_FORMAT_B8G8R8A8_UNORM, VK_FORMAT_D32_SFLOAT,
                                  VK_FORMAT_D16_UNORM};
  if (!config().no_srgb) offered.insert(offered.begin(), {VK_FORMAT_R8G8B8A8_SRGB, VK_FORMAT_B8G8R8A8_SRGB});
  return two_call<int64_t>(capacity, count, formats, offered);
}

XrResult xrCreateSwapchain(XrSession session, const XrSwapchainCreateInfo* ci, XrSwapchain* out) {
  RT_ENTER();
  Session* s = as_session(session);
  if (!s) return XR_ERROR_HANDLE_INVALID;
  if (s->lost) return XR_ERROR_SESSION_LOST;
  const VkFormat format = VkFormat(ci->format);
  const bool depth = format == VK_FORMAT_D32_SFLOAT || format == VK_FORMAT_D16_UNORM;
  const bool srgb = format == VK_FORMAT_R8G8B8A8_SRGB || format == VK_FORMAT_B8G8R8A8_SRGB;
  if (!depth && !(srgb && !config().no_srgb) && format != VK_FORMAT_R8G8B8A8_UNORM &&
      format != VK_FORMAT_B8G8R8A8_UNORM)
    return XR_ERROR_SWAPCHAIN_FORMAT_UNSUPPORTED;
  if (ci->width == 0 || ci->height == 0 || ci->width > 4096 || ci->height > 4096 || ci->arraySize != 1 ||
      ci->faceCount != 1 || ci->mipCount != 1 || ci->sampleCount != 1)
    return XR_ERROR_VALIDATION_FAILURE;
  auto sc = std::make_unique<Swapchain>();
  sc->session = s;
  sc->info = *ci;
  sc->depth = depth;
  VkImageUsageFlags usage = VK_IMAGE_USAGE_TRANSFER_SRC_BIT;  // the compositor (and dumps) read colour back
  if (ci->usageFlags & XR_SWAPCHAIN_USAGE_COLOR_ATTACHMENT_BIT) usage |= VK_IMAGE_USAGE_COLOR_ATTACHMENT_BIT;
  if (ci->usageFlags & XR_SWAPCHAIN_USAGE_DEPTH_STENCIL_ATTACHMENT_BIT) usage |= VK_IMAGE_USAGE_DEPTH_STENCIL_ATTACHMENT_BIT;
  if (ci->usageFlags & XR_SWAPCHAIN_USAGE_UNORDERED_ACCESS_BIT) usage |= VK_IMAGE_USAGE_STORAGE_BIT;
  if (ci->usageFlags & XR_SWAPCHAIN_USAGE_TRANSFER_DST_BIT) usage |= VK_IMAGE_USAGE_TRANSFER_DST_BIT;
  if (ci->usageFlags & XR_SWAPCHAIN_USAGE_SAMPLED_BIT) usage |= VK_IMAGE_USAGE_SAMPLED_BIT;
  VkPhysicalDeviceMemoryProperties mem;
  vkGetPhysicalDeviceMemoryProperties(s->physical, &mem);
  for (int i = 0; i < 3; ++i) {
    VkImageCreateInfo ici{VK_STRUCTURE_TYPE_IMAGE_CREATE_INFO};
    ici.imageType = VK_IMAGE_TYPE_2D;
    ici.format = format;
    ici.extent = {ci->width, ci->height, 1};
    ici.mipLevels = 1;
    ici.arrayLayers = 1;
    ici.samples = VK_SAMPLE_COUNT_1_BIT;
    ici.tiling = VK_IMAGE_TILING_OPTIMAL;
    ici.usage = usage;
    ici.initialLayout = VK_IMAGE_LAYOUT_UNDEFINED;
    SwapImage img;
    if (vkCreateImage(s->device, &ici, nullptr, &img.image) != VK_SUCCESS) return XR_ERROR_RUNTIME_FAILURE;
    VkMemoryRequirements req;
    vkGetImageMemoryRequirements(s->device, img.image, &req);
    VkMemoryAllocateInfo ai{VK_STRUCTURE_TYPE_MEMORY_ALLOCATE_INFO};
    ai.allocationSize = req.size;
    ai.memoryTypeIndex = UINT32_MAX;
    for (uint32_t t = 0; t < mem.memoryTypeCount && ai.memoryTypeIndex == UINT32_MAX; ++t)
      if ((req.memoryTypeBits & (1u << t)) && (mem.memoryTypes[t].propertyFlags & VK_MEMORY_PROPERTY_DEVICE_LOCAL_BIT))
        ai.memoryTypeIndex = t;
    if (ai.memoryTypeIndex == UINT32_MAX || vkAllocateMemory(s->device, &ai, nullptr, &img.memory) != VK_SUCCESS ||
        vkBindImageMemory(s->device, img.image, img.memory, 0) != VK_SUCCESS) {
      vkDestroyImage(s->device, img.image, nullptr);
      return XR_ERROR_RUNTIME_FAILURE;
    }
    sc->images.push_back(img);
  }
  // The app finds every image in the attachment layout at its first acquire.
  const VkImageAspectFlags aspect = depth ? VK_IMAGE_ASPECT_DEPTH_BIT : VK_IMAGE_ASPECT_COLOR_BIT;
  const VkImageLayout layout =
      depth ? VK_IMAGE_LAYOUT_DEPTH_STENCIL_ATTACHMENT_OPTIMAL : VK_IMAGE_LAYOUT_COLOR_ATTACHMENT_OPTIMAL;
  run_commands(s, [&](VkCommandBuffer cmd) {
    for (const SwapImage& img : sc->images) barrier(cmd, img.image, aspect, VK_IMAGE_LAYOUT_UNDEFINED, layout);
  });
  *out = reinterpret_cast<XrSwapchain>(sc.get());
  s->swapchains.push_back(std::move(sc));
  return XR_SUCCESS;
}

Swapchain* as_swapchain(XrSwapchain h) {
  if (!g_instance || !g_instance->session) return nullptr;
  for (auto& sc : g_instance->session->swapchains)
    if (reinterpret_cast<XrSwapchain>(sc.get()) == h) return sc.get();
  return nullptr;
}

XrResult xrDestroySwapchain(XrSwapchain swapchain) {
  RT_ENTER();
  Swapchain* sc = as_swapchain(swapchain);
  if (!sc) return XR_ERROR_HANDLE_INVALID;
  Session* s = sc->session;
  vkQueueWaitIdle(s->queue);
  for (const SwapImage& img : sc->images) {
    vkDestroyImage(s->device, img.image, nullptr);
    vkFreeMemory(s->device, img.memory, nullptr);
  }
  auto& list = s->swapchains;
  for (auto it = list.begin(); it != list.end(); ++it)
    if (it->get() == sc) {
      list.erase(it);
      break;
    }
  return XR_SUCCESS;
}

XrResult xrEnumerateSwapchainImages(XrSwapchain swapchain, uint32_t capacity, uint32_t* count,
                                    XrSwapchainImageBaseHeader* images) {
  RT_ENTER();
  Swapchain* sc = as_swapchain(swapchain);
  if (!sc) return XR_ERROR_HANDLE_INVALID;
  *count = uint32_t(sc->images.size());
  if (capacity == 0) return XR_SUCCESS;
  if (capacity < sc->images.size()) return XR_ERROR_SIZE_INSUFFICIENT;
  if (images[0].type != XR_TYPE_SWAPCHAIN_IMAGE_VULKAN2_KHR) return XR_ERROR_VALIDATION_FAILURE;
  auto* out = reinterpret_cast<XrSwapchainImageVulkan2KHR*>(images);
  for (size_t i = 0; i < sc->images.size(); ++i) out[i].image = sc->images[i].image;
  return XR_SUCCESS;
}

XrResult xrAcquireSwapchainImage(XrSwapchain swapchain, const XrSwapchainImageAcquireInfo*, uint32_t* index) {
  RT_ENTER();
  Swapchain* sc = as_swapchain(swapchain);
  if (!sc) return XR_ERROR_HANDLE_INVALID;
  if (sc->session->lost) return XR_ERROR_SESSION_LOST;
  if (sc->acquired.size() >= sc->images.size()) return XR_ERROR_CALL_ORDER_INVALID;
  *index = sc->next;
  sc->acquired.push_back(sc->next);
  sc->next = (sc->next + 1) % sc->images.size();
  return XR_SUCCESS;
}

XrResult xrWaitSwapchainImage(XrSwapchain swapchain, const XrSwapchainImageWaitInfo*) {
  RT_ENTER();
  Swapchain* sc = as_swapchain(swapchain);
  if (!sc) return XR_ERROR_HANDLE_INVALID;
  if (sc->session->lost) return XR_ERROR_SESSION_LOST;
  if (sc->acquired.empty() || sc->waited) return XR_ERROR_CALL_ORDER_INVALID;
  sc->waited = true;
  return XR_SUCCESS;
}

XrResult xrReleaseSwapchainImage(XrSwapchain swapchain, const XrSwapchainImageReleaseInfo*) {
  RT_ENTER();
  Swapchain* sc = as_swapchain(swapchain);
  if (!sc) return XR_ERROR_HANDLE_INVALID;
  if (sc->session->lost) return XR_ERROR_SESSION_LOST;
  if (sc->acquired.empty() || !sc->waited) return XR_ERROR_CALL_ORDER_INVALID;
  sc->last_released = sc->acquired.front();
  sc->acquired.pop_front();
  sc->waited = false;
  return XR_SUCCESS;
}

// ---------------------------------------------------------------- frames

XrResult xrWaitFrame(XrSession session, const XrFrameWaitInfo*, XrFrameState* state) {
  RT_ENTER();
  Session* s = as_session(session);
  if (!s) return XR_ERROR_HANDLE_INVALID;
  if (s->lost) return XR_ERROR_SESSION_LOST;
  if (!s->running) return XR_ERROR_SESSION_NOT_RUNNING;
  if (config().loss_frame >= 0 && s->frame >= config().loss_frame && !std::getenv("VXR_TEST_RUNTIME_LOST_ONCE")) {
    setenv("VXR_TEST_RUNTIME_LOST_ONCE", "1", 1);
    s->lost = true;
    push_state(s, XR_SESSION_STATE_LOSS_PENDING);
    return XR_SESSION_LOSS_PENDING;
  }
  s->waited = true;
  state->predictedDisplayTime = kFirstDisplayTime + s->frame * kPeriod;
  state->predictedDisplayPeriod = kPeriod;
  state->shouldRender =
      (s->state == XR_SESSION_STATE_VISIBLE || s->state == XR_SESSION_STATE_FOCUSED) ? XR_TRUE : XR_FALSE;
  return XR_SUCCESS;
}

XrResult xrBeginFrame(XrSession session, const XrFrameBeginInfo*) {
  RT_ENTER();
  Session* s = as_session(session);
  if (!s) return XR_ERROR_HANDLE_INVALID;
  if (s->lost) return XR_ERROR_SESSION_LOST;
  if (!s->running) return XR_ERROR_SESSION_NOT_RUNNING;
  if (!s->waited) return XR_ERROR_CALL_ORDER_INVALID;
  s->waited = false;
  const bool discarded = s->begun;
  s->begun = true;
  return discarded ? XR_FRAME_DISCARDED : XR_SUCCESS;
}

void dump(Session* s, long frame, int eye, Swapchain* sc) {
  const std::string& dir = config().dump_dir;
  if (dir.empty() || sc->last_released < 0) return;
  const uint32_t w = sc->info.width, h = sc->info.height;
  VkBufferCreateInfo bci{VK_STRUCTURE_TYPE_BUFFER_CREATE_INFO};
  bci.size = VkDeviceSize(w) * h * 4;
  bci.usage = VK_BUFFER_USAGE_TRANSFER_DST_BIT;
  VkBuffer buf;
  if (vkCreateBuffer(s->device, &bci, nullptr, &buf) != VK_SUCCESS) return;
  VkMemoryRequirements req;
  vkGetBufferMemoryRequirements(s->device, buf, &req);
  VkPhysicalDeviceMemoryProperties mem;
  vkGetPhysicalDeviceMemoryProperties(s->physical, &mem);
  VkMemoryAllocateInfo ai{VK_STRUCTURE_TYPE_MEMORY_ALLOCATE_INFO};
  ai.allocationSize = req.size;
  const VkMemoryPropertyFlags want = VK_MEMORY_PROPERTY_HOST_VISIBLE_BIT | VK_MEMORY_PROPERTY_HOST_COHERENT_BIT;
  for (uint32_t t = 0; t < mem.memoryTypeCount; ++t)
    if ((req.memoryTypeBits & (1u << t)) && (mem.memoryTypes[t].propertyFlags & want) == want) {
      ai.memoryTypeIndex = t;
      break;
    }
  VkDeviceMemory memory;
  if (vkAllocateMemory(s->device, &ai, nullptr, &memory) != VK_SUCCESS) {
    vkDestroyBuffer(s->device, buf, nullptr);
    return;
  }
  vkBindBufferMemory(s->device, buf, memory, 0);
  const VkImage image = sc->images[sc->last_released].image;
  run_commands(s, [&](VkCommandBuffer cmd) {
    barrier(cmd, image, VK_IMAGE_ASPECT_COLOR_BIT, VK_IMAGE_LAYOUT_COLOR_ATTACHMENT_OPTIMAL,
            VK_IMAGE_LAYOUT_TRANSFER_SRC_OPTIMAL);
    VkBufferImageCopy region{};
    region.imageSubresource = {VK_IMAGE_ASPECT_COLOR_BIT, 0, 0, 1};
    region.imageExtent = {w, h, 1};
    vkCmdCopyImageToBuffer(cmd, image, VK_IMAGE_LAYOUT_TRANSFER_SRC_OPTIMAL, buf, 1, &region);
    barrier(cmd, image, VK_IMAGE_ASPECT_COLOR_BIT, VK_IMAGE_LAYOUT_TRANSFER_SRC_OPTIMAL,
            VK_IMAGE_LAYOUT_COLOR_ATTACHMENT_OPTIMAL);
  });
  void* p = nullptr;
  vkMapMemory(s->device, memory, 0, VK_WHOLE_SIZE, 0, &p);
  vxr::ImageRgba8 img(w, h);
  std::memcpy(img.pixels.data(), p, img.pixels.size());
  vkUnmapMemory(s->device, memory);
  vkDestroyBuffer(s->device, buf, nullptr);
  vkFreeMemory(s->device, memory, nullptr);
  const VkFormat f = VkFormat(sc->info.format);
  if (f == VK_FORMAT_B8G8R8A8_UNORM || f == VK_FORMAT_B8G8R8A8_SRGB)
    for (size_t i = 0; i < img.pixels.size(); i += 4) std::swap(img.pixels[i], img.pixels[i + 2]);
  char name[64];
  std::snprintf(name, sizeof name, "frame%06ld_%s.png", frame, eye == 0 ? "left" : "right");
  std::filesystem::create_directories(dir);
  (void)vxr::write_png((std::filesystem::path(dir) / name).string(), img);
}

XrResult xrEndFrame(XrSession session, const XrFrameEndInfo* ei) {
  RT_ENTER();
  Session* s = as_session(session);
  if (!s) return XR_ERROR_HANDLE_INVALID;
  if (s->lost) return XR_ERROR_SESSION_LOST;
  if (!s->running) return XR_ERROR_SESSION_NOT_RUNNING;
  if (!s->begun) return XR_ERROR_CALL_ORDER_INVALID;
  if (ei->displayTime != kFirstDisplayTime + s->frame * kPeriod) return XR_ERROR_TIME_INVALID;
  if (ei->environmentBlendMode != XR_ENVIRONMENT_BLEND_MODE_OPAQUE) return XR_ERROR_ENVIRONMENT_BLEND_MODE_UNSUPPORTED;
  bool depth = false;
  for (uint32_t l = 0; l < ei->layerCount; ++l) {
    const XrCompositionLayerBaseHeader* layer = ei->layers[l];
    if (!layer) return XR_ERROR_LAYER_INVALID;
    if (layer->type != XR_TYPE_COMPOSITION_LAYER_PROJECTION) return XR_ERROR_LAYER_INVALID;
    const auto* proj = reinterpret_cast<const XrCompositionLayerProjection*>(layer);
    if (proj->viewCount != 2) return XR_ERROR_VALIDATION_FAILURE;
    const auto* space = reinterpret_cast<const Space*>(proj->space);
    if (space && space->kind == Space::kReference)
      s->layer_space = space->ref == XR_REFERENCE_SPACE_TYPE_STAGE ? "STAGE" : "LOCAL";
    for (uint32_t v = 0; v < 2; ++v) {
      Swapchain* sc = as_swapchain(proj->views[v].subImage.swapchain);
      if (!sc || sc->last_released < 0) return XR_ERROR_LAYER_INVALID;
      for (auto* n = static_cast<const XrBaseInStructure*>(proj->views[v].next); n; n = n->next)
        if (n->type == XR_TYPE_COMPOSITION_LAYER_DEPTH_INFO_KHR) {
          const auto* d = reinterpret_cast<const XrCompositionLayerDepthInfoKHR*>(n);
          Swapchain* dsc = as_swapchain(d->subImage.swapchain);
          if (!s->inst->depth_enabled || !dsc || !dsc->depth || dsc->last_released < 0) return XR_ERROR_LAYER_INVALID;
          depth = true;
        }
      if (config().dump_frames.count(s->frame)) dump(s, s->frame, int(v), sc);
    }
  }
  ++s->frames_ended;
  if (ei->layerCount > 0) ++s->frames_with_layers;
  if (depth) ++s->frames_with_depth;
  s->begun = false;
  // The first submitted frame makes the session visible and focused.
  if (s->state == XR_SESSION_STATE_READY && !s->exit_requested) {
    push_state(s, XR_SESSION_STATE_SYNCHRONIZED);
    push_state(s, XR_SESSION_STATE_VISIBLE);
    push_state(s, XR_SESSION_STATE_FOCUSED);
  }
  ++s->frame;
  return XR_SUCCESS;
}

// ---------------------------------------------------------------- actions

XrResult xrCreateActionSet(XrInstance instance, const XrActionSetCreateInfo* ci, XrActionSet* out) {
  RT_ENTER();
  Instance* inst = as_instance(instance);
  if (!inst) return XR_ERROR_HANDLE_INVALID;
  for (const auto& set : inst->action_sets)
    if (set->name == ci->actionSetName) return XR_ERROR_NAME_DUPLICATED;
  auto set = std::make_unique<ActionSet>();
  set->name = ci->actionSetName;
  *out = reinterpret_cast<XrActionSet>(set.get());
  inst->action_sets.push_back(std::move(set));
  return XR_SUCCESS;
}

XrResult xrDestroyActionSet(XrActionSet actionSet) {
  RT_ENTER();
  if (!g_instance) return XR_ERROR_HANDLE_INVALID;
  auto& list = g_instance->action_sets;
  for (auto it = list.begin(); it != list.end(); ++it)
    if (reinterpret_cast<XrActionSet>(it->get()) == actionSet) {
      list.erase(it);
      return XR_SUCCESS;
    }
  return XR_ERROR_HANDLE_INVALID;
}

XrResult xrCreateAction(XrActionSet actionSet, const XrActionCreateInfo* ci, XrAction* out) {
  RT_ENTER();
  auto* set = reinterpret_cast<ActionSet*>(actionSet);
  if (!set) return XR_ERROR_HANDLE_INVALID;
  if (set->attached) return XR_ERROR_ACTIONSETS_ALREADY_ATTACHED;
  auto a = std::make_unique<Action>();
  a->set = set;
  a->name = ci->actionName;
  a->type = ci->actionType;
  a->subactions.assign(ci->subactionPaths, ci->subactionPaths + ci->countSubactionPaths);
  *out = reinterpret_cast<XrAction>(a.get());
  set->actions.push_back(std::move(a));
  return XR_SUCCESS;
}

XrResult xrDestroyAction(XrAction) {
  RT_ENTER();
  return XR_SUCCESS;  // owned by its set
}

XrResult xrSuggestInteractionProfileBindings(XrInstance instance, const XrInteractionProfileSuggestedBinding* sb) {
  RT_ENTER();
  Instance* inst = as_instance(instance);
  if (!inst) return XR_ERROR_HANDLE_INVALID;
  if (sb->interactionProfile == XR_NULL_PATH || sb->interactionProfile >= inst->paths.size())
    return XR_ERROR_PATH_INVALID;
  const std::string profile = inst->paths[sb->interactionProfile];
  if (profile.rfind("/interaction_profiles/", 0) != 0) return XR_ERROR_PATH_UNSUPPORTED;
  auto& list = inst->suggested[profile];
  list.clear();
  for (uint32_t i = 0; i < sb->countSuggestedBindings; ++i) {
    const XrPath p = sb->suggestedBindings[i].binding;
    if (p == XR_NULL_PATH || p >= inst->paths.size()) return XR_ERROR_PATH_INVALID;
    list.emplace_back(reinterpret_cast<Action*>(sb->suggestedBindings[i].action), inst->paths[p]);
  }
  return XR_SUCCESS;
}

XrResult xrAttachSessionActionSets(XrSession session, const XrSessionActionSetsAttachInfo* ai) {
  RT_ENTER();
  Session* s = as_session(session);
  if (!s) return XR_ERROR_HANDLE_INVALID;
  if (s->lost) return XR_ERROR_SESSION_LOST;
  for (uint32_t i = 0; i < ai->countActionSets; ++i) reinterpret_cast<ActionSet*>(ai->actionSets[i])->attached = true;
  // The "controllers in the user's hands": the script's profile, else Touch, else the first suggested.
  const std::string wanted = config().profile.empty() ? "/interaction_profiles/oculus/touch_controller" : config().profile;
  if (s->inst->suggested.count(wanted))
    s->profile = wanted;
  else if (!s->inst->suggested.empty())
    s->profile = s->inst->suggested.begin()->first;
  XrEventDataBuffer buf{XR_TYPE_EVENT_DATA_BUFFER};
  auto* e = reinterpret_cast<XrEventDataInteractionProfileChanged*>(&buf);
  e->type = XR_TYPE_EVENT_DATA_INTERACTION_PROFILE_CHANGED;
  e->next = nullptr;
  e->session = session;
  s->inst->events.push_back(buf);
  return XR_SUCCESS;
}

XrResult xrGetCurrentInteractionProfile(XrSession session, XrPath topLevelUserPath, XrInteractionProfileState* st) {
  RT_ENTER();
  Session* s = as_session(session);
  if (!s) return XR_ERROR_HANDLE_INVALID;
  if (topLevelUserPath == XR_NULL_PATH || topLevelUserPath >= s->inst->paths.size()) return XR_ERROR_PATH_INVALID;
  st->interactionProfile = XR_NULL_PATH;
  if (!s->profile.empty()) st->interactionProfile = s->inst->path_ids[s->profile];
  return XR_SUCCESS;
}

XrResult xrSyncActions(XrSession session, const XrActionsSyncInfo*) {
  RT_ENTER();
  Session* s = as_session(session);
  if (!s) return XR_ERROR_HANDLE_INVALID;
  if (s->lost) return XR_ERROR_SESSION_LOST;
  if (s->state != XR_SESSION_STATE_FOCUSED) return XR_SESSION_NOT_FOCUSED;
  s->synced_frame = s->frame;
  return XR_SUCCESS;
}

// The value of `action` for `hand` from the script, by what the binding points at.
struct Value {
  bool active = false;
  float x = 0, y = 0;
};

// The script's value for the physical control a binding path names (xr/script.h).
// A Vive's trackpad is the script's thumbstick, its click "thumbstick_click".
double control_value(const std::string& path, const ScriptHand& sh, bool trackpad_is_stick) {
  auto is = [&](const char* control) { return path.rfind(control, 0) == 0; };
  if (is("/input/squeeze") || is("/input/select")) return sh.squeeze;
  if (is("/input/trigger")) return sh.trigger;
  if (is("/input/thumbstick/click")) return sh.thumbstick_click ? 1.0 : 0.0;
  if (is("/input/trackpad/click")) return (trackpad_is_stick ? sh.thumbstick_click : sh.trackpad_click) ? 1.0 : 0.0;
  if (is("/input/menu/")) return sh.menu ? 1.0 : 0.0;
  if (is("/input/a/") || is("/input/x/")) return sh.a ? 1.0 : 0.0;
  if (is("/input/b/") || is("/input/y/")) return sh.b ? 1.0 : 0.0;
  return 0.0;
}

Value read_value(Session* s, XrAction action, XrPath subaction) {
  Value v;
  const Action* a = reinterpret_cast<const Action*>(action);
  if (s->state != XR_SESSION_STATE_FOCUSED || s->synced_frame < 0) return v;
  int h = hand_of(s, subaction);
  if (h == -2) return v;
  const ScriptFrame f = script_at(s->synced_frame);
  for (int hand = 0; hand < 2; ++hand) {
    if (h >= 0 && hand != h) continue;
    const std::string path = bound_path(s, a, hand);
    if (path.empty()) continue;
    const ScriptHand& sh = f.hands[hand];
    const bool click = path.find("/click") != std::string::npos;
    auto as = [&](double value) { return float(click ? (value >= 0.5 ? 1.0 : 0.0) : value); };
    v.active = true;
    if (path == "/input/thumbstick" || path == "/input/trackpad") {
      v.x = float(sh.thumbstick.x);
      v.y = float(sh.thumbstick.y);
    } else {
      v.x = std::max(v.x, as(control_value(path, sh, s->profile == "/interaction_profiles/htc/vive_controller")));
    }
  }
  return v;
}

Action* checked_action(XrAction a, XrActionType type) {
  auto* action = reinterpret_cast<Action*>(a);
  return action && action->type == type ? action : nullptr;
}

XrResult xrGetActionStateBoolean(XrSession session, const XrActionStateGetInfo* gi, XrActionStateBoolean* st) {
  RT_ENTER();
  Session* s = as_session(session);
  if (!s) return XR_ERROR_HANDLE_INVALID;
  if (!checked_action(gi->action, XR_ACTION_TYPE_BOOLEAN_INPUT)) return XR_ERROR_ACTION_TYPE_MISMATCH;
  const Value v = read_value(s, gi->action, gi->subactionPath);
  st->isActive = v.active;
  st->currentState = v.x >= 0.5f;
  st->changedSinceLastSync = XR_FALSE;
  st->lastChangeTime = 0;
  return XR_SUCCESS;
}

XrResult xrGetActionStateFloat(XrSession session, const XrActionStateGetInfo* gi, XrActionStateFloat* st) {
  RT_ENTER();
  Session* s = as_session(session);
  if (!s) return XR_ERROR_HANDLE_INVALID;
  if (!checked_action(gi->action, XR_ACTION_TYPE_FLOAT_INPUT)) return XR_ERROR_ACTION_TYPE_MISMATCH;
  const Value v = read_value(s, gi->action, gi->subactionPath);
  st->isActive = v.active;
  st->currentState = v.x;
  st->changedSinceLastSync = XR_FALSE;
  st->lastChangeTime = 0;
  return XR_SUCCESS;
}

XrResult xrGetActionStateVector2f(XrSession session, const XrActionStateGetInfo* gi, XrActionStateVector2f* st) {
  RT_ENTER();
  Session* s = as_session(session);
  if (!s) return XR_ERROR_HANDLE_INVALID;
  if (!checked_action(gi->action, XR_ACTION_TYPE_VECTOR2F_INPUT)) return XR_ERROR_ACTION_TYPE_MISMATCH;
  const Value v = read_value(s, gi->action, gi->subactionPath);
  st->isActive = v.active;
  st->currentState = {v.x, v.y};
  st->changedSinceLastSync = XR_FALSE;
  st->lastChangeTime = 0;
  return XR_SUCCESS;
}

XrResult xrGetActionStatePose(XrSession session, const XrActionStateGetInfo* gi, XrActionStatePose* st) {
  RT_ENTER();
  Session* s = as_session(session);
  if (!s) return XR_ERROR_HANDLE_INVALID;
  if (!checked_action(gi->action, XR_ACTION_TYPE_POSE_INPUT)) return XR_ERROR_ACTION_TYPE_MISMATCH;
  st->isActive = read_value(s, gi->action, gi->subactionPath).active;
  return XR_SUCCESS;
}

XrResult xrApplyHapticFeedback(XrSession session, const XrHapticActionInfo* hi, const XrHapticBaseHeader* h) {
  RT_ENTER();
  Session* s = as_session(session);
  if (!s) return XR_ERROR_HANDLE_INVALID;
  if (s->lost) return XR_ERROR_SESSION_LOST;
  if (!checked_action(hi->action, XR_ACTION_TYPE_VIBRATION_OUTPUT)) return XR_ERROR_ACTION_TYPE_MISMATCH;
  if (!h || h->type != XR_TYPE_HAPTIC_VIBRATION) return XR_ERROR_VALIDATION_FAILURE;
  if (s->state == XR_SESSION_STATE_FOCUSED) ++s->haptics;
  return XR_SUCCESS;
}

XrResult xrStopHapticFeedback(XrSession session, const XrHapticActionInfo*) {
  RT_ENTER();
  return as_session(session) ? XR_SUCCESS : XR_ERROR_HANDLE_INVALID;
}

// ---------------------------------------------------------------- dispatch

struct Entry {
  const char* name;
  PFN_xrVoidFunction fn;
};

#define RT_FN(f) {#f, reinterpret_cast<PFN_xrVoidFunction>(&f)}
const Entry kEntries[] = {
    RT_FN(xrGetInstanceProcAddr), RT_FN(xrEnumerateInstanceExtensionProperties), RT_FN(xrCreateInstance),
    RT_FN(xrDestroyInstance), RT_FN(xrGetInstanceProperties), RT_FN(xrPollEvent), RT_FN(xrResultToString),
    RT_FN(xrStructureTypeToString), RT_FN(xrStringToPath), RT_FN(xrPathToString), RT_FN(xrGetSystem),
    RT_FN(xrGetSystemProperties), RT_FN(xrEnumerateViewConfigurations), RT_FN(xrGetViewConfigurationProperties),
    RT_FN(xrEnumerateViewConfigurationViews), RT_FN(xrEnumerateEnvironmentBlendModes),
    RT_FN(xrGetVulkanGraphicsRequirements2KHR), RT_FN(xrCreateVulkanInstanceKHR), RT_FN(xrGetVulkanGraphicsDevice2KHR),
    RT_FN(xrCreateVulkanDeviceKHR), RT_FN(xrCreateSession), RT_FN(xrDestroySession), RT_FN(xrBeginSession),
    RT_FN(xrEndSession), RT_FN(xrRequestExitSession), RT_FN(xrEnumerateReferenceSpaces), RT_FN(xrCreateReferenceSpace),
    RT_FN(xrCreateActionSpace), RT_FN(xrDestroySpace), RT_FN(xrLocateSpace), RT_FN(xrGetReferenceSpaceBoundsRect),
    RT_FN(xrLocateViews), RT_FN(xrEnumerateSwapchainFormats), RT_FN(xrCreateSwapchain), RT_FN(xrDestroySwapchain),
    RT_FN(xrEnumerateSwapchainImages), RT_FN(xrAcquireSwapchainImage), RT_FN(xrWaitSwapchainImage),
    RT_FN(xrReleaseSwapchainImage), RT_FN(xrWaitFrame), RT_FN(xrBeginFrame), RT_FN(xrEndFrame),
    RT_FN(xrCreateActionSet), RT_FN(xrDestroyActionSet), RT_FN(xrCreateAction), RT_FN(xrDestroyAction),
    RT_FN(xrSuggestInteractionProfileBindings), RT_FN(xrAttachSessionActionSets), RT_FN(xrGetCurrentInteractionProfile),
    RT_FN(xrSyncActions), RT_FN(xrGetActionStateBoolean), RT_FN(xrGetActionStateFloat), RT_FN(xrGetActionStateVector2f),
    RT_FN(xrGetActionStatePose), RT_FN(xrApplyHapticFeedback), RT_FN(xrStopHapticFeedback),
};
#undef RT_FN

XrResult xrGetInstanceProcAddr(XrInstance instance, const char* name, PFN_xrVoidFunction* function) {
  if (!name || !function) return XR_ERROR_VALIDATION_FAILURE;
  *function = nullptr;
  const std::string n = name;
  const bool global = n == "xrEnumerateInstanceExtensionProperties" || n == "xrEnumerateApiLayerProperties" ||
                      n == "xrCreateInstance";
  if (instance == XR_NULL_HANDLE && !global) return XR_ERROR_HANDLE_INVALID;
  // The legacy XR_KHR_vulkan_enable path is not offered: lavapipe lacks the external fd extensions it needs.
  for (const Entry& e : kEntries)
    if (n == e.name) {
      *function = e.fn;
      return XR_SUCCESS;
    }
  return XR_ERROR_FUNCTION_UNSUPPORTED;
}

}  // namespace rt

extern "C" XrResult xrNegotiateLoaderRuntimeInterface(const XrNegotiateLoaderInfo* info,
                                                      XrNegotiateRuntimeRequest* request) {
  if (!info || !request || info->structType != XR_LOADER_INTERFACE_STRUCT_LOADER_INFO ||
      info->structVersion != 1 || info->structSize != sizeof(XrNegotiateLoaderInfo) ||
      request->structType != XR_LOADER_INTERFACE_STRUCT_RUNTIME_REQUEST || request->structVersion != 1 ||
      request->structSize != sizeof(XrNegotiateRuntimeRequest) || info->minInterfaceVersion > 1 ||
      info->maxInterfaceVersion < 1 || info->minApiVersion > XR_CURRENT_API_VERSION)
    return XR_ERROR_INITIALIZATION_FAILED;
  request->runtimeInterfaceVersion = 1;
  request->runtimeApiVersion = XR_CURRENT_API_VERSION;
  request->getInstanceProcAddr = rt::xrGetInstanceProcAddr;
  return XR_SUCCESS;
}
