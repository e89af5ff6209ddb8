#include "xr/openxr/openxr_target.h"

#include <chrono>
#include <cmath>
#include <cstring>
#include <thread>

#include "core/log.h"
#include "core/trace.h"
#include "xr/eye_renderer.h"

namespace vxr::xr {
namespace {

constexpr XrViewConfigurationType kViewConfig = XR_VIEW_CONFIGURATION_TYPE_PRIMARY_STEREO;
constexpr double kNearZ = 0.05, kFarZ = 100.0;

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

// Picks the first of `preferred` that the runtime offers.
template <typename T>
T pick(const std::vector<int64_t>& offered, std::initializer_list<T> preferred, T none) {
  for (T p : preferred)
    for (int64_t o : offered)
      if (o == int64_t(p)) return p;
  return none;
}

}  // namespace

template <typename T>
T OpenXrTarget::proc(const char* name) {
  PFN_xrVoidFunction fn = nullptr;
  if (XR_FAILED(xrGetInstanceProcAddr(instance_, name, &fn))) return nullptr;
  return reinterpret_cast<T>(fn);
}

Result<std::unique_ptr<OpenXrTarget>> OpenXrTarget::create(const OpenXrOptions& options) {
  std::unique_ptr<OpenXrTarget> t(new OpenXrTarget(options));
  VXR_RETURN_IF_ERROR(t->init_instance());
  return t;
}

Status OpenXrTarget::init_instance() {
  uint32_t n = 0;
  VXR_XR_CALL(errors_, xrEnumerateInstanceExtensionProperties, (nullptr, 0, &n, nullptr));
  std::vector<XrExtensionProperties> exts(n, {XR_TYPE_EXTENSION_PROPERTIES});
  VXR_XR_CALL(errors_, xrEnumerateInstanceExtensionProperties, (nullptr, n, &n, exts.data()));
  bool enable2 = false;
  for (const auto& e : exts) {
    if (!std::strcmp(e.extensionName, XR_KHR_VULKAN_ENABLE2_EXTENSION_NAME)) enable2 = true;
    if (!std::strcmp(e.extensionName, XR_KHR_COMPOSITION_LAYER_DEPTH_EXTENSION_NAME)) depth_extension_ = true;
  }
  if (!enable2)
    return unsupported("OpenXR: the runtime does not offer XR_KHR_vulkan_enable2, which vxr needs (update the runtime)");
  std::vector<const char*> enabled = {XR_KHR_VULKAN_ENABLE2_EXTENSION_NAME};
  if (depth_extension_ && o_.use_depth) enabled.push_back(XR_KHR_COMPOSITION_LAYER_DEPTH_EXTENSION_NAME);

  XrInstanceCreateInfo ci{XR_TYPE_INSTANCE_CREATE_INFO};
  std::strcpy(ci.applicationInfo.applicationName, "vxr");
  ci.applicationInfo.applicationVersion = 1;
  std::strcpy(ci.applicationInfo.engineName, "vxr");
  ci.applicationInfo.apiVersion = XR_CURRENT_API_VERSION;
  ci.enabledExtensionCount = static_cast<uint32_t>(enabled.size());
  ci.enabledExtensionNames = enabled.data();
  VXR_XR_CALL(errors_, xrCreateInstance, (&ci, &instance_));

  XrInstanceProperties ip{XR_TYPE_INSTANCE_PROPERTIES};
  VXR_XR_CALL(errors_, xrGetInstanceProperties, (instance_, &ip));
  runtime_name_ = ip.runtimeName;

  XrSystemGetInfo si{XR_TYPE_SYSTEM_GET_INFO};
  si.formFactor = XR_FORM_FACTOR_HEAD_MOUNTED_DISPLAY;
  VXR_XR_CALL(errors_, xrGetSystem, (instance_, &si, &system_));
  XrSystemProperties sp{XR_TYPE_SYSTEM_PROPERTIES};
  VXR_XR_CALL(errors_, xrGetSystemProperties, (instance_, system_, &sp));
  system_name_ = sp.systemName;

  VXR_RETURN_IF_ERROR(actions_.create(instance_, errors_));
  actions_created_ = true;
  return Status::ok();
}

OpenXrTarget::~OpenXrTarget() {
  detach();
  if (instance_) xrDestroyInstance(instance_);
}

std::string OpenXrTarget::describe() const {
  std::string s = "OpenXR (runtime " + runtime_name_ + ", system " + system_name_;
  if (session_) {
    s += std::string(", ") + (space_type_ == XR_REFERENCE_SPACE_TYPE_STAGE ? "STAGE" : "LOCAL") + " space";
    s += depth_enabled_ ? ", depth layers" : ", no depth layers";
    if (!color_.empty()) s += ", " + std::to_string(color_[0].width) + "x" + std::to_string(color_[0].height) + " per eye";
    if (!profile_.empty()) s += ", controllers " + profile_;
  }
  return s + ")";
}

Status OpenXrTarget::prepare_context(gpu::ContextOptions& options) {
  auto get_reqs = proc<PFN_xrGetVulkanGraphicsRequirements2KHR>("xrGetVulkanGraphicsRequirements2KHR");
  auto create_instance = proc<PFN_xrCreateVulkanInstanceKHR>("xrCreateVulkanInstanceKHR");
  auto get_device = proc<PFN_xrGetVulkanGraphicsDevice2KHR>("xrGetVulkanGraphicsDevice2KHR");
  auto create_device = proc<PFN_xrCreateVulkanDeviceKHR>("xrCreateVulkanDeviceKHR");
  if (!get_reqs || !create_instance || !get_device || !create_device)
    return unsupported("OpenXR: the runtime lists XR_KHR_vulkan_enable2 but does not provide its functions");

  XrGraphicsRequirementsVulkan2KHR reqs{XR_TYPE_GRAPHICS_REQUIREMENTS_VULKAN2_KHR};
  VXR_XR_CALL(errors_, get_reqs, (instance_, system_, &reqs));
  if (reqs.minApiVersionSupported > XR_MAKE_VERSION(1, 3, 0))
    return unsupported("OpenXR: the runtime needs Vulkan " + std::to_string(XR_VERSION_MAJOR(reqs.minApiVersionSupported)) +
                       "." + std::to_string(XR_VERSION_MINOR(reqs.minApiVersionSupported)) + ", vxr uses 1.3");

  options.hooks.create_instance = [this, create_instance](const VkInstanceCreateInfo& vci) -> Result<VkInstance> {
    XrVulkanInstanceCreateInfoKHR ci{XR_TYPE_VULKAN_INSTANCE_CREATE_INFO_KHR};
    ci.systemId = system_;
    ci.pfnGetInstanceProcAddr = &vkGetInstanceProcAddr;
    ci.vulkanCreateInfo = &vci;
    VkInstance vk = VK_NULL_HANDLE;
    VkResult vr = VK_SUCCESS;
    VXR_XR_CALL(errors_, create_instance, (instance_, &ci, &vk, &vr));
    if (vr != VK_SUCCESS) return gpu_error("OpenXR: the runtime's vkCreateInstance failed (VkResult " + std::to_string(vr) + ")");
    return vk;
  };
  options.hooks.pick_physical_device = [this, get_device](VkInstance vk) -> Result<VkPhysicalDevice> {
    XrVulkanGraphicsDeviceGetInfoKHR gi{XR_TYPE_VULKAN_GRAPHICS_DEVICE_GET_INFO_KHR};
    gi.systemId = system_;
    gi.vulkanInstance = vk;
    VkPhysicalDevice pd = VK_NULL_HANDLE;
    VXR_XR_CALL(errors_, get_device, (instance_, &gi, &pd));
    return pd;
  };
  options.hooks.create_device = [this, create_device](VkPhysicalDevice pd,
                                                      const VkDeviceCreateInfo& dci) -> Result<VkDevice> {
    XrVulkanDeviceCreateInfoKHR ci{XR_TYPE_VULKAN_DEVICE_CREATE_INFO_KHR};
    ci.systemId = system_;
    ci.pfnGetInstanceProcAddr = &vkGetInstanceProcAddr;
    ci.vulkanPhysicalDevice = pd;
    ci.vulkanCreateInfo = &dci;
    VkDevice dev = VK_NULL_HANDLE;
    VkResult vr = VK_SUCCESS;
    VXR_XR_CALL(errors_, create_device, (instance_, &ci, &dev, &vr));
    if (vr != VK_SUCCESS) return gpu_error("OpenXR: the runtime's vkCreateDevice failed (VkResult " + std::to_string(vr) + ")");
    return dev;
  };
  return Status::ok();
}

Status OpenXrTarget::attach(gpu::Context& ctx) {
  ctx_ = &ctx;
  XrGraphicsBindingVulkan2KHR binding{XR_TYPE_GRAPHICS_BINDING_VULKAN2_KHR};
  binding.instance = ctx.instance();
  binding.physicalDevice = ctx.physical_device();
  binding.device = ctx.device();
  binding.queueFamilyIndex = ctx.queue_family();
  binding.queueIndex = 0;
  XrSessionCreateInfo sci{XR_TYPE_SESSION_CREATE_INFO};
  sci.next = &binding;
  sci.systemId = system_;
  VXR_XR_CALL(errors_, xrCreateSession, (instance_, &sci, &session_));
  state_ = XR_SESSION_STATE_UNKNOWN;

  uint32_t n = 0;
  VXR_XR_CALL(errors_, xrEnumerateReferenceSpaces, (session_, 0, &n, nullptr));
  std::vector<XrReferenceSpaceType> spaces(n);
  VXR_XR_CALL(errors_, xrEnumerateReferenceSpaces, (session_, n, &n, spaces.data()));
  space_type_ = XR_REFERENCE_SPACE_TYPE_LOCAL;
  for (auto s : spaces)
    if (s == XR_REFERENCE_SPACE_TYPE_STAGE) space_type_ = XR_REFERENCE_SPACE_TYPE_STAGE;
  XrReferenceSpaceCreateInfo rci{XR_TYPE_REFERENCE_SPACE_CREATE_INFO};
  rci.referenceSpaceType = space_type_;
  rci.poseInReferenceSpace.orientation.w = 1.0f;
  if (space_type_ == XR_REFERENCE_SPACE_TYPE_LOCAL) rci.poseInReferenceSpace.position.y = -1.6f;  // LOCAL starts at the head: put the floor 1.6 m below
  VXR_XR_CALL(errors_, xrCreateReferenceSpace, (session_, &rci, &space_));

  VXR_RETURN_IF_ERROR(actions_.attach(session_, errors_));

  VXR_XR_CALL(errors_, xrEnumerateViewConfigurations, (instance_, system_, 0, &n, nullptr));
  std::vector<XrViewConfigurationType> configs(n);
  VXR_XR_CALL(errors_, xrEnumerateViewConfigurations, (instance_, system_, n, &n, configs.data()));
  bool stereo = false;
  for (auto c : configs) stereo |= c == kViewConfig;
  if (!stereo) return unsupported("OpenXR: the system has no PRIMARY_STEREO view configuration");
  VXR_XR_CALL(errors_, xrEnumerateViewConfigurationViews, (instance_, system_, kViewConfig, 0, &n, nullptr));
  config_views_.assign(n, {XR_TYPE_VIEW_CONFIGURATION_VIEW});
  VXR_XR_CALL(errors_, xrEnumerateViewConfigurationViews, (instance_, system_, kViewConfig, n, &n, config_views_.data()));
  views_.assign(n, {XR_TYPE_VIEW});
  return create_swapchains();
}

Status OpenXrTarget::create_swapchains() {
  uint32_t n = 0;
  VXR_XR_CALL(errors_, xrEnumerateSwapchainFormats, (session_, 0, &n, nullptr));
  std::vector<int64_t> formats(n);
  VXR_XR_CALL(errors_, xrEnumerateSwapchainFormats, (session_, n, &n, formats.data()));
  // sRGB first: compositors treat swapchain values as linear light, and an
  // sRGB image stores the renderer's linear values encoded (the renderer
  // blits unrounded floats into it); UNORM is the fallback (rounded bytes).
  const VkFormat color = pick<VkFormat>(formats, {VK_FORMAT_R8G8B8A8_SRGB, VK_FORMAT_B8G8R8A8_SRGB,
                                                  VK_FORMAT_R8G8B8A8_UNORM, VK_FORMAT_B8G8R8A8_UNORM},
                                        VK_FORMAT_UNDEFINED);
  if (color == VK_FORMAT_UNDEFINED)
    return unsupported("OpenXR: the runtime offers no 8-bit RGBA/BGRA swapchain format");
  const VkFormat depth = depth_extension_ && o_.use_depth
                             ? pick<VkFormat>(formats, {VK_FORMAT_D32_SFLOAT, VK_FORMAT_D16_UNORM}, VK_FORMAT_UNDEFINED)
                             : VK_FORMAT_UNDEFINED;
  depth_enabled_ = depth != VK_FORMAT_UNDEFINED;

  auto make = [&](VkFormat format, XrSwapchainUsageFlags usage, uint32_t w, uint32_t h, Swapchain& sc) -> Status {
    XrSwapchainCreateInfo ci{XR_TYPE_SWAPCHAIN_CREATE_INFO};
    ci.usageFlags = usage;
    ci.format = format;
    ci.sampleCount = 1;
    ci.width = w;
    ci.height = h;
    ci.faceCount = 1;
    ci.arraySize = 1;
    ci.mipCount = 1;
    sc.format = format;
    sc.width = w;
    sc.height = h;
    VXR_XR_CALL(errors_, xrCreateSwapchain, (session_, &ci, &sc.handle));
    uint32_t count = 0;
    VXR_XR_CALL(errors_, xrEnumerateSwapchainImages, (sc.handle, 0, &count, nullptr));
    std::vector<XrSwapchainImageVulkan2KHR> images(count, {XR_TYPE_SWAPCHAIN_IMAGE_VULKAN2_KHR});
    VXR_XR_CALL(errors_, xrEnumerateSwapchainImages,
                (sc.handle, count, &count, reinterpret_cast<XrSwapchainImageBaseHeader*>(images.data())));
    for (const auto& i : images) sc.images.push_back(i.image);
    return Status::ok();
  };
  color_.resize(config_views_.size());
  depth_.resize(depth_enabled_ ? config_views_.size() : 0);
  for (size_t v = 0; v < config_views_.size(); ++v) {
    uint32_t w = config_views_[v].recommendedImageRectWidth, h = config_views_[v].recommendedImageRectHeight;
    if (o_.max_eye_width) w = std::min(w, o_.max_eye_width);
    if (o_.max_eye_height) h = std::min(h, o_.max_eye_height);
    XrSwapchainUsageFlags usage = XR_SWAPCHAIN_USAGE_COLOR_ATTACHMENT_BIT | XR_SWAPCHAIN_USAGE_TRANSFER_DST_BIT;
    if (o_.readable) usage |= XR_SWAPCHAIN_USAGE_TRANSFER_SRC_BIT;
    VXR_RETURN_IF_ERROR(make(color, usage, w, h, color_[v]));
    if (depth_enabled_)
      VXR_RETURN_IF_ERROR(make(depth,
                               XR_SWAPCHAIN_USAGE_DEPTH_STENCIL_ATTACHMENT_BIT | XR_SWAPCHAIN_USAGE_TRANSFER_DST_BIT,
                               w, h, depth_[v]));
  }
  return Status::ok();
}

Status OpenXrTarget::handle_event(const XrEventDataBuffer& event) {
  switch (event.type) {
    case XR_TYPE_EVENT_DATA_SESSION_STATE_CHANGED: {
      const auto& e = reinterpret_cast<const XrEventDataSessionStateChanged&>(event);
      state_ = e.state;
      log_debug(std::string("OpenXR: session state ") + state_name(state_));
      switch (state_) {
        case XR_SESSION_STATE_READY: {
          XrSessionBeginInfo bi{XR_TYPE_SESSION_BEGIN_INFO};
          bi.primaryViewConfigurationType = kViewConfig;
          VXR_XR_CALL(errors_, xrBeginSession, (session_, &bi));
          running_ = true;
          break;
        }
        case XR_SESSION_STATE_STOPPING:
          VXR_XR_CALL(errors_, xrEndSession, (session_));
          running_ = false;
          break;
        case XR_SESSION_STATE_EXITING: exit_ = true; break;
        case XR_SESSION_STATE_LOSS_PENDING:
          errors_.mark_lost();
          return gpu_error("OpenXR: the runtime is losing the session (LOSS_PENDING)");
        default: break;
      }
      break;
    }
    case XR_TYPE_EVENT_DATA_INSTANCE_LOSS_PENDING:
      errors_.mark_lost();
      return gpu_error("OpenXR: the runtime is losing the instance (INSTANCE_LOSS_PENDING)");
    case XR_TYPE_EVENT_DATA_INTERACTION_PROFILE_CHANGED:
      profile_ = actions_.current_profile(instance_, session_, errors_);
      log_debug("OpenXR: controllers " + profile_);
      break;
    case XR_TYPE_EVENT_DATA_EVENTS_LOST: log_warn("OpenXR: the runtime dropped events"); break;
    default: break;
  }
  return Status::ok();
}

Status OpenXrTarget::poll_events() {
  for (;;) {
    XrEventDataBuffer event{XR_TYPE_EVENT_DATA_BUFFER};
    const XrResult r = xrPollEvent(instance_, &event);
    if (r == XR_EVENT_UNAVAILABLE) return Status::ok();
    if (XR_FAILED(r)) return errors_.fail(r, "xrPollEvent", __FILE__, __LINE__);
    VXR_RETURN_IF_ERROR(handle_event(event));
  }
}

Result<FrameState> OpenXrTarget::wait_frame() {
  VXR_TRACE_SCOPE("openxr.wait_frame");
  FrameState f;
  const auto start = std::chrono::steady_clock::now();
  for (;;) {
    VXR_RETURN_IF_ERROR(poll_events());
    if (exit_) {
      f.exit = true;
      return f;
    }
    if (running_) break;
    if (std::chrono::steady_clock::now() - start > std::chrono::seconds(60))
      return gpu_error(std::string("OpenXR: the session stayed ") + state_name(state_) +
                       " for 60 s without becoming ready; is the headset on and the runtime's compositor running?");
    std::this_thread::sleep_for(std::chrono::milliseconds(5));
  }

  XrFrameWaitInfo wi{XR_TYPE_FRAME_WAIT_INFO};
  frame_state_ = {XR_TYPE_FRAME_STATE};
  VXR_XR_CALL(errors_, xrWaitFrame, (session_, &wi, &frame_state_));
  XrFrameBeginInfo bi{XR_TYPE_FRAME_BEGIN_INFO};
  VXR_XR_CALL(errors_, xrBeginFrame, (session_, &bi));
  frame_begun_ = true;
  f.display_time_ns = frame_state_.predictedDisplayTime;

  if (state_ == XR_SESSION_STATE_FOCUSED)
    VXR_RETURN_IF_ERROR(actions_.read(session_, space_, frame_state_.predictedDisplayTime, f.input, errors_));

  if (frame_state_.shouldRender) {
    XrViewLocateInfo li{XR_TYPE_VIEW_LOCATE_INFO};
    li.viewConfigurationType = kViewConfig;
    li.displayTime = frame_state_.predictedDisplayTime;
    li.space = space_;
    XrViewState vs{XR_TYPE_VIEW_STATE};
    uint32_t n = 0;
    for (auto& v : views_) v = {XR_TYPE_VIEW};
    VXR_XR_CALL(errors_, xrLocateViews, (session_, &li, &vs, uint32_t(views_.size()), &n, views_.data()));
    const XrViewStateFlags need = XR_VIEW_STATE_POSITION_VALID_BIT | XR_VIEW_STATE_ORIENTATION_VALID_BIT;
    if ((vs.viewStateFlags & need) == need && n == color_.size()) {
      f.should_render = true;
      for (uint32_t v = 0; v < n; ++v) {
        const XrFovf& fov = views_[v].fov;
        f.views.push_back({to_pose(views_[v].pose), Fov{fov.angleLeft, fov.angleRight, fov.angleUp, fov.angleDown},
                           color_[v].width, color_[v].height});
      }
    }
  }
  return f;
}

Result<TargetImage> OpenXrTarget::acquire(size_t view) {
  if (view >= color_.size()) return out_of_range("OpenXR: no swapchain for view " + std::to_string(view));
  Swapchain& sc = color_[view];
  XrSwapchainImageAcquireInfo ai{XR_TYPE_SWAPCHAIN_IMAGE_ACQUIRE_INFO};
  VXR_XR_CALL(errors_, xrAcquireSwapchainImage, (sc.handle, &ai, &sc.acquired));
  XrSwapchainImageWaitInfo wi{XR_TYPE_SWAPCHAIN_IMAGE_WAIT_INFO};
  wi.timeout = XR_INFINITE_DURATION;
  VXR_XR_CALL(errors_, xrWaitSwapchainImage, (sc.handle, &wi));
  return TargetImage{sc.images[sc.acquired], sc.format, {sc.width, sc.height},
                     VK_IMAGE_LAYOUT_COLOR_ATTACHMENT_OPTIMAL};
}

Status OpenXrTarget::clear_depth(Swapchain& sc, const ViewSpec& view, const glm::dvec3& focus) {
  XrSwapchainImageAcquireInfo ai{XR_TYPE_SWAPCHAIN_IMAGE_ACQUIRE_INFO};
  uint32_t index = 0;
  VXR_XR_CALL(errors_, xrAcquireSwapchainImage, (sc.handle, &ai, &index));
  XrSwapchainImageWaitInfo wi{XR_TYPE_SWAPCHAIN_IMAGE_WAIT_INFO};
  wi.timeout = XR_INFINITE_DURATION;
  VXR_XR_CALL(errors_, xrWaitSwapchainImage, (sc.handle, &wi));
  // One plane through the volume's centre: enough for the compositor to
  // reproject the volume at the right distance.
  const double z = std::clamp(-view.pose.inverse().apply(focus).z, kNearZ, kFarZ);
  VkClearDepthStencilValue value{static_cast<float>(kFarZ * (z - kNearZ) / (z * (kFarZ - kNearZ))), 0};
  const VkImage image = sc.images[index];
  VXR_RETURN_IF_ERROR(ctx_->submit_and_wait([&](VkCommandBuffer cmd) {
    image_barrier(cmd, image, VK_IMAGE_ASPECT_DEPTH_BIT, VK_IMAGE_LAYOUT_DEPTH_STENCIL_ATTACHMENT_OPTIMAL,
                  VK_IMAGE_LAYOUT_TRANSFER_DST_OPTIMAL);
    VkImageSubresourceRange range{VK_IMAGE_ASPECT_DEPTH_BIT, 0, 1, 0, 1};
    vkCmdClearDepthStencilImage(cmd, image, VK_IMAGE_LAYOUT_TRANSFER_DST_OPTIMAL, &value, 1, &range);
    image_barrier(cmd, image, VK_IMAGE_ASPECT_DEPTH_BIT, VK_IMAGE_LAYOUT_TRANSFER_DST_OPTIMAL,
                  VK_IMAGE_LAYOUT_DEPTH_STENCIL_ATTACHMENT_OPTIMAL);
  }));
  XrSwapchainImageReleaseInfo ri{XR_TYPE_SWAPCHAIN_IMAGE_RELEASE_INFO};
  VXR_XR_CALL(errors_, xrReleaseSwapchainImage, (sc.handle, &ri));
  return Status::ok();
}

Status OpenXrTarget::end_frame(const FrameState& frame, const FrameContent& content) {
  VXR_TRACE_SCOPE("openxr.end_frame");
  if (!frame_begun_) return Status::ok();
  frame_begun_ = false;
  bool submit = frame.should_render;
  for (Swapchain& sc : color_) {
    if (sc.acquired == UINT32_MAX) {
      submit = false;
      continue;
    }
    XrSwapchainImageReleaseInfo ri{XR_TYPE_SWAPCHAIN_IMAGE_RELEASE_INFO};
    sc.acquired = UINT32_MAX;
    VXR_XR_CALL(errors_, xrReleaseSwapchainImage, (sc.handle, &ri));
  }
  std::vector<XrCompositionLayerProjectionView> pviews(color_.size(), {XR_TYPE_COMPOSITION_LAYER_PROJECTION_VIEW});
  std::vector<XrCompositionLayerDepthInfoKHR> dinfo(depth_.size(), {XR_TYPE_COMPOSITION_LAYER_DEPTH_INFO_KHR});
  XrCompositionLayerProjection layer{XR_TYPE_COMPOSITION_LAYER_PROJECTION};
  const XrCompositionLayerBaseHeader* layers[1] = {reinterpret_cast<XrCompositionLayerBaseHeader*>(&layer)};
  if (submit) {
    for (size_t v = 0; v < color_.size(); ++v) {
      pviews[v].pose = views_[v].pose;
      pviews[v].fov = views_[v].fov;
      pviews[v].subImage.swapchain = color_[v].handle;
      pviews[v].subImage.imageRect = {{0, 0}, {int32_t(color_[v].width), int32_t(color_[v].height)}};
      if (depth_enabled_) {
        VXR_RETURN_IF_ERROR(clear_depth(depth_[v], frame.views[v], content.focus_point));
        dinfo[v].subImage.swapchain = depth_[v].handle;
        dinfo[v].subImage.imageRect = pviews[v].subImage.imageRect;
        dinfo[v].minDepth = 0.0f;
        dinfo[v].maxDepth = 1.0f;
        dinfo[v].nearZ = static_cast<float>(kNearZ);
        dinfo[v].farZ = static_cast<float>(kFarZ);
        pviews[v].next = &dinfo[v];
      }
    }
    layer.space = space_;
    layer.viewCount = static_cast<uint32_t>(pviews.size());
    layer.views = pviews.data();
  }
  XrFrameEndInfo ei{XR_TYPE_FRAME_END_INFO};
  ei.displayTime = frame_state_.predictedDisplayTime;
  ei.environmentBlendMode = XR_ENVIRONMENT_BLEND_MODE_OPAQUE;
  ei.layerCount = submit ? 1 : 0;
  ei.layers = submit ? layers : nullptr;
  VXR_XR_CALL(errors_, xrEndFrame, (session_, &ei));
  return Status::ok();
}

void OpenXrTarget::request_exit() {
  if (!session_ || !running_) {
    exit_ = true;
    return;
  }
  if (exit_requested_) return;
  exit_requested_ = true;
  const XrResult r = xrRequestExitSession(session_);
  if (XR_FAILED(r)) {
    log_warn(errors_.fail(r, "xrRequestExitSession", __FILE__, __LINE__).message() + "; stopping anyway");
    exit_ = true;
  }
}

void OpenXrTarget::haptic_pulse(Hand hand, double amplitude, double seconds) {
  if (state_ != XR_SESSION_STATE_FOCUSED) return;
  if (Status s = actions_.haptic(session_, hand, amplitude, seconds, errors_); !s) log_warn(s.message());
}

void OpenXrTarget::detach() {
  actions_.detach();
  for (auto* list : {&color_, &depth_})
    for (Swapchain& sc : *list)
      if (sc.handle) xrDestroySwapchain(sc.handle);
  color_.clear();
  depth_.clear();
  if (space_) xrDestroySpace(space_);
  space_ = XR_NULL_HANDLE;
  if (session_ && XR_FAILED(xrDestroySession(session_)) && instance_) {
    // The session (and the swapchain images it holds on our device) must go
    // before the device does; destroying the instance destroys all its children.
    log_warn("OpenXR: xrDestroySession failed; destroying the instance to release the session");
    xrDestroyInstance(instance_);
    instance_ = XR_NULL_HANDLE;
  }
  session_ = XR_NULL_HANDLE;
  running_ = false;
  frame_begun_ = false;
  ctx_ = nullptr;
}

Result<std::string> probe_openxr() {
  auto t = OpenXrTarget::create({});
  if (!t) return t.status();
  return (*t)->describe();
}

}  // namespace vxr::xr
