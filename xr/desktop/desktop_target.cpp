#include "xr/desktop/desktop_target.h"

#define GLFW_INCLUDE_VULKAN
#include <filesystem>
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
#include <cstring>
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
#include "xr/desktop/viewer_movie.h"
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
// While the view moves, voxels twice as large per pixel (one pyramid level coarser: an eighth of the bricks
// to stream, half the samples along each ray), so the picture follows the mouse on large data; the first
// still frame is drawn at full detail again.
constexpr double kMovingLodBias = 1.0;
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
  // A click (press and release within a few pixels, not on a panel) places with the tools panel's tool;
  // with the ROI tool a drag draws the box.
  glfwSetMouseButtonCallback(t->window_, [](GLFWwindow* win, int button, int action, int) {
    DesktopTarget* target = self(win);
    if (!target->tools_ || button != GLFW_MOUSE_BUTTON_LEFT) return;
    double x = 0, y = 0;
    glfwGetCursorPos(win, &x, &y);
    const bool roi = target->panel_->mode == ToolPanel::Mode::kRoi;
    if (action == GLFW_PRESS) {
      target->press_x_ = x;
      target->press_y_ = y;
      target->press_on_ui_ = ImGuiLayer::wants_mouse();
      if (roi && !target->press_on_ui_) target->on_roi_drag(int(annotate::ToolAction::kPress), x, y);
    } else if (action == GLFW_RELEASE && target->roi_dragging_) {
      target->on_roi_drag(int(annotate::ToolAction::kRelease), x, y);
    } else if (action == GLFW_RELEASE && !roi && !target->press_on_ui_ &&
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
    if (!k || !target->state_ || ImGuiLayer::wants_keyboard()) return;
    target->state_->handle_key(*k);
    if (k == ViewerKey::kFinishTool && target->tools_) target->finish_tool();
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
    movie_panel_ = std::make_unique<MoviePanel>();
    open_panel_ = std::make_unique<OpenPanel>();
    // `vxr view --card ID`: the window starts at the card's camera.
    if (o_.viewer->start_orbit) {
      const Status s = state_->restore(state_->render(), state_->scene().timepoint, *o_.viewer->start_orbit);
      if (!s) log_warn("viewer: the card's camera: " + s.message());
    }
    if (o_.viewer->restore_view) restore_remembered_view();
    if (o_.viewer->script)
      script_ = std::make_unique<UiScriptRunner>(*o_.viewer->script, tools_.get(),
                                                 [this](const ViewerState&) { return card_scene(); });
  }
}

void DesktopTarget::on_viewer_cursor(double dx, double dy) {
  double x = 0, y = 0;
  glfwGetCursorPos(window_, &x, &y);
  if (roi_dragging_) {  // the box follows the cursor; the view stays
    on_roi_drag(int(annotate::ToolAction::kMove), x, y);
    return;
  }
  if (ImGuiLayer::wants_mouse()) return;
  if (tools_ && panel_->mode == ToolPanel::Mode::kMeasure) {
    // The measurement being drawn follows the cursor.
    if (const auto v = voxel_under(x, y))
      if (Status s = tools_->measure_hover(*v, state_->scene().timepoint); !s) panel_->message = s.message();
  }
  if (glfwGetMouseButton(window_, GLFW_MOUSE_BUTTON_LEFT) == GLFW_PRESS) {
    state_->orbit_drag(dx, dy);
    state_->note_motion();
  } else if (glfwGetMouseButton(window_, GLFW_MOUSE_BUTTON_RIGHT) == GLFW_PRESS ||
             glfwGetMouseButton(window_, GLFW_MOUSE_BUTTON_MIDDLE) == GLFW_PRESS) {
    state_->pan_drag(dx, dy, double(o_.height));
    state_->note_motion();
  }
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
    if (!ImGuiLayer::wants_mouse()) {
      state_->zoom(dy);
      state_->note_motion();
    }
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

void DesktopTarget::restore_remembered_view() {
  const std::string& path = o_.viewer->view_memory;
  if (path.empty()) return;
  auto remembered = load_remembered_view(path);
  if (!remembered) {
    log_warn("viewer: " + remembered.status().message() + ": ignored");
    return;
  }
  if (!*remembered) return;  // the first time this dataset opens
  const Scene& scene = **remembered;
  if (scene.volume != o_.viewer->scene.volume || scene.channels != o_.viewer->scene.channels) {
    log_warn("viewer: " + path + ": remembers another input or other channels (" + scene.volume + "): ignored");
    return;
  }
  const OrbitCamera orbit = scene_orbit(scene, o_.viewer->placement).value_or(state_->orbit());
  if (Status s = state_->restore(scene.render, scene.timepoint, orbit); !s)
    log_warn("viewer: " + path + ": " + s.message() + ": ignored");
}

void DesktopTarget::remember_view() {
  if (!state_ || o_.viewer->view_memory.empty()) return;
  if (Status s = save_remembered_view(o_.viewer->view_memory, card_scene()); !s)
    log_warn("viewer: view not remembered: " + s.message());
}

void DesktopTarget::detach() {
  if (ctx_) remember_view();  // once per session the window drew, before its size is forgotten
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
  movie_buffer_ = {};
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
    // A movie keeps its frame size: the window follows a resize once the export is written.
    if (resized_ && !export_) VXR_RETURN_IF_ERROR(follow_window_size());
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
    if (movie_frame_pending_) {
      movie_frame_pending_ = false;
      const Status s = write_movie_frame();
      if (!s && export_from_script_) return s;
      if (!s) movie_panel_->message = s.message();
    }
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

void DesktopTarget::request_open(const std::string& path) {
  if (!o_.viewer || !o_.viewer->open_request) return;
  *o_.viewer->open_request = path;
  exit_requested_ = true;
}

// The script's steps due this frame, acted on as the panels' buttons and the mouse would.
Status DesktopTarget::script_frame(FrameState& f, bool* card, std::optional<uint64_t>* restore) {
  const std::string& path = o_.viewer->script->path;
  click_error_.clear();
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
    static const std::pair<const char*, ToolPanel::Mode> modes[] = {
        {"navigate", ToolPanel::Mode::kNavigate}, {"count", ToolPanel::Mode::kCount}, {"measure", ToolPanel::Mode::kMeasure},
        {"trace", ToolPanel::Mode::kTrace},       {"track", ToolPanel::Mode::kTrack}, {"roi", ToolPanel::Mode::kRoi}};
    tools_->cancel();
    for (const auto& [n, mode] : modes)
      if (name == n) panel_->mode = mode;
    if (name == "count" || name == "track")
      std::snprintf(panel_->cls, sizeof panel_->cls, "%s", work.tool.substr(name.size() + 1).c_str());
  }
  if (work.open) request_open(*work.open);
  if (work.panel_card) std::snprintf(panel_->card_title, sizeof panel_->card_title, "%s", work.panel_card->c_str());
  *card = work.panel_card.has_value();
  *restore = work.restore_card;
  if (work.finish) finish_tool();
  if (work.remove) remove_annotation(work.remove->first, work.remove->second);
  if (work.keyframe) add_keyframe();
  if (work.export_movie) {
    export_from_script_ = true;
    if (Status s = start_movie_export(*work.export_movie); !s) return invalid_argument(path + ": export-movie: " + s.message());
  }
  if (work.click) on_viewer_click((*work.click)[0], (*work.click)[1]);
  if (work.drag) {  // press, a move half way, release: as the mouse sends them
    const auto& d = *work.drag;
    on_roi_drag(int(annotate::ToolAction::kPress), d[0], d[1]);
    if (click_error_.empty()) on_roi_drag(int(annotate::ToolAction::kMove), 0.5 * (d[0] + d[2]), 0.5 * (d[1] + d[3]));
    if (click_error_.empty()) on_roi_drag(int(annotate::ToolAction::kRelease), d[2], d[3]);
  }
  // A script stops at the first refused click, drag, finish or remove, as at any refused step.
  if (!click_error_.empty()) return invalid_argument(path + ": " + click_error_);
  return Status::ok();
}

Fov DesktopTarget::viewer_fov() const {
  const double ty = std::tan(state_->orbit().fov_y_deg * 3.14159265358979323846 / 360.0);
  const double tx = ty * double(o_.width) / double(o_.height);
  return Fov{-std::atan(tx), std::atan(tx), std::atan(ty), -std::atan(ty)};
}

std::vector<WindowView> DesktopTarget::viewer_window_views() const {
  const Pose head = pose_for_camera(viewer_world_camera(*state_, o_.viewer->placement), o_.viewer->transform);
  const Fov fov = viewer_fov();
  if (!o_.stereo) return {WindowView{ViewSpec{head, fov, o_.width, o_.height}, 0.0}};
  std::vector<WindowView> views;
  for (const ViewSpec& eye : stereo_views(head, o_.ipd_m, fov, o_.width, o_.height))
    views.push_back({eye, double(views.size() * o_.width)});
  return views;
}

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
  // Held W/S/A/D/Q/E fly over this frame's time (not while a panel's text field has the keyboard).
  const FlyInput held = held_fly_keys([this](int key) { return glfwGetKey(window_, key) == GLFW_PRESS; });
  if (held.any() && !ImGuiLayer::wants_keyboard()) {
    state_->fly_for(held, frame_ms_ / 1000.0);
    state_->note_motion();
  }
  bool script_card = false;  // the script pressed the tools panel's buttons
  std::optional<uint64_t> script_restore;
  if (script_ && !export_) {  // a movie being exported holds the script until it is written
    VXR_RETURN_IF_ERROR(script_frame(f, &script_card, &script_restore));
    if (f.exit) return Status::ok();
  }
  if (state_->quit_requested()) glfwSetWindowShouldClose(window_, GLFW_TRUE);
  glfwSetWindowTitle(window_, (viewer_window_title(setup.dataset, frame_ms_) +
                               (export_ ? " - movie frame " + std::to_string(export_->next_frame() + 1) + "/" +
                                              std::to_string(export_->request().frames)
                                        : std::string()))
                                  .c_str());

  ui_->begin();
  PanelInputs in;
  in.dataset = setup.dataset;
  in.frame_ms = frame_ms_;
  in.histograms = setup.histograms;
  draw_viewer_panels(*state_, in);
  if (state_->ui_visible() && setup.open_request && open_panel_) {
    draw_open_panel(*open_panel_);
    if (open_panel_->open) {
      std::error_code ec;
      if (std::filesystem::exists(open_panel_->path, ec))
        request_open(open_panel_->path);
      else
        open_panel_->message = std::string(open_panel_->path) + " does not exist";
    }
  }
  if (state_->ui_visible()) {
    movie_panel_->keyframes = keyframes_.size();
    movie_panel_->progress = export_ ? std::optional<double>(export_->progress()) : std::nullopt;
    draw_movie_panel(*movie_panel_);
    if (movie_panel_->add_keyframe) add_keyframe();
    if (movie_panel_->clear_keyframes) keyframes_.clear();
    if (movie_panel_->start_export) {
      export_from_script_ = false;
      const Status s = start_movie_export({movie_panel_->output, uint64_t(movie_panel_->frames), movie_panel_->fps});
      if (!s) movie_panel_->message = s.message();
    }
  }
  if (tools_) {
    if (state_->ui_visible()) {
      draw_tools_panel(*tools_, *panel_, state_->scene().timepoint);  // sets save_card / restore / finish / remove
    } else {
      panel_->save_card = false;
      panel_->restore.reset();
      panel_->finish = false;
      panel_->remove.reset();
    }
    if (panel_->finish) finish_tool();
    if (panel_->remove) remove_annotation(panel_->remove->first, panel_->remove->second);
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
  std::vector<WindowView> views = viewer_window_views();
  movie_frame_pending_ = export_ != nullptr;
  if (export_) {  // the movie's camera instead of the orbit: one view, eye 0 read back
    views = {WindowView{ViewSpec{export_->pose(export_->next_frame()), viewer_fov(), o_.width, o_.height}, 0.0}};
  } else {
    draw_annotation_overlay(views);
  }
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
  // Coarse while the user moves the view, full detail once it is still (progressive refinement).
  f.lod_bias_offset = state_->moving() ? kMovingLodBias : 0.0;
  drawn_timepoint_ = f.timepoint;
  f.should_render = true;
  f.display_time_ns = int64_t(frame_) * 16666667;
  if (!nothing_visible_)
    for (const WindowView& v : views) f.views.push_back(v.view);
  return Status::ok();
}

void DesktopTarget::read_overlay() {
  if (tools_->revision() == overlay_revision_) return;
  overlay_revision_ = tools_->revision();
  overlay_ = {};
  annotate::AnnotationStore& store = tools_->store();
  auto markers = store.markers();
  auto measurements = store.measurements();
  auto skeletons = store.skeletons();
  auto tracks = store.tracks();
  auto rois = store.rois();
  for (const Status& s : {markers.status(), measurements.status(), skeletons.status(), tracks.status(), rois.status()})
    if (!s) {
      log_warn("viewer: " + store.path() + ": " + s.message());
      return;
    }
  std::map<annotate::Id, annotate::Marker> by_id;
  for (const annotate::Marker& m : *markers) {
    overlay_.markers.push_back({OverlayPoint{m.pos, m.color}, m.timepoint});
    by_id[m.id] = m;
  }
  for (const annotate::Measurement& m : *measurements)
    overlay_.lines.push_back({OverlayPoint{m.a, {1, 1, 1, 1}}, OverlayPoint{m.b, {1, 1, 1, 1}}});
  const std::array<double, 4> skeleton_colour{0, 1, 0, 1}, track_colour{1, 0, 1, 1};
  for (const annotate::SkeletonInfo& info : *skeletons) {
    auto sk = store.skeleton(info.id);
    if (!sk) {
      log_warn("viewer: " + store.path() + ": " + sk.status().message());
      continue;
    }
    for (const auto& [id, n] : sk->nodes()) {
      overlay_.nodes.push_back({n.pos, skeleton_colour});
      if (const annotate::SkeletonNode* p = sk->find(n.parent))
        overlay_.lines.push_back({OverlayPoint{p->pos, skeleton_colour}, OverlayPoint{n.pos, skeleton_colour}});
    }
  }
  for (const annotate::Track& t : *tracks)  // its markers in timepoint order, one step to the next
    for (size_t i = 1; i < t.markers.size(); ++i)
      if (by_id.count(t.markers[i - 1]) && by_id.count(t.markers[i]))
        overlay_.lines.push_back({OverlayPoint{by_id[t.markers[i - 1]].pos, track_colour},
                                  OverlayPoint{by_id[t.markers[i]].pos, track_colour}});
  for (const annotate::Roi& r : *rois) overlay_.boxes.push_back({r.min, r.max});
}

void DesktopTarget::draw_annotation_overlay(const std::vector<WindowView>& views) {
  if (!tools_) return;
  read_overlay();
  for (const WindowView& v : views) draw_overlay_view(v);
}

void DesktopTarget::draw_overlay_view(const WindowView& view) {
  const VolumePlacement& placement = o_.viewer->placement;
  const VolumeTransform& transform = o_.viewer->transform;
  auto project = [&](const std::array<double, 3>& v, ImVec2* out) {
    const auto p = project_voxel(view, transform, placement, v);
    if (p) *out = ImVec2(float((*p)[0]), float((*p)[1]));
    return p.has_value();
  };
  auto colour = [](const std::array<double, 4>& c) {
    return ImGui::GetColorU32(ImVec4(float(c[0]), float(c[1]), float(c[2]), float(c[3])));
  };
  ImDrawList* draw = ImGui::GetBackgroundDrawList();
  draw->PushClipRect(ImVec2(float(view.x0), 0), ImVec2(float(view.x0 + view.view.width), float(view.view.height)));
  const float radius = std::max(6.0f, float(view.view.height) / 60.0f);
  const annotate::ToolLiveState& live = tools_->palette().live();
  std::vector<std::array<OverlayPoint, 2>> lines = overlay_.lines;
  if (const auto& drawing = live.measuring)  // the one being drawn, in grey
    lines.push_back({OverlayPoint{drawing->a, {0.7, 0.7, 0.7, 1}}, OverlayPoint{drawing->b, {0.7, 0.7, 0.7, 1}}});
  for (const auto& [a, b] : lines) {
    ImVec2 pa, pb;
    if (project(a.voxel, &pa) && project(b.voxel, &pb)) draw->AddLine(pa, pb, colour(a.color), 2.0f);
  }
  for (const auto& m : overlay_.lines) {  // measurement ends (white) get rings
    ImVec2 pa, pb;
    if (m[0].color != std::array<double, 4>{1, 1, 1, 1}) continue;
    if (project(m[0].voxel, &pa) && project(m[1].voxel, &pb)) {
      draw->AddCircle(pa, radius * 0.6f, colour(m[0].color), 0, 2.0f);
      draw->AddCircle(pb, radius * 0.6f, colour(m[1].color), 0, 2.0f);
    }
  }
  for (const OverlayPoint& n : overlay_.nodes) {
    ImVec2 at;
    if (project(n.voxel, &at)) draw->AddCircleFilled(at, radius * 0.4f, colour(n.color));
  }
  // Boxes: the 12 edges of each (the one being dragged or last stored in grey when it is not stored yet).
  std::vector<std::array<std::array<double, 3>, 2>> boxes = overlay_.boxes;
  if (live.roi && live.roi->id == 0) boxes.push_back({live.roi->min, live.roi->max});
  for (const auto& [lo, hi] : boxes) {
    const ImU32 c = colour(live.roi && live.roi->id == 0 && lo == live.roi->min && hi == live.roi->max
                               ? std::array<double, 4>{0.7, 0.7, 0.7, 1}
                               : std::array<double, 4>{0, 1, 1, 1});
    for (int edge = 0; edge < 12; ++edge) {
      const int axis = edge / 4, a = (axis + 1) % 3, b = (axis + 2) % 3;
      std::array<double, 3> p = lo, q = lo;
      p[a] = q[a] = (edge & 1) ? hi[a] : lo[a];
      p[b] = q[b] = (edge & 2) ? hi[b] : lo[b];
      q[axis] = hi[axis];
      ImVec2 pp, pq;
      if (project(p, &pp) && project(q, &pq)) draw->AddLine(pp, pq, c, 2.0f);
    }
  }
  const uint32_t t = state_->scene().timepoint;
  for (const auto& [p, timepoint] : overlay_.markers) {
    ImVec2 at;
    if (!project(p.voxel, &at)) continue;
    if (timepoint != t) {  // another timepoint's marker (a track's): a ring
      draw->AddCircle(at, radius, colour(p.color), 0, 2.0f);
      continue;
    }
    draw->AddCircleFilled(at, radius, colour(p.color));
    draw->AddCircle(at, radius + 1.0f, IM_COL32(0, 0, 0, 255), 0, 2.0f);  // readable on bright data too
    if (live.roi && live.roi->contains(p.voxel))  // inside the box being dragged or last stored: a cyan ring
      draw->AddCircle(at, radius + 4.0f, colour({0, 1, 1, 1}), 0, 2.0f);
  }
  draw->PopClipRect();
}

std::optional<std::array<double, 3>> DesktopTarget::voxel_under(double x, double y) const {
  const std::vector<WindowView> views = viewer_window_views();
  const std::optional<size_t> v = view_at(views, x);
  if (!v) return std::nullopt;
  const glm::dvec3 focus = vec(viewer_world_camera(*state_, o_.viewer->placement).target);
  return xr::voxel_under(views[*v], o_.viewer->transform, o_.viewer->placement, focus, x, y);
}

void DesktopTarget::on_viewer_click(double x, double y) {
  click_error_.clear();
  if (!tools_ || panel_->mode == ToolPanel::Mode::kNavigate || panel_->mode == ToolPanel::Mode::kRoi) return;
  const std::optional<std::array<double, 3>> v = voxel_under(x, y);
  if (!v) {
    click_error_ = panel_->message = "click: the pixel's ray does not meet the plane through the orbit centre";
    return;
  }
  const annotate::Vec3 at{(*v)[0], (*v)[1], (*v)[2]};
  const uint32_t t = state_->scene().timepoint;
  Status s = Status::ok();
  switch (panel_->mode) {
    case ToolPanel::Mode::kCount: s = tools_->count(at, panel_->cls, t); break;
    case ToolPanel::Mode::kMeasure: s = tools_->measure_click(at, t); break;
    case ToolPanel::Mode::kTrace: s = tools_->trace_click(traced_node_under(x, y).value_or(at), t); break;
    case ToolPanel::Mode::kTrack: s = tools_->track_click(at, panel_->cls, t); break;
    default: break;
  }
  panel_->message = s ? tools_->palette().live().last_edit : s.message();
  if (!s) click_error_ = "click: " + s.message();
}

// The node of the skeleton being traced drawn within a few pixels of (x, y): clicking it continues from it.
std::optional<annotate::Vec3> DesktopTarget::traced_node_under(double x, double y) const {
  const annotate::Id skeleton = tools_->palette().live().skeleton;
  if (skeleton == 0) return std::nullopt;
  auto sk = tools_->store().skeleton(skeleton);
  if (!sk) return std::nullopt;  // the click adds a node, which reports the store's problem
  std::vector<std::array<double, 3>> positions;
  for (const auto& [id, n] : sk->nodes()) positions.push_back(n.pos);
  const std::vector<WindowView> views = viewer_window_views();
  const std::optional<size_t> v = view_at(views, x);
  if (!v) return std::nullopt;
  const auto hit = nearest_on_screen(views[*v], o_.viewer->transform, o_.viewer->placement, positions, x, y, 8.0);
  if (!hit) return std::nullopt;
  return positions[*hit];
}

void DesktopTarget::on_roi_drag(int action_code, double x, double y) {
  if (!tools_ || panel_->mode != ToolPanel::Mode::kRoi) {
    click_error_ = "drag: the ROI tool draws boxes (tool roi)";
    return;
  }
  const auto action = annotate::ToolAction(action_code);
  const std::vector<WindowView> views = viewer_window_views();
  if (action == annotate::ToolAction::kPress) {
    const std::optional<size_t> v = view_at(views, x);
    if (!v) return;
    roi_view_ = *v;
    roi_axis_ = depth_axis(views[*v], o_.viewer->transform);
  }
  if (roi_view_ >= views.size()) return;
  // A drag that left its view keeps to it: the pixel is seen through the view it started in.
  const glm::dvec3 focus = vec(viewer_world_camera(*state_, o_.viewer->placement).target);
  const auto voxel = xr::voxel_under(views[roi_view_], o_.viewer->transform, o_.viewer->placement, focus, x, y);
  if (!voxel) return;
  // The box spans the dragged rectangle and the whole volume along the axis nearest the view direction.
  const auto corner = on_volume_face(*voxel, roi_axis_, o_.viewer->placement, action != annotate::ToolAction::kPress);
  const Status s = tools_->roi_drag(action, {corner[0], corner[1], corner[2]}, state_->scene().timepoint);
  roi_dragging_ = s && action != annotate::ToolAction::kRelease;
  panel_->message = s ? tools_->palette().live().last_edit : s.message();
  if (!s) click_error_ = "drag: " + s.message();
}

void DesktopTarget::finish_tool() {
  const Status s = tools_->finish(state_->scene().timepoint);
  panel_->message = s ? tools_->palette().live().last_edit : s.message();
  if (!s) click_error_ = "finish: " + s.message();
}

void DesktopTarget::remove_annotation(AnnotationKind kind, uint64_t id) {
  const Status s = tools_->remove(kind, id);
  panel_->message = s ? std::string("removed ") + annotation_kind_name(kind) + " " + std::to_string(id) : s.message();
  if (!s) click_error_ = std::string("remove ") + annotation_kind_name(kind) + " " + std::to_string(id) + ": " + s.message();
}

void DesktopTarget::add_keyframe() {
  keyframes_.push_back(pose_for_camera(viewer_world_camera(*state_, o_.viewer->placement), o_.viewer->transform));
  movie_panel_->message = "keyframe " + std::to_string(keyframes_.size()) + " added";
}

Status DesktopTarget::start_movie_export(const MovieRequest& request) {
  if (o_.stereo) return unsupported(request.output + ": movies are exported from the mono window (drop --stereo)");
  if (export_) return invalid_argument(request.output + ": a movie is being exported already");
  const std::string inputs[] = {o_.viewer->scene.volume, o_.viewer->script ? o_.viewer->script->path : std::string(),
                                o_.viewer->store ? o_.viewer->store->path() : std::string()};
  VXR_ASSIGN_OR_RETURN(MovieExport m, MovieExport::start(request, keyframes_, inputs));
  export_ = std::make_unique<MovieExport>(std::move(m));
  movie_panel_->message = "exporting " + std::to_string(request.frames) + " frames to " + request.output;
  return Status::ok();
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
  const OrbitCamera orbit = scene_orbit(*scene, o_.viewer->placement).value_or(state_->orbit());
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
  movie_copied_ = movie_frame_pending_ && !nothing_visible_;
  if (movie_copied_) VXR_RETURN_IF_ERROR(record_movie_copy(cmd));
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

// The movie's frame: eye 0 as rendered (no panels, no overlay), into a host buffer.
Status DesktopTarget::record_movie_copy(VkCommandBuffer cmd) {
  const gpu::Image& eye = eyes_.front();
  const VkDeviceSize bytes = VkDeviceSize(eye.extent.width) * eye.extent.height * 4;
  if (!movie_buffer_.buffer || movie_buffer_.size < bytes) {
    VXR_ASSIGN_OR_RETURN(movie_buffer_, gpu::create_buffer(*ctx_, {bytes, VK_BUFFER_USAGE_TRANSFER_DST_BIT,
                                                                   gpu::MemoryIntent::kReadback, "desktop movie frame"}));
  }
  VkBufferImageCopy region{};
  region.imageSubresource = {VK_IMAGE_ASPECT_COLOR_BIT, 0, 0, 1};
  region.imageExtent = {eye.extent.width, eye.extent.height, 1};
  // The eye rests in TRANSFER_SRC_OPTIMAL, written before the blit that just read it.
  vkCmdCopyImageToBuffer(cmd, eye.image, VK_IMAGE_LAYOUT_TRANSFER_SRC_OPTIMAL, movie_buffer_.buffer, 1, &region);
  VkMemoryBarrier to_host{VK_STRUCTURE_TYPE_MEMORY_BARRIER};
  to_host.srcAccessMask = VK_ACCESS_TRANSFER_WRITE_BIT;
  to_host.dstAccessMask = VK_ACCESS_HOST_READ_BIT;
  vkCmdPipelineBarrier(cmd, VK_PIPELINE_STAGE_TRANSFER_BIT, VK_PIPELINE_STAGE_HOST_BIT, 0, 1, &to_host, 0, nullptr, 0,
                       nullptr);
  return Status::ok();
}

// Writes the frame record_movie_copy read back; after the last, the MP4 (if one was asked for).
Status DesktopTarget::write_movie_frame() {
  std::unique_ptr<MovieExport> m = std::move(export_);  // back below unless this ends it
  if (!m) return Status::ok();
  if (!movie_buffer_.host_coherent) {
    VkMappedMemoryRange range{VK_STRUCTURE_TYPE_MAPPED_MEMORY_RANGE};
    range.memory = movie_buffer_.memory;
    range.size = VK_WHOLE_SIZE;
    VXR_VK_TRY(vkInvalidateMappedMemoryRanges(ctx_->device(), 1, &range));
  }
  const gpu::Image& eye = eyes_.front();
  ImageRgba8 img(eye.extent.width, eye.extent.height);  // the eyes are RGBA8 (sRGB-encoded on an sRGB window)
  if (movie_copied_)  // else every channel was hidden: a black frame, as the window showed
    std::memcpy(img.pixels.data(), movie_buffer_.mapped, img.pixels.size());
  for (size_t i = 3; i < img.pixels.size(); i += 4) img.pixels[i] = 255;  // the window is opaque
  VXR_ASSIGN_OR_RETURN(std::string path, m->frame_path(m->next_frame()));
  VXR_RETURN_IF_ERROR(write_png(path, img));
  m->frame_written();
  if (!m->done()) {
    export_ = std::move(m);
    return Status::ok();
  }
  VXR_ASSIGN_OR_RETURN(std::string written, m->finish());
  movie_panel_->message = "movie " + written + ": " + std::to_string(m->request().frames) + " frames";
  log_info("viewer: " + movie_panel_->message);
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
