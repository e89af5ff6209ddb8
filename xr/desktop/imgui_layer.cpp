#include "xr/desktop/imgui_layer.h"

#include <GLFW/glfw3.h>
#include <imgui.h>
#include <backends/imgui_impl_glfw.h>
#include <backends/imgui_impl_vulkan.h>

#include "gpu/vk_check.h"

namespace vxr::xr {
namespace {

VkResult g_backend_result = VK_SUCCESS;  // the Vulkan backend's last failure, reported by the next call
void on_backend_result(VkResult r) {
  if (r != VK_SUCCESS) g_backend_result = r;
}

}  // namespace

Result<std::unique_ptr<ImGuiLayer>> ImGuiLayer::create(GLFWwindow* window, gpu::Context& ctx, VkFormat format,
                                                       const std::vector<VkImage>& images, VkExtent2D extent) {
  if (ImGui::GetCurrentContext()) return internal_error("an ImGui layer already exists in this process");
  std::unique_ptr<ImGuiLayer> l(new ImGuiLayer(ctx, format));
  IMGUI_CHECKVERSION();
  ImGui::CreateContext();
  ImGuiIO& io = ImGui::GetIO();
  io.IniFilename = nullptr;  // panel placement is the viewer's, not a stray imgui.ini in the working folder
  ImGui::StyleColorsDark();
  if (!ImGui_ImplGlfw_InitForVulkan(window, true)) return internal_error("ImGui's GLFW backend did not start");
  l->glfw_ready_ = true;

  // The backend allocates one descriptor set (the font texture).
  VkDescriptorPoolSize size{VK_DESCRIPTOR_TYPE_COMBINED_IMAGE_SAMPLER, 4};
  VkDescriptorPoolCreateInfo dpi{VK_STRUCTURE_TYPE_DESCRIPTOR_POOL_CREATE_INFO};
  dpi.flags = VK_DESCRIPTOR_POOL_CREATE_FREE_DESCRIPTOR_SET_BIT;
  dpi.maxSets = 4;
  dpi.poolSizeCount = 1;
  dpi.pPoolSizes = &size;
  VkDescriptorPool pool = VK_NULL_HANDLE;
  VXR_VK_TRY(vkCreateDescriptorPool(ctx.device(), &dpi, nullptr, &pool));
  l->pool_ = gpu::Handle<VkDescriptorPool>(ctx.device(), pool);

  // Loads what the blit left, draws over it, hands it to the presentation engine.
  VkAttachmentDescription color{};
  color.format = format;
  color.samples = VK_SAMPLE_COUNT_1_BIT;
  color.loadOp = VK_ATTACHMENT_LOAD_OP_LOAD;
  color.storeOp = VK_ATTACHMENT_STORE_OP_STORE;
  color.stencilLoadOp = VK_ATTACHMENT_LOAD_OP_DONT_CARE;
  color.stencilStoreOp = VK_ATTACHMENT_STORE_OP_DONT_CARE;
  color.initialLayout = VK_IMAGE_LAYOUT_TRANSFER_DST_OPTIMAL;
  color.finalLayout = VK_IMAGE_LAYOUT_PRESENT_SRC_KHR;
  VkAttachmentReference ref{0, VK_IMAGE_LAYOUT_COLOR_ATTACHMENT_OPTIMAL};
  VkSubpassDescription sub{};
  sub.pipelineBindPoint = VK_PIPELINE_BIND_POINT_GRAPHICS;
  sub.colorAttachmentCount = 1;
  sub.pColorAttachments = &ref;
  VkSubpassDependency deps[2] = {};
  deps[0].srcSubpass = VK_SUBPASS_EXTERNAL;  // the blit's writes before the load
  deps[0].dstSubpass = 0;
  deps[0].srcStageMask = VK_PIPELINE_STAGE_TRANSFER_BIT;
  deps[0].srcAccessMask = VK_ACCESS_TRANSFER_WRITE_BIT;
  deps[0].dstStageMask = VK_PIPELINE_STAGE_COLOR_ATTACHMENT_OUTPUT_BIT;
  deps[0].dstAccessMask = VK_ACCESS_COLOR_ATTACHMENT_READ_BIT | VK_ACCESS_COLOR_ATTACHMENT_WRITE_BIT;
  deps[1].srcSubpass = 0;  // the panels' writes before any later copy (a screenshot) or the present
  deps[1].dstSubpass = VK_SUBPASS_EXTERNAL;
  deps[1].srcStageMask = VK_PIPELINE_STAGE_COLOR_ATTACHMENT_OUTPUT_BIT;
  deps[1].srcAccessMask = VK_ACCESS_COLOR_ATTACHMENT_WRITE_BIT;
  deps[1].dstStageMask = VK_PIPELINE_STAGE_TRANSFER_BIT | VK_PIPELINE_STAGE_BOTTOM_OF_PIPE_BIT;
  deps[1].dstAccessMask = VK_ACCESS_TRANSFER_READ_BIT;
  VkRenderPassCreateInfo rpi{VK_STRUCTURE_TYPE_RENDER_PASS_CREATE_INFO};
  rpi.attachmentCount = 1;
  rpi.pAttachments = &color;
  rpi.subpassCount = 1;
  rpi.pSubpasses = &sub;
  rpi.dependencyCount = 2;
  rpi.pDependencies = deps;
  VkRenderPass pass = VK_NULL_HANDLE;
  VXR_VK_TRY(vkCreateRenderPass(ctx.device(), &rpi, nullptr, &pass));
  l->pass_ = gpu::Handle<VkRenderPass>(ctx.device(), pass);

  const uint32_t count = uint32_t(std::max<size_t>(2, images.size()));
  ImGui_ImplVulkan_InitInfo info{};
  info.Instance = ctx.instance();
  info.PhysicalDevice = ctx.physical_device();
  info.Device = ctx.device();
  info.QueueFamily = ctx.queue_family();
  info.Queue = ctx.queue();
  info.PipelineCache = ctx.pipeline_cache();
  info.DescriptorPool = pool;
  info.Subpass = 0;
  info.MinImageCount = count;
  info.ImageCount = count;
  info.MSAASamples = VK_SAMPLE_COUNT_1_BIT;
  info.CheckVkResultFn = on_backend_result;
  g_backend_result = VK_SUCCESS;
  if (!ImGui_ImplVulkan_Init(&info, pass)) return internal_error("ImGui's Vulkan backend did not start");
  l->vulkan_ready_ = true;
  VXR_RETURN_IF_ERROR(ctx.submit_and_wait([](VkCommandBuffer cmd) { ImGui_ImplVulkan_CreateFontsTexture(cmd); }));
  ImGui_ImplVulkan_DestroyFontUploadObjects();
  if (g_backend_result != VK_SUCCESS)
    return gpu_error(std::string("ImGui's Vulkan backend failed: ") + gpu::vk_result_name(g_backend_result));
  VXR_RETURN_IF_ERROR(l->set_images(images, extent));
  return l;
}

ImGuiLayer::~ImGuiLayer() {
  vkDeviceWaitIdle(ctx_.device());
  destroy_framebuffers();
  if (vulkan_ready_) ImGui_ImplVulkan_Shutdown();
  if (glfw_ready_) ImGui_ImplGlfw_Shutdown();
  if (ImGui::GetCurrentContext()) ImGui::DestroyContext();
}

void ImGuiLayer::destroy_framebuffers() {
  for (VkFramebuffer f : framebuffers_) vkDestroyFramebuffer(ctx_.device(), f, nullptr);
  for (VkImageView v : views_) vkDestroyImageView(ctx_.device(), v, nullptr);
  framebuffers_.clear();
  views_.clear();
}

Status ImGuiLayer::set_images(const std::vector<VkImage>& images, VkExtent2D extent) {
  destroy_framebuffers();
  extent_ = extent;
  for (VkImage image : images) {
    VkImageViewCreateInfo vi{VK_STRUCTURE_TYPE_IMAGE_VIEW_CREATE_INFO};
    vi.image = image;
    vi.viewType = VK_IMAGE_VIEW_TYPE_2D;
    vi.format = format_;
    vi.subresourceRange = {VK_IMAGE_ASPECT_COLOR_BIT, 0, 1, 0, 1};
    VkImageView view = VK_NULL_HANDLE;
    VXR_VK_TRY(vkCreateImageView(ctx_.device(), &vi, nullptr, &view));
    views_.push_back(view);
    VkFramebufferCreateInfo fi{VK_STRUCTURE_TYPE_FRAMEBUFFER_CREATE_INFO};
    fi.renderPass = pass_;
    fi.attachmentCount = 1;
    fi.pAttachments = &view;
    fi.width = extent.width;
    fi.height = extent.height;
    fi.layers = 1;
    VkFramebuffer fb = VK_NULL_HANDLE;
    VXR_VK_TRY(vkCreateFramebuffer(ctx_.device(), &fi, nullptr, &fb));
    framebuffers_.push_back(fb);
  }
  return Status::ok();
}

void ImGuiLayer::begin() {
  ImGui_ImplVulkan_NewFrame();
  ImGui_ImplGlfw_NewFrame();
  ImGui::NewFrame();
}

void ImGuiLayer::end() { ImGui::Render(); }

void ImGuiLayer::record(VkCommandBuffer cmd, uint32_t index) {
  VkRenderPassBeginInfo bi{VK_STRUCTURE_TYPE_RENDER_PASS_BEGIN_INFO};
  bi.renderPass = pass_;
  bi.framebuffer = framebuffers_.at(index);
  bi.renderArea = {{0, 0}, extent_};
  vkCmdBeginRenderPass(cmd, &bi, VK_SUBPASS_CONTENTS_INLINE);
  ImGui_ImplVulkan_RenderDrawData(ImGui::GetDrawData(), cmd);
  vkCmdEndRenderPass(cmd);
}

bool ImGuiLayer::wants_mouse() { return ImGui::GetCurrentContext() && ImGui::GetIO().WantCaptureMouse; }
bool ImGuiLayer::wants_keyboard() { return ImGui::GetCurrentContext() && ImGui::GetIO().WantCaptureKeyboard; }

}  // namespace vxr::xr
