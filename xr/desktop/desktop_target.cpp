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

#include <imgui.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <glm/gtc/quaternion.hpp>
#include <fstream>
#include <iterator>
#include <map>

#include "core/image.h"
#include "core/log.h"
#include "core/output_file.h"
#include "render/movie_player.h"
#include "gpu/vk_check.h"
#include "xr/desktop/imgui_layer.h"
#include "xr/desktop/viewer_keys.h"
#include "xr/desktop/viewer_panels.h"
#include "xr/desktop/viewer_setup.h"
#include "xr/desktop/viewer_tools.h"
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
constexpr uint32_t kPrefetchAhead = 4;  // timepoints decoded ahead of the shown one (MoviePlayerOptions::prefetch)

}  // namespace

Status desktop_available() { return init_glfw(); }

Result<std::unique_ptr<DesktopTarget>> DesktopTarget::create(const DesktopOptions& o) {
  VXR_RETURN_IF_ERROR(init_glfw());
  std::unique_ptr<DesktopTarget> t(new DesktopTarget(o));
  glfwWindowHint(GLFW_CLIENT_API, GLFW_NO_API);
  // The viewer follows the window's size (and remembers it); the bare window keeps its eye size.
  glfwWindowHint(GLFW_RESIZABLE, o.viewer ? GLFW_TRUE : GLFW_FALSE);
  const int w = int(o.stereo ? 2 * o.width : o.width);
  t->window_ = glfwCreateWindow(w, int(o.height), "vxr", nullptr, nullptr);
  if (!t->window_) return unsupported("cannot open a " + std::to_string(w) + "x" + std::to_string(o.height) +
                                      " window: " + g_glfw_error);
  glfwSetWindowUserPointer(t->window_, t.get());
  glfwSetCursorPosCallback(t->window_, [](GLFWwindow* win, double x, double y) {
    DesktopTarget* target = self(win);
    if (target->state_)
      target->on_viewer_cursor(x - g_last_x, y - g_last_y);
    else if (glfwGetMouseButton(win, GLFW_MOUSE_BUTTON_LEFT) == GLFW_PRESS)
      target->on_drag(x - g_last_x, y - g_last_y);
    g_last_x = x;
    g_last_y = y;
  });
  // A click (press and release within a few pixels, not on a panel) places with the tools panel's tool.
  glfwSetMouseButtonCallback(t->window_, [](GLFWwindow* win, int button, int action, int) {
    DesktopTarget* target = self(win);
    if (!target->tools_ || button != GLFW_MOUSE_BUTTON_LEFT) return;
    double x = 0, y = 0;
    glfwGetCursorPos(win, &x, &y);
    if (action == GLFW_PRESS) {
      target->press_x_ = x;
      target->press_y_ = y;
      target->press_on_ui_ = ImGuiLayer::wants_mouse();
    } else if (action == GLFW_RELEASE && !target->press_on_ui_ &&
               std::hypot(x - target->press_x_, y - target->press_y_) < 4.0) {
      target->on_viewer_click(x, y);
    }
  });
  glfwSetScrollCallback(t->window_, [](GLFWwindow* win, double, double dy) { self(win)->on_scroll(dy); });
  // Keys through the callback: polling glfwGetKey once a frame misses a tap shorter than a frame.
  glfwSetKeyCallback(t->window_, [](GLFWwindow* win, int key, int, int action, int) {
    const std::optional<ViewerKey> k = viewer_key_from_glfw(key, action);
    if (k == ViewerKey::kQuit) glfwSetWindowShouldClose(win, GLFW_TRUE);
    DesktopTarget* target = self(win);
    if (k && target->state_ && !ImGuiLayer::wants_keyboard()) target->state_->handle_key(*k);
  });
  glfwSetFramebufferSizeCallback(t->window_, [](GLFWwindow* win, int, int) { self(win)->resized_ = true; });
  if (t->state_) glfwSetWindowTitle(t->window_, viewer_window_title(o.viewer->dataset, 0.0).c_str());
  return t;
}

DesktopTarget::DesktopTarget(const DesktopOptions& o) : o_(o) {
  if (o_.viewer) {
    state_ = std::make_unique<ViewerState>(o_.viewer->scene, o_.viewer->timepoints, o_.viewer->data_range);
    if (o_.viewer->store) {
      tools_ = std::make_unique<ViewerTools>(*o_.viewer->store);
      panel_ = std::make_unique<ToolPanel>();
    }
    if (o_.viewer->script)
      script_ = std::make_unique<UiScriptRunner>(*o_.viewer->script, tools_.get(),
                                                 [this](const ViewerState&) { return card_scene(); });
  }
}

void DesktopTarget::on_viewer_cursor(double dx, double dy) {
  if (ImGuiLayer::wants_mouse()) return;
  if (tools_ && panel_->mode == ToolPanel::Mode::kMeasure && !o_.stereo) {
    // The measurement being drawn follows the cursor.
    double x = 0, y = 0;
    glfwGetCursorPos(window_, &x, &y);
    if (Status s = tools_->measure_hover(voxel_under(x, y), state_->scene().timepoint); !s) panel_->message = s.message();
  }
  if (glfwGetMouseButton(window_, GLFW_MOUSE_BUTTON_LEFT) == GLFW_PRESS)
    state_->orbit_drag(dx, dy);
  else if (glfwGetMouseButton(window_, GLFW_MOUSE_BUTTON_RIGHT) == GLFW_PRESS ||
           glfwGetMouseButton(window_, GLFW_MOUSE_BUTTON_MIDDLE) == GLFW_PRESS)
    state_->pan_drag(dx, dy, double(o_.height));
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

void DesktopTarget::on_scroll(double dy) {
  if (state_) {
    if (!ImGuiLayer::wants_mouse()) state_->zoom(dy);
    return;
  }
  distance_ = std::clamp(distance_ * std::pow(0.9, dy), 0.02, 50.0);
}

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
  VXR_RETURN_IF_ERROR(create_eyes());
  if (state_) {
    VXR_ASSIGN_OR_RETURN(ui_, ImGuiLayer::create(window_, ctx, swap_format_, swap_images_, swap_extent_));
    last_frame_start_ = std::chrono::steady_clock::now();
  }
  return Status::ok();
}

Status DesktopTarget::create_eyes() {
  eyes_.clear();
  // Eyes in the swapchain's encoding: on an sRGB window the renderer writes
  // linear values the format encodes (as on an sRGB headset swapchain), and
  // the blit copies the encoded bytes unchanged (decode + encode).
  const bool srgb = swap_format_ == VK_FORMAT_B8G8R8A8_SRGB || swap_format_ == VK_FORMAT_R8G8B8A8_SRGB;
  const VkFormat eye_format = srgb ? VK_FORMAT_R8G8B8A8_SRGB : VK_FORMAT_R8G8B8A8_UNORM;
  for (int v = 0; v < (o_.stereo ? 2 : 1); ++v) {
    VXR_ASSIGN_OR_RETURN(gpu::Image img,
                         gpu::create_image(*ctx_, {VK_IMAGE_TYPE_2D, eye_format, {o_.width, o_.height, 1},
                                                   VK_IMAGE_USAGE_TRANSFER_DST_BIT | VK_IMAGE_USAGE_TRANSFER_SRC_BIT |
                                                       VK_IMAGE_USAGE_SAMPLED_BIT |
                                                       (srgb ? 0u : uint32_t(VK_IMAGE_USAGE_STORAGE_BIT)),
                                                   "desktop eye"}));
    VXR_RETURN_IF_ERROR(ctx_->submit_and_wait([&](VkCommandBuffer cmd) {
      image_barrier(cmd, img.image, VK_IMAGE_ASPECT_COLOR_BIT, VK_IMAGE_LAYOUT_UNDEFINED,
                    VK_IMAGE_LAYOUT_TRANSFER_SRC_OPTIMAL);
    }));
    eyes_.push_back(std::move(img));
  }
  return Status::ok();
}

// The viewer's window was resized: swapchain, eyes and panels follow its framebuffer.
Status DesktopTarget::follow_window_size() {
  int w = 0, h = 0;
  glfwGetFramebufferSize(window_, &w, &h);
  if (w <= 0 || h <= 0) return Status::ok();  // minimised: keep the old size until it comes back
  resized_ = false;
  const uint32_t eye_w = o_.stereo ? std::max(1, w / 2) : uint32_t(w);
  if (eye_w == o_.width && uint32_t(h) == o_.height) return Status::ok();
  o_.width = eye_w;
  o_.height = uint32_t(h);
  user_resized_ = true;
  VXR_RETURN_IF_ERROR(recreate_swapchain());
  return create_eyes();
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
  // TRANSFER_SRC where offered: the viewer's screenshots copy the swapchain image.
  ci.imageUsage = VK_IMAGE_USAGE_TRANSFER_DST_BIT | VK_IMAGE_USAGE_COLOR_ATTACHMENT_BIT |
                  (caps.supportedUsageFlags & VK_IMAGE_USAGE_TRANSFER_SRC_BIT);
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

Status DesktopTarget::recreate_swapchain() {
  destroy_swapchain();
  VXR_RETURN_IF_ERROR(create_swapchain());
  if (ui_) VXR_RETURN_IF_ERROR(ui_->set_images(swap_images_, swap_extent_));
  return Status::ok();
}

void DesktopTarget::detach() {
  if (state_ && user_resized_) {
    // The next viewer opens at the size the user left this one.
    const std::string config = viewer_config_path();
    if (!config.empty())
      if (Status s = save_window_geometry(config, {std::max(64u, o_.stereo ? 2 * o_.width : o_.width),
                                                               std::max(64u, o_.height)}); !s)
        log_warn("viewer: window size not remembered: " + s.message());
    user_resized_ = false;
  }
  if (!ctx_) return;
  ui_.reset();  // its framebuffers and pipeline go before the device
  screenshot_buffer_ = {};
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
  if (state_) {
    if (resized_) VXR_RETURN_IF_ERROR(follow_window_size());
    VXR_RETURN_IF_ERROR(viewer_frame(f));
    return f;
  }
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
  if (state_) {
    if (!image_acquired_) return Status::ok();
    image_acquired_ = false;
    if (!screenshot_pending_.empty()) VXR_RETURN_IF_ERROR(write_screenshot());
    if (!card_shot_.empty()) {
      if (Status s = save_panel_card(card_shot_); !s) panel_->message = s.message();
      card_shot_.clear();
      card_temp_.reset();
    }
    VkPresentInfoKHR pi{VK_STRUCTURE_TYPE_PRESENT_INFO_KHR};
    VkSemaphore done = render_done_[image_index_];
    pi.waitSemaphoreCount = 1;
    pi.pWaitSemaphores = &done;
    pi.swapchainCount = 1;
    pi.pSwapchains = &swapchain_;
    pi.pImageIndices = &image_index_;
    const VkResult r = vkQueuePresentKHR(ctx_->queue(), &pi);
    if (r == VK_ERROR_OUT_OF_DATE_KHR || r == VK_SUBOPTIMAL_KHR) return recreate_swapchain();
    if (r != VK_SUCCESS) return gpu_error("vkQueuePresentKHR failed: " + std::string(gpu::vk_result_name(r)));
    return Status::ok();
  }
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

// ---- the viewer ----------------------------------------------------------

void DesktopTarget::use_chunk_cache(ChunkCache* cache, const ChunkSource* source) {
  prefetch_.clear();
  if (!state_ || !cache || !source || state_->timepoints() < 2) return;
  // MoviePlayer's policy (render/movie_player.h, what `vxr play` uses): prefetch gets half the cache, split
  // over the drawn channels; the level is the finest where the shown timepoint and kPrefetchAhead more fit.
  const uint32_t channels = uint32_t(std::clamp<size_t>(state_->channel_count(), 1, source->info().channels));
  const uint64_t per_timepoint = cache->budget_bytes() / 2 / (kPrefetchAhead + 1) / channels;
  const uint32_t level = finest_level_within(*source, per_timepoint);
  for (uint32_t c = 0; c < channels; ++c) prefetch_.emplace_back(*cache, *source, level, c, 0.5 / channels);
  log_info("viewer: playback prefetches level " + std::to_string(level) + " of " + std::to_string(channels) +
           " channel(s), " + std::to_string(prefetch_.front().bytes_per_timepoint() >> 10) +
           " KiB per timepoint and channel");
}

CameraState viewer_world_camera(const ViewerState& state, const VolumePlacement& placement) {
  const glm::dvec3 e = placement.extent();
  const double longest = std::max({e.x, e.y, e.z});
  CameraState c = state.camera();
  for (int i = 0; i < 3; ++i) {
    c.eye[i] *= longest;
    c.target[i] *= longest;
  }
  return c;
}

namespace {

glm::dvec3 vec(const std::array<double, 3>& a) { return {a[0], a[1], a[2]}; }

// The reference-space pose whose view, through `t`, is `c` (a camera in the volume's frame).
Pose pose_for_camera(const CameraState& c, const VolumeTransform& t) {
  const glm::dvec3 eye = vec(c.eye), forward = glm::normalize(vec(c.target) - eye);
  const glm::dvec3 right = glm::normalize(glm::cross(forward, vec(c.up)));
  const glm::dvec3 up = glm::cross(right, forward);
  const glm::dquat in_volume = glm::quat_cast(glm::dmat3(right, up, -forward));
  return {glm::normalize(t.orientation * in_volume), t.to_reference(eye)};
}

}  // namespace

Status DesktopTarget::viewer_frame(FrameState& f) {
  const ViewerSetup& setup = *o_.viewer;
  const auto now = std::chrono::steady_clock::now();
  frame_ms_ = std::chrono::duration<double, std::milli>(now - last_frame_start_).count();
  last_frame_start_ = now;
  screenshot_pending_.clear();
  // Playback as volume/playback.h shows it: the next timepoints queued, a due one shown once loaded.
  if (state_->playback().playing())
    for (TimepointPrefetcher& p : prefetch_) p.update(state_->playback().upcoming(kPrefetchAhead + 1));
  state_->tick(std::chrono::duration<double>(now.time_since_epoch()).count(),  // any origin will do
               [this](uint32_t t) {
                 return std::all_of(prefetch_.begin(), prefetch_.end(),
                                    [t](const TimepointPrefetcher& p) { return p.ready(t); });
               });
  bool script_card = false;  // the script pressed the tools panel's buttons
  std::optional<uint64_t> script_restore;
  if (script_) {
    VXR_ASSIGN_OR_RETURN(UiScriptRunner::FrameWork work, script_->before_frame(*state_));
    if (work.done) {
      f.exit = true;
      return Status::ok();
    }
    screenshot_pending_ = work.screenshot;
    // Takes effect when the X server says so: the framebuffer callback, then follow_window_size().
    if (work.resize[0] > 0) glfwSetWindowSize(window_, work.resize[0], work.resize[1]);
    if (!work.tool.empty()) {
      const std::string name = work.tool.substr(0, work.tool.find(' '));
      tools_->cancel();
      panel_->mode = name == "count"     ? ToolPanel::Mode::kCount
                     : name == "measure" ? ToolPanel::Mode::kMeasure
                                         : ToolPanel::Mode::kNavigate;
      if (name == "count") std::snprintf(panel_->cls, sizeof panel_->cls, "%s", work.tool.substr(6).c_str());
    }
    if (work.panel_card) std::snprintf(panel_->card_title, sizeof panel_->card_title, "%s", work.panel_card->c_str());
    script_card = work.panel_card.has_value();
    script_restore = work.restore_card;
    if (work.click) {
      on_viewer_click((*work.click)[0], (*work.click)[1]);
      // A script stops at the first refused click, as at any refused step.
      if (!click_error_.empty()) return invalid_argument(o_.viewer->script->path + ": click: " + click_error_);
    }
  }
  if (state_->quit_requested()) glfwSetWindowShouldClose(window_, GLFW_TRUE);
  glfwSetWindowTitle(window_, viewer_window_title(setup.dataset, frame_ms_).c_str());

  const double ty = std::tan(state_->orbit().fov_y_deg * 3.14159265358979323846 / 360.0);
  const double tx = ty * double(o_.width) / double(o_.height);
  const Fov fov{-std::atan(tx), std::atan(tx), std::atan(ty), -std::atan(ty)};

  ui_->begin();
  PanelInputs in;
  in.dataset = setup.dataset;
  in.frame_ms = frame_ms_;
  in.histograms = setup.histograms;
  draw_viewer_panels(*state_, in);
  if (tools_) {
    if (state_->ui_visible()) {
      draw_tools_panel(*tools_, *panel_);  // sets save_card / restore from its buttons
    } else {
      panel_->save_card = false;
      panel_->restore.reset();
    }
    if (script_card) panel_->save_card = true;
    if (script_restore) panel_->restore = script_restore;
    if (panel_->restore) {
      const Status s = restore_card(*panel_->restore);
      panel_->message = s ? "card " + std::to_string(*panel_->restore) + " shown" : s.message();
      if (!s && script_restore) return invalid_argument(o_.viewer->script->path + ": restore-card: " + s.message());
    }
    // The card takes this frame's picture: read back with the frame, stored in end_frame.
    if (panel_->save_card) {
      if (screenshot_pending_.empty()) {
        auto temp = TempFile::create_beside(o_.viewer->store->path() + "/card-snapshot.png");
        if (!temp) {
          panel_->message = temp.status().message();
        } else {
          card_temp_ = std::make_unique<TempFile>(std::move(temp).value());
          screenshot_pending_ = card_temp_->path();
        }
      }
      if (!screenshot_pending_.empty()) card_shot_ = screenshot_pending_;
    }
  }
  // The camera after this frame's edits (panels, keys, script), so a change shows in the frame that made it.
  const Pose head = pose_for_camera(viewer_world_camera(*state_, setup.placement), setup.transform);
  const ViewSpec mono{head, fov, o_.width, o_.height};
  if (!o_.stereo) draw_annotation_overlay(mono);
  ui_->end();

  // Every channel hidden: nothing to cast; record_after_views clears the window instead.
  const auto& channels = state_->render().channels;
  nothing_visible_ = std::none_of(channels.begin(), channels.end(), [](const ChannelSettings& c) { return c.enabled; });
  if (!nothing_visible_ && (state_->revision() != drawn_revision_ || !drawn_settings_)) {
    drawn_settings_ = std::make_shared<const RenderSettings>(state_->render());
    drawn_revision_ = state_->revision();
  }
  f.settings = drawn_settings_;
  f.timepoint = state_->scene().timepoint;
  drawn_timepoint_ = f.timepoint;
  f.should_render = true;
  f.display_time_ns = int64_t(frame_) * 16666667;
  if (!nothing_visible_)
    f.views = o_.stereo ? stereo_views(head, o_.ipd_m, fov, o_.width, o_.height) : std::vector<ViewSpec>{mono};
  return Status::ok();
}

void DesktopTarget::draw_annotation_overlay(const ViewSpec& view) {
  if (!tools_) return;
  annotate::AnnotationStore* store = &tools_->store();
  if (tools_->revision() != overlay_revision_) {
    overlay_revision_ = tools_->revision();
    overlay_points_.clear();
    overlay_lines_.clear();
    auto markers = store->markers();
    auto measurements = store->measurements();
    if (!markers || !measurements) {
      log_warn("viewer: " + store->path() + ": " + (!markers ? markers.status() : measurements.status()).message());
    } else {
      for (const annotate::Marker& m : *markers) overlay_points_.push_back({m.pos, m.color});
      for (const annotate::Measurement& m : *measurements)
        overlay_lines_.push_back({OverlayPoint{m.a, {1, 1, 1, 1}}, OverlayPoint{m.b, {1, 1, 1, 1}}});
    }
  }
  const VolumePlacement& placement = o_.viewer->placement;
  const Camera cam = camera_for_view(view, o_.viewer->transform);
  const glm::dvec3 forward = glm::normalize(cam.target - cam.eye);
  const glm::dvec3 right = glm::normalize(glm::cross(forward, cam.up));
  const glm::dvec3 up = glm::cross(right, forward);
  const double tx = std::tan(view.fov.right), ty = std::tan(view.fov.up);
  // Voxel coordinates -> window pixels (the renderer's convention: voxel v at (v - dims/2) * size).
  auto project = [&](const std::array<double, 3>& v, ImVec2* out) {
    glm::dvec3 w;
    for (int i = 0; i < 3; ++i) w[i] = (v[i] - 0.5 * placement.dims[i]) * placement.voxel_size[i];
    const glm::dvec3 d = w - cam.eye;
    const double z = glm::dot(d, forward);
    if (z <= 1e-9) return false;
    const double nx = glm::dot(d, right) / (z * tx), ny = glm::dot(d, up) / (z * ty);
    *out = ImVec2(float(0.5 * (nx + 1.0) * view.width), float(0.5 * (1.0 - ny) * view.height));
    return true;
  };
  auto colour = [](const std::array<double, 4>& c) {
    return ImGui::GetColorU32(ImVec4(float(c[0]), float(c[1]), float(c[2]), float(c[3])));
  };
  ImDrawList* draw = ImGui::GetBackgroundDrawList();
  const float radius = std::max(6.0f, float(view.height) / 60.0f);
  std::vector<std::array<OverlayPoint, 2>> lines = overlay_lines_;
  if (const auto& drawing = tools_->palette().live().measuring)  // the one being drawn, in grey
    lines.push_back({OverlayPoint{drawing->a, {0.7, 0.7, 0.7, 1}}, OverlayPoint{drawing->b, {0.7, 0.7, 0.7, 1}}});
  for (const auto& [a, b] : lines) {
    ImVec2 pa, pb;
    if (project(a.voxel, &pa) && project(b.voxel, &pb)) {
      draw->AddLine(pa, pb, colour(a.color), 2.0f);
      draw->AddCircle(pa, radius * 0.6f, colour(a.color), 0, 2.0f);
      draw->AddCircle(pb, radius * 0.6f, colour(b.color), 0, 2.0f);
    }
  }
  for (const OverlayPoint& p : overlay_points_) {
    ImVec2 at;
    if (!project(p.voxel, &at)) continue;
    draw->AddCircleFilled(at, radius, colour(p.color));
    draw->AddCircle(at, radius + 1.0f, IM_COL32(0, 0, 0, 255), 0, 2.0f);  // readable on bright data too
  }
}

std::array<double, 3> DesktopTarget::voxel_under(double x, double y) const {
  const VolumePlacement& placement = o_.viewer->placement;
  const CameraState c = viewer_world_camera(*state_, placement);
  const glm::dvec3 eye = vec(c.eye), focus = vec(c.target), forward = glm::normalize(focus - eye);
  const glm::dvec3 right = glm::normalize(glm::cross(forward, vec(c.up))), up = glm::cross(right, forward);
  const double ty = std::tan(c.fov_y_deg * 3.14159265358979323846 / 360.0);
  const double tx = ty * double(o_.width) / double(o_.height);
  const double nx = 2.0 * x / double(o_.width) - 1.0, ny = 1.0 - 2.0 * y / double(o_.height);
  const glm::dvec3 dir = forward + nx * tx * right + ny * ty * up;
  const glm::dvec3 w = eye + dir * (glm::dot(focus - eye, forward) / glm::dot(dir, forward));
  std::array<double, 3> voxel;
  for (int i = 0; i < 3; ++i) voxel[i] = w[i] / placement.voxel_size[i] + 0.5 * placement.dims[i];
  return voxel;
}

void DesktopTarget::on_viewer_click(double x, double y) {
  click_error_.clear();
  if (!tools_ || panel_->mode == ToolPanel::Mode::kNavigate) return;
  if (o_.stereo) {
    panel_->message = "the tools place in the mono window only";
    return;
  }
  const std::array<double, 3> v = voxel_under(x, y);
  const uint32_t t = state_->scene().timepoint;
  const Status s = panel_->mode == ToolPanel::Mode::kCount ? tools_->count({v[0], v[1], v[2]}, panel_->cls, t)
                                                             : tools_->measure_click({v[0], v[1], v[2]}, t);
  panel_->message = s ? tools_->palette().live().last_edit : s.message();
  if (!s) click_error_ = s.message();
}

Scene DesktopTarget::card_scene() const {
  Scene scene = state_->scene();
  scene.camera = viewer_world_camera(*state_, o_.viewer->placement);
  scene.has_camera = true;
  scene.viewport = {o_.width, o_.height};
  return scene;
}

Status DesktopTarget::save_panel_card(const std::string& png_path) {
  std::ifstream in(png_path, std::ios::binary);
  std::vector<uint8_t> png((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  if (!in.good() && !in.eof()) return io_error(png_path + ": cannot read the card's picture back");
  VXR_ASSIGN_OR_RETURN(annotate::Id id, tools_->card(card_scene(), panel_->card_title, panel_->card_note, std::move(png)));
  panel_->message = "card " + std::to_string(id) + " saved";
  panel_->card_title[0] = panel_->card_note[0] = '\0';
  return Status::ok();
}

// Shows a card's scene: its settings and timepoint, and the orbit that sees its camera.
Status DesktopTarget::restore_card(uint64_t id) {
  VXR_ASSIGN_OR_RETURN(annotate::Card card, tools_->store().card(id, false));
  auto scene = scene_from_json(card.scene_json);
  if (!scene) return Status(scene.status().code(), "card " + std::to_string(id) + ": " + scene.status().message());
  OrbitCamera orbit = state_->orbit();
  if (scene->has_camera) {
    const glm::dvec3 e = o_.viewer->placement.extent();
    orbit = orbit_for_camera(scene->camera, std::max({e.x, e.y, e.z}));
  }
  const Status s = state_->restore(scene->render, scene->timepoint, orbit);
  return s ? s : Status(s.code(), "card " + std::to_string(id) + ": " + s.message());
}

Status DesktopTarget::record_after_views(VkCommandBuffer cmd, FrameSubmit& submit) {
  if (!state_) return Status::ok();  // the bare window presents in end_frame
  uint32_t index = 0;
  VkResult r = vkAcquireNextImageKHR(ctx_->device(), swapchain_, UINT64_MAX, acquired_, VK_NULL_HANDLE, &index);
  if (r == VK_ERROR_OUT_OF_DATE_KHR) {
    VXR_RETURN_IF_ERROR(recreate_swapchain());
    r = vkAcquireNextImageKHR(ctx_->device(), swapchain_, UINT64_MAX, acquired_, VK_NULL_HANDLE, &index);
  }
  if (r != VK_SUCCESS && r != VK_SUBOPTIMAL_KHR)
    return gpu_error("vkAcquireNextImageKHR failed: " + std::string(gpu::vk_result_name(r)));
  const VkImage target = swap_images_[index];
  image_barrier(cmd, target, VK_IMAGE_ASPECT_COLOR_BIT, VK_IMAGE_LAYOUT_UNDEFINED, VK_IMAGE_LAYOUT_TRANSFER_DST_OPTIMAL);
  if (nothing_visible_) {
    const VkClearColorValue black{{0.0f, 0.0f, 0.0f, 1.0f}};
    const VkImageSubresourceRange all{VK_IMAGE_ASPECT_COLOR_BIT, 0, 1, 0, 1};
    vkCmdClearColorImage(cmd, target, VK_IMAGE_LAYOUT_TRANSFER_DST_OPTIMAL, &black, 1, &all);
  }
  const int32_t slot_w = int32_t(swap_extent_.width / eyes_.size());
  for (size_t v = 0; v < eyes_.size() && !nothing_visible_; ++v) {
    const gpu::Image& e = eyes_[v];
    VkImageBlit blit{};
    blit.srcSubresource = blit.dstSubresource = {VK_IMAGE_ASPECT_COLOR_BIT, 0, 0, 1};
    blit.srcOffsets[1] = {int32_t(e.extent.width), int32_t(e.extent.height), 1};
    blit.dstOffsets[0] = {int32_t(v) * slot_w, 0, 0};
    blit.dstOffsets[1] = {int32_t(v + 1) * slot_w, int32_t(swap_extent_.height), 1};
    vkCmdBlitImage(cmd, e.image, VK_IMAGE_LAYOUT_TRANSFER_SRC_OPTIMAL, target, VK_IMAGE_LAYOUT_TRANSFER_DST_OPTIMAL, 1,
                   &blit, VK_FILTER_LINEAR);
  }
  ui_->record(cmd, index);  // TRANSFER_DST -> panels drawn -> PRESENT_SRC
  if (!screenshot_pending_.empty()) {
    const VkDeviceSize bytes = VkDeviceSize(swap_extent_.width) * swap_extent_.height * 4;
    if (!screenshot_buffer_.buffer || screenshot_buffer_.size < bytes) {
      VXR_ASSIGN_OR_RETURN(screenshot_buffer_,
                           gpu::create_buffer(*ctx_, {bytes, VK_BUFFER_USAGE_TRANSFER_DST_BIT,
                                                      gpu::MemoryIntent::kReadback, "desktop screenshot"}));
    }
    image_barrier(cmd, target, VK_IMAGE_ASPECT_COLOR_BIT, VK_IMAGE_LAYOUT_PRESENT_SRC_KHR,
                  VK_IMAGE_LAYOUT_TRANSFER_SRC_OPTIMAL);
    VkBufferImageCopy region{};
    region.imageSubresource = {VK_IMAGE_ASPECT_COLOR_BIT, 0, 0, 1};
    region.imageExtent = {swap_extent_.width, swap_extent_.height, 1};
    vkCmdCopyImageToBuffer(cmd, target, VK_IMAGE_LAYOUT_TRANSFER_SRC_OPTIMAL, screenshot_buffer_.buffer, 1, &region);
    VkMemoryBarrier to_host{VK_STRUCTURE_TYPE_MEMORY_BARRIER};
    to_host.srcAccessMask = VK_ACCESS_TRANSFER_WRITE_BIT;
    to_host.dstAccessMask = VK_ACCESS_HOST_READ_BIT;
    vkCmdPipelineBarrier(cmd, VK_PIPELINE_STAGE_TRANSFER_BIT, VK_PIPELINE_STAGE_HOST_BIT, 0, 1, &to_host, 0, nullptr,
                         0, nullptr);
    image_barrier(cmd, target, VK_IMAGE_ASPECT_COLOR_BIT, VK_IMAGE_LAYOUT_TRANSFER_SRC_OPTIMAL,
                  VK_IMAGE_LAYOUT_PRESENT_SRC_KHR);
  }
  submit.wait.push_back(acquired_);
  submit.signal.push_back(render_done_[index]);
  image_acquired_ = true;
  image_index_ = index;
  return Status::ok();
}

// The swapchain image the frame copied (B8G8R8A8 or R8G8B8A8, sRGB-encoded
// bytes where the window is sRGB: what the window shows) as a PNG.
Status DesktopTarget::write_screenshot() {
  const std::string path = screenshot_pending_;
  screenshot_pending_.clear();
  if (!screenshot_buffer_.host_coherent) {
    VkMappedMemoryRange range{VK_STRUCTURE_TYPE_MAPPED_MEMORY_RANGE};
    range.memory = screenshot_buffer_.memory;
    range.size = VK_WHOLE_SIZE;
    VXR_VK_TRY(vkInvalidateMappedMemoryRanges(ctx_->device(), 1, &range));
  }
  const bool bgra = swap_format_ == VK_FORMAT_B8G8R8A8_SRGB || swap_format_ == VK_FORMAT_B8G8R8A8_UNORM;
  ImageRgba8 img(swap_extent_.width, swap_extent_.height);
  const auto* src = static_cast<const uint8_t*>(screenshot_buffer_.mapped);
  for (size_t i = 0; i < size_t(img.width) * img.height; ++i) {
    const uint8_t* p = src + 4 * i;
    uint8_t* o = &img.pixels[4 * i];
    o[0] = bgra ? p[2] : p[0];
    o[1] = p[1];
    o[2] = bgra ? p[0] : p[2];
    o[3] = 255;  // the window is opaque
  }
  VXR_RETURN_IF_ERROR(write_png(path, img));
  if (script_ && !(card_temp_ && path == card_temp_->path())) script_->screenshot_written(path);
  log_info("viewer: screenshot " + path + " (timepoint " + std::to_string(drawn_timepoint_) + ")");
  return Status::ok();
}

}  // namespace vxr::xr
