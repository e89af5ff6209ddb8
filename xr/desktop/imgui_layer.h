// Dear ImGui drawn into the desktop window's swapchain image, in the frame's
// own command buffer after the volume. Debian's libimgui 1.86 Vulkan backend
// draws inside a VkRenderPass: ours loads the image the eyes were blitted
// into (TRANSFER_DST_OPTIMAL) and leaves it ready to present.
#pragma once

#include <vulkan/vulkan.h>

#include <memory>
#include <vector>

#include "core/status.h"
#include "gpu/context.h"
#include "gpu/handle.h"

struct GLFWwindow;

namespace vxr::xr {

class ImGuiLayer {
 public:
  // ImGui keeps one global context: one layer at a time. Installs ImGui's
  // GLFW callbacks, which call the window's earlier ones too.
  static Result<std::unique_ptr<ImGuiLayer>> create(GLFWwindow* window, gpu::Context& ctx, VkFormat format,
                                                    const std::vector<VkImage>& images, VkExtent2D extent);
  ~ImGuiLayer();
  ImGuiLayer(const ImGuiLayer&) = delete;
  ImGuiLayer& operator=(const ImGuiLayer&) = delete;

  // After the swapchain was made again: framebuffers for its images.
  Status set_images(const std::vector<VkImage>& images, VkExtent2D extent);

  // Between begin() and end() the caller issues ImGui calls.
  void begin();
  void end();
  // Records the frame's draw lists over swapchain image `index` (in
  // TRANSFER_DST_OPTIMAL) and leaves it in PRESENT_SRC_KHR.
  void record(VkCommandBuffer cmd, uint32_t index);

  // ImGui uses the mouse / keyboard this frame (a panel is under the cursor
  // or a field has focus): the viewer's navigation leaves them alone.
  static bool wants_mouse();
  static bool wants_keyboard();

 private:
  ImGuiLayer(gpu::Context& ctx, VkFormat format) : ctx_(ctx), format_(format) {}
  void destroy_framebuffers();

  gpu::Context& ctx_;
  VkFormat format_;
  VkExtent2D extent_{0, 0};
  bool glfw_ready_ = false, vulkan_ready_ = false;
  gpu::Handle<VkDescriptorPool> pool_;
  gpu::Handle<VkRenderPass> pass_;
  std::vector<VkImageView> views_;
  std::vector<VkFramebuffer> framebuffers_;
};

}  // namespace vxr::xr
