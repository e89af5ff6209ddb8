#include "xr/desktop/desktop_target.h"

#define GLFW_INCLUDE_VULKAN
#include <GLFW/glfw3.h>
#define GLFW_EXPOSE_NATIVE_X11
#include <GLFW/glfw3native.h>
#include <X11/Xlib.h>
#include <X11/Xutil.h>
// Xlib's macros collide with vxr names.
#undef Status
#undef None
#undef Bool

#include <algorithm>
#include <cmath>
#include <cstdlib>

#include "core/image.h"
#include "gpu/vk_check.h"
#include "xr/desktop/viewer_keys.h"
#include "xr/eye_renderer.h"
#include "xr/volume_transform.h"

namespace vxr::xr {
namespace {

bool g_glfw_ready = false;
std::string g_glfw_error;

void on_glfw_error(int, const char* text) { g_glfw_error = text ? text : "unknown GLFW error"; }

Status init_glfw() {
  if (g_glfw_ready) return Status::ok();
  if (!std::getenv("DISPLAY")) return unsupported("DISPLAY is not set (run under X11, or xvfb-run)");
  glfwSetErrorCallback(on_glfw_error);
  if (!glfwInit()) return unsupported("GLFW could not start: " + g_glfw_error);
  if (!glfwVulkanSupported()) {
    glfwTerminate();
    return unsupported("GLFW finds no Vulkan loader with surface support");
  }
  g_glfw_ready = true;
  std::atexit([] { glfwTerminate(); });
  return Status::ok();
}

DesktopTarget* self(GLFWwindow* w) { return static_cast<DesktopTarget*>(glfwGetWindowUserPointer(w)); }

double g_last_x = 0, g_last_y = 0;

}  // namespace

Status desktop_available() { return init_glfw(); }

Result<std::unique_ptr<DesktopTarget>> DesktopTarget::create(const DesktopOptions& o) {
  VXR_RETURN_IF_ERROR(init_glfw());
  std::unique_ptr<DesktopTarget> t(new DesktopTarget(o));
  glfwWindowHint(GLFW_CLIENT_API, GLFW_NO_API);
  glfwWindowHint(GLFW_RESIZABLE, GLFW_FALSE);
  const int w = int(o.stereo ? 2 * o.width : o.width);
  t->window_ = glfwCreateWindow(w, int(o.height), "vxr", nullptr, nullptr);
  if (!t->window_) return unsupported("cannot open a " + std::to_string(w) + "x" + std::to_string(o.height) +
                                      " window: " + g_glfw_error);
  glfwSetWindowUserPointer(t->window_, t.get());
  glfwSetCursorPosCallback(t->window_, [](GLFWwindow* win, double x, double y) {
    if (glfwGetMouseButton(win, GLFW_MOUSE_BUTTON_LEFT) == GLFW_PRESS) self(win)->on_drag(x - g_last_x, y - g_last_y);
    g_last_x = x;
    g_last_y = y;
  });
  glfwSetScrollCallback(t->window_, [](GLFWwindow* win, double, double dy) { self(win)->on_scroll(dy); });
  // Esc through the key callback: polling glfwGetKey once a frame misses a tap shorter than a frame.
  glfwSetKeyCallback(t->window_, [](GLFWwindow* win, int key, int, int action, int) {
    if (viewer_key_from_glfw(key, action) == ViewerKey::kQuit) glfwSetWindowShouldClose(win, GLFW_TRUE);
  });
  return t;
}

DesktopTarget::~DesktopTarget() {
  detach();
  if (window_) glfwDestroyWindow(window_);
}

std::string DesktopTarget::describe() const {
  return std::string("desktop window ") + std::to_string(o_.stereo ? 2 * o_.width : o_.width) + "x" +
         std::to_string(o_.height) + (o_.stereo ? " (side-by-side stereo)" : "") +
         (swap_format_ == VK_FORMAT_UNDEFINED                                                       ? ""
          : swap_format_ == VK_FORMAT_B8G8R8A8_SRGB || swap_format_ == VK_FORMAT_R8G8B8A8_SRGB ? ", sRGB swapchain"
                                                                                                : ", UNORM swapchain");
}

Status DesktopTarget::prepare_context(gpu::ContextOptions& options) {
  uint32_t n = 0;
  const char** exts = glfwGetRequiredInstanceExtensions(&n);
  if (!exts) return unsupported("GLFW lists no Vulkan surface extensions for this display");
  for (uint32_t i = 0; i < n; ++i) options.instance_extensions.push_back(exts[i]);
  options.device_extensions.push_back(VK_KHR_SWAPCHAIN_EXTENSION_NAME);
  return Status::ok();
}

void DesktopTarget::on_drag(double dx, double dy) {
  yaw_ -= dx * 0.01;
  pitch_ = std::clamp(pitch_ - dy * 0.01, -1.5, 1.5);
}

void DesktopTarget::on_scroll(double dy) { distance_ = std::clamp(distance_ * std::pow(0.9, dy), 0.02, 50.0); }

Pose DesktopTarget::head_pose() const {
  const glm::dquat q = glm::angleAxis(yaw_, glm::dvec3(0, 1, 0)) * glm::angleAxis(pitch_, glm::dvec3(1, 0, 0));
  return {q, focus_ + q * glm::dvec3(0, 0, distance_)};
}

Status DesktopTarget::attach(gpu::Context& ctx) {
  ctx_ = &ctx;
  VXR_VK_TRY(glfwCreateWindowSurface(ctx.instance(), window_, nullptr, &surface_));
  VkBool32 present = VK_FALSE;
  VXR_VK_TRY(vkGetPhysicalDeviceSurfaceSupportKHR(ctx.physical_device(), ctx.queue_family(), surface_, &present));
  if (!present) return unsupported(ctx.info().name + " cannot present to this window");

  VkCommandPoolCreateInfo pci{VK_STRUCTURE_TYPE_COMMAND_POOL_CREATE_INFO};
  pci.flags = VK_COMMAND_POOL_CREATE_RESET_COMMAND_BUFFER_BIT;
  pci.queueFamilyIndex = ctx.queue_family();
  VkCommandPool pool;
  VXR_VK_TRY(vkCreateCommandPool(ctx.device(), &pci, nullptr, &pool));
  pool_ = gpu::Handle<VkCommandPool>(ctx.device(), pool);
  VkSemaphoreCreateInfo sci{VK_STRUCTURE_TYPE_SEMAPHORE_CREATE_INFO};
  VkSemaphore sem;
  VXR_VK_TRY(vkCreateSemaphore(ctx.device(), &sci, nullptr, &sem));
  acquired_ = gpu::Handle<VkSemaphore>(ctx.device(), sem);
  VkFenceCreateInfo fci{VK_STRUCTURE_TYPE_FENCE_CREATE_INFO};
  VkFence fence;
  VXR_VK_TRY(vkCreateFence(ctx.device(), &fci, nullptr, &fence));
  fence_ = gpu::Handle<VkFence>(ctx.device(), fence);

  VXR_RETURN_IF_ERROR(create_swapchain());
  // Eyes in the swapchain's encoding: on an sRGB window the renderer writes
  // linear values the format encodes (as on an sRGB headset swapchain), and
  // the blit copies the encoded bytes unchanged (decode + encode).
  const bool srgb = swap_format_ == VK_FORMAT_B8G8R8A8_SRGB || swap_format_ == VK_FORMAT_R8G8B8A8_SRGB;
  const VkFormat eye_format = srgb ? VK_FORMAT_R8G8B8A8_SRGB : VK_FORMAT_R8G8B8A8_UNORM;
  for (int v = 0; v < (o_.stereo ? 2 : 1); ++v) {
    VXR_ASSIGN_OR_RETURN(gpu::Image img,
                         gpu::create_image(ctx, {VK_IMAGE_TYPE_2D, eye_format, {o_.width, o_.height, 1},
                                                 VK_IMAGE_USAGE_TRANSFER_DST_BIT | VK_IMAGE_USAGE_TRANSFER_SRC_BIT |
                                                     VK_IMAGE_USAGE_SAMPLED_BIT |
                                                     (srgb ? 0u : VK_IMAGE_USAGE_STORAGE_BIT),
                                                 "desktop eye"}));
    VXR_RETURN_IF_ERROR(ctx.submit_and_wait([&](VkCommandBuffer cmd) {
      image_barrier(cmd, img.image, VK_IMAGE_ASPECT_COLOR_BIT, VK_IMAGE_LAYOUT_UNDEFINED,
                    VK_IMAGE_LAYOUT_TRANSFER_SRC_OPTIMAL);
    }));
    eyes_.push_back(std::move(img));
  }
  return Status::ok();
}

Status DesktopTarget::create_swapchain() {
  VkSurfaceCapabilitiesKHR caps;
  VXR_VK_TRY(vkGetPhysicalDeviceSurfaceCapabilitiesKHR(ctx_->physical_device(), surface_, &caps));
  uint32_t n = 0;
  VXR_VK_TRY(vkGetPhysicalDeviceSurfaceFormatsKHR(ctx_->physical_device(), surface_, &n, nullptr));
  std::vector<VkSurfaceFormatKHR> formats(n);
  VXR_VK_TRY(vkGetPhysicalDeviceSurfaceFormatsKHR(ctx_->physical_device(), surface_, &n, formats.data()));
  swap_format_ = VK_FORMAT_UNDEFINED;
  VkColorSpaceKHR space = VK_COLOR_SPACE_SRGB_NONLINEAR_KHR;
  const std::vector<VkFormat> wanted =
      o_.srgb_swapchain ? std::vector<VkFormat>{VK_FORMAT_B8G8R8A8_SRGB, VK_FORMAT_R8G8B8A8_SRGB, VK_FORMAT_B8G8R8A8_UNORM,
                                                VK_FORMAT_R8G8B8A8_UNORM}
                        : std::vector<VkFormat>{VK_FORMAT_B8G8R8A8_UNORM, VK_FORMAT_R8G8B8A8_UNORM};
  for (VkFormat want : wanted)
    for (const auto& f : formats)
      if (swap_format_ == VK_FORMAT_UNDEFINED && f.format == want) {
        swap_format_ = f.format;
        space = f.colorSpace;
      }
  if (swap_format_ == VK_FORMAT_UNDEFINED) return unsupported("the window offers no 8-bit RGBA/BGRA swapchain format");
  if (!(caps.supportedUsageFlags & VK_IMAGE_USAGE_TRANSFER_DST_BIT))
    return unsupported("the window's swapchain images cannot be copied into (no TRANSFER_DST)");
  swap_extent_ = caps.currentExtent.width != UINT32_MAX
                     ? caps.currentExtent
                     : VkExtent2D{o_.stereo ? 2 * o_.width : o_.width, o_.height};
  VkSwapchainCreateInfoKHR ci{VK_STRUCTURE_TYPE_SWAPCHAIN_CREATE_INFO_KHR};
  ci.surface = surface_;
  ci.minImageCount = caps.maxImageCount ? std::min(caps.minImageCount + 1, caps.maxImageCount) : caps.minImageCount + 1;
  ci.imageFormat = swap_format_;
  ci.imageColorSpace = space;
  ci.imageExtent = swap_extent_;
  ci.imageArrayLayers = 1;
  ci.imageUsage = VK_IMAGE_USAGE_TRANSFER_DST_BIT | VK_IMAGE_USAGE_COLOR_ATTACHMENT_BIT;
  ci.imageSharingMode = VK_SHARING_MODE_EXCLUSIVE;
  ci.preTransform = caps.currentTransform;
  ci.compositeAlpha = VK_COMPOSITE_ALPHA_OPAQUE_BIT_KHR;
  ci.presentMode = VK_PRESENT_MODE_FIFO_KHR;
  ci.clipped = VK_TRUE;
  VXR_VK_TRY(vkCreateSwapchainKHR(ctx_->device(), &ci, nullptr, &swapchain_));
  VXR_VK_TRY(vkGetSwapchainImagesKHR(ctx_->device(), swapchain_, &n, nullptr));
  swap_images_.resize(n);
  VXR_VK_TRY(vkGetSwapchainImagesKHR(ctx_->device(), swapchain_, &n, swap_images_.data()));
  render_done_.clear();
  for (uint32_t i = 0; i < n; ++i) {
    VkSemaphoreCreateInfo sci{VK_STRUCTURE_TYPE_SEMAPHORE_CREATE_INFO};
    VkSemaphore sem;
    VXR_VK_TRY(vkCreateSemaphore(ctx_->device(), &sci, nullptr, &sem));
    render_done_.emplace_back(ctx_->device(), sem);
  }
  return Status::ok();
}

void DesktopTarget::destroy_swapchain() {
  if (!ctx_) return;
  vkDeviceWaitIdle(ctx_->device());
  render_done_.clear();
  if (swapchain_) vkDestroySwapchainKHR(ctx_->device(), swapchain_, nullptr);
  swapchain_ = VK_NULL_HANDLE;
  swap_images_.clear();
}

void DesktopTarget::detach() {
  if (!ctx_) return;
  destroy_swapchain();
  eyes_.clear();
  acquired_.reset();
  fence_.reset();
  pool_.reset();
  if (surface_) vkDestroySurfaceKHR(ctx_->instance(), surface_, nullptr);
  surface_ = VK_NULL_HANDLE;
  ctx_ = nullptr;
}

Result<FrameState> DesktopTarget::wait_frame() {
  glfwPollEvents();
  FrameState f;
  const bool done = exit_requested_ || glfwWindowShouldClose(window_) || (o_.end_frame && frame_ >= o_.end_frame);
  if (done) {
    if (!o_.screenshot_path.empty() && frame_ > 0) VXR_RETURN_IF_ERROR(screenshot());
    f.exit = true;
    return f;
  }
  if (glfwGetKey(window_, GLFW_KEY_ESCAPE) == GLFW_PRESS) glfwSetWindowShouldClose(window_, GLFW_TRUE);
  // Fly: W/S along the view, A/D sideways, Q/E down/up (moves the orbit centre).
  const Pose head = head_pose();
  const double step = 0.01 * distance_;
  const glm::dvec3 fwd = head.orientation * glm::dvec3(0, 0, -1), right = head.orientation * glm::dvec3(1, 0, 0);
  if (glfwGetKey(window_, GLFW_KEY_W) == GLFW_PRESS) focus_ += step * fwd;
  if (glfwGetKey(window_, GLFW_KEY_S) == GLFW_PRESS) focus_ -= step * fwd;
  if (glfwGetKey(window_, GLFW_KEY_D) == GLFW_PRESS) focus_ += step * right;
  if (glfwGetKey(window_, GLFW_KEY_A) == GLFW_PRESS) focus_ -= step * right;
  if (glfwGetKey(window_, GLFW_KEY_E) == GLFW_PRESS) focus_.y += step;
  if (glfwGetKey(window_, GLFW_KEY_Q) == GLFW_PRESS) focus_.y -= step;

  f.should_render = true;
  f.display_time_ns = int64_t(frame_) * 16666667;
  Fov fov = o_.fov;
  const double ty = std::tan(0.5 * (fov.up - fov.down));
  const double tx = ty * double(o_.width) / double(o_.height);
  fov = {-std::atan(tx), std::atan(tx), std::atan(ty), -std::atan(ty)};
  if (o_.stereo) {
    f.views = stereo_views(head_pose(), o_.ipd_m, fov, o_.width, o_.height);
  } else {
    f.views = {ViewSpec{head_pose(), fov, o_.width, o_.height}};
  }
  return f;
}

Result<TargetImage> DesktopTarget::acquire(size_t view) {
  if (view >= eyes_.size()) return out_of_range("the desktop window has " + std::to_string(eyes_.size()) + " views");
  const gpu::Image& e = eyes_[view];
  // Eye images rest in TRANSFER_SRC_OPTIMAL: end_frame blits from them.
  return TargetImage{e.image, e.format, {e.extent.width, e.extent.height}, VK_IMAGE_LAYOUT_TRANSFER_SRC_OPTIMAL,
                     e.view};
}

Status DesktopTarget::end_frame(const FrameState& frame, const FrameContent& content) {
  ++frame_;
  if (!have_focus_) {
    focus_ = content.focus_point;
    have_focus_ = true;
  }
  if (!frame.should_render) return Status::ok();
  std::vector<TargetImage> sources;
  for (const gpu::Image& e : eyes_)
    sources.push_back({e.image, e.format, {e.extent.width, e.extent.height}, VK_IMAGE_LAYOUT_TRANSFER_SRC_OPTIMAL});
  return present(sources);
}

bool DesktopTarget::poll() {
  glfwPollEvents();
  if (glfwGetKey(window_, GLFW_KEY_ESCAPE) == GLFW_PRESS) glfwSetWindowShouldClose(window_, GLFW_TRUE);
  return !glfwWindowShouldClose(window_);
}

Status DesktopTarget::present(const std::vector<TargetImage>& sources) {
  uint32_t index = 0;
  VkResult r = vkAcquireNextImageKHR(ctx_->device(), swapchain_, UINT64_MAX, acquired_, VK_NULL_HANDLE, &index);
  if (r == VK_ERROR_OUT_OF_DATE_KHR) {
    destroy_swapchain();
    return create_swapchain();
  }
  if (r != VK_SUCCESS && r != VK_SUBOPTIMAL_KHR) return gpu_error("vkAcquireNextImageKHR failed: " + std::to_string(r));

  VkCommandBufferAllocateInfo ai{VK_STRUCTURE_TYPE_COMMAND_BUFFER_ALLOCATE_INFO};
  ai.commandPool = pool_;
  ai.level = VK_COMMAND_BUFFER_LEVEL_PRIMARY;
  ai.commandBufferCount = 1;
  VkCommandBuffer cmd;
  VXR_VK_TRY(vkAllocateCommandBuffers(ctx_->device(), &ai, &cmd));
  VkCommandBufferBeginInfo bi{VK_STRUCTURE_TYPE_COMMAND_BUFFER_BEGIN_INFO};
  bi.flags = VK_COMMAND_BUFFER_USAGE_ONE_TIME_SUBMIT_BIT;
  VXR_VK_TRY(vkBeginCommandBuffer(cmd, &bi));
  const VkImage target = swap_images_[index];
  image_barrier(cmd, target, VK_IMAGE_ASPECT_COLOR_BIT, VK_IMAGE_LAYOUT_UNDEFINED, VK_IMAGE_LAYOUT_TRANSFER_DST_OPTIMAL);
  const int32_t slot_w = int32_t(swap_extent_.width / std::max<size_t>(1, sources.size()));
  for (size_t v = 0; v < sources.size(); ++v) {
    const TargetImage& src = sources[v];
    const bool move = src.layout != VK_IMAGE_LAYOUT_TRANSFER_SRC_OPTIMAL && src.layout != VK_IMAGE_LAYOUT_GENERAL;
    if (move)
      image_barrier(cmd, src.image, VK_IMAGE_ASPECT_COLOR_BIT, src.layout, VK_IMAGE_LAYOUT_TRANSFER_SRC_OPTIMAL);
    VkImageBlit blit{};
    blit.srcSubresource = blit.dstSubresource = {VK_IMAGE_ASPECT_COLOR_BIT, 0, 0, 1};
    blit.srcOffsets[1] = {int32_t(src.extent.width), int32_t(src.extent.height), 1};
    blit.dstOffsets[0] = {int32_t(v) * slot_w, 0, 0};
    blit.dstOffsets[1] = {int32_t(v + 1) * slot_w, int32_t(swap_extent_.height), 1};
    vkCmdBlitImage(cmd, src.image, move ? VK_IMAGE_LAYOUT_TRANSFER_SRC_OPTIMAL : src.layout, target,
                   VK_IMAGE_LAYOUT_TRANSFER_DST_OPTIMAL, 1, &blit, VK_FILTER_LINEAR);
    if (move)
      image_barrier(cmd, src.image, VK_IMAGE_ASPECT_COLOR_BIT, VK_IMAGE_LAYOUT_TRANSFER_SRC_OPTIMAL, src.layout);
  }
  image_barrier(cmd, target, VK_IMAGE_ASPECT_COLOR_BIT, VK_IMAGE_LAYOUT_TRANSFER_DST_OPTIMAL,
                VK_IMAGE_LAYOUT_PRESENT_SRC_KHR);
  VXR_VK_TRY(vkEndCommandBuffer(cmd));

  VkSemaphoreSubmitInfo wait{VK_STRUCTURE_TYPE_SEMAPHORE_SUBMIT_INFO};
  wait.semaphore = acquired_;
  wait.stageMask = VK_PIPELINE_STAGE_2_ALL_COMMANDS_BIT;
  VkSemaphoreSubmitInfo signal{VK_STRUCTURE_TYPE_SEMAPHORE_SUBMIT_INFO};
  signal.semaphore = render_done_[index];
  signal.stageMask = VK_PIPELINE_STAGE_2_ALL_COMMANDS_BIT;
  VkCommandBufferSubmitInfo cbi{VK_STRUCTURE_TYPE_COMMAND_BUFFER_SUBMIT_INFO};
  cbi.commandBuffer = cmd;
  VkSubmitInfo2 si{VK_STRUCTURE_TYPE_SUBMIT_INFO_2};
  si.waitSemaphoreInfoCount = 1;
  si.pWaitSemaphoreInfos = &wait;
  si.commandBufferInfoCount = 1;
  si.pCommandBufferInfos = &cbi;
  si.signalSemaphoreInfoCount = 1;
  si.pSignalSemaphoreInfos = &signal;
  VkFence fence = fence_;
  VXR_VK_TRY(vkResetFences(ctx_->device(), 1, &fence));
  VXR_VK_TRY(vkQueueSubmit2(ctx_->queue(), 1, &si, fence));
  VXR_VK_TRY(vkWaitForFences(ctx_->device(), 1, &fence, VK_TRUE, UINT64_MAX));
  vkFreeCommandBuffers(ctx_->device(), pool_, 1, &cmd);

  VkPresentInfoKHR pi{VK_STRUCTURE_TYPE_PRESENT_INFO_KHR};
  VkSemaphore done = render_done_[index];
  pi.waitSemaphoreCount = 1;
  pi.pWaitSemaphores = &done;
  pi.swapchainCount = 1;
  pi.pSwapchains = &swapchain_;
  pi.pImageIndices = &index;
  r = vkQueuePresentKHR(ctx_->queue(), &pi);
  if (r == VK_ERROR_OUT_OF_DATE_KHR || r == VK_SUBOPTIMAL_KHR) {
    destroy_swapchain();
    return create_swapchain();
  }
  if (r != VK_SUCCESS) return gpu_error("vkQueuePresentKHR failed: " + std::to_string(r));
  return Status::ok();
}

// What the X server shows in the window (not our own copy of it).
Status DesktopTarget::screenshot() {
  if (o_.screenshot_path.empty() || !ctx_) return Status::ok();
  vkQueueWaitIdle(ctx_->queue());
  Display* dpy = glfwGetX11Display();
  const Window win = glfwGetX11Window(window_);
  XSync(dpy, False);
  XWindowAttributes attrs;
  if (!XGetWindowAttributes(dpy, win, &attrs)) return io_error("cannot read the window's attributes from the X server");
  XImage* xi = XGetImage(dpy, win, 0, 0, attrs.width, attrs.height, AllPlanes, ZPixmap);
  if (!xi) return io_error("the X server refused to hand out the window's pixels");
  ImageRgba8 img(attrs.width, attrs.height);
  for (int y = 0; y < attrs.height; ++y)
    for (int x = 0; x < attrs.width; ++x) {
      const unsigned long p = XGetPixel(xi, x, y);
      uint8_t* o = img.at(x, y);
      o[0] = uint8_t((p & xi->red_mask) >> __builtin_ctzl(xi->red_mask));
      o[1] = uint8_t((p & xi->green_mask) >> __builtin_ctzl(xi->green_mask));
      o[2] = uint8_t((p & xi->blue_mask) >> __builtin_ctzl(xi->blue_mask));
      o[3] = 255;
    }
  XDestroyImage(xi);
  return write_png(o_.screenshot_path, img);
}

}  // namespace vxr::xr
