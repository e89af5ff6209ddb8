// A desktop window (GLFW + a Vulkan swapchain) as a FrameTarget.
//
// Stands alone with mouse/keyboard navigation: left-drag orbits about the
// volume, the scroll wheel zooms, W/A/S/D fly, Q/E go down/up, Esc closes.
// --stereo shows both eyes side by side (the paper's on-monitor side-by-side
// picture). The eye images are ordinary device images; end_frame blits them
// into the window's swapchain image and presents.
//
// With a ViewerSetup the window is the viewer: Dear ImGui panels over a
// ViewerState (xr/desktop/viewer_state.h) that says what the renderer draws
// each frame, the orbit camera from the mouse, keys through the key callback,
// the title "vxr - DATASET - N ms", the store's markers, measurements,
// skeletons, tracks and boxes drawn over each view (both eyes in stereo, where
// clicks pick through the eye clicked), movie export along camera keyframes,
// and an optional UI script. The eyes are then blitted and
// the panels drawn into the swapchain image in the frame's own command buffer
// (record_after_views), and only a screenshot reads anything back.
#pragma once

#include <array>
#include <chrono>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "core/output_file.h"
#include "gpu/resources.h"
#include "scene/render_settings.h"
#include "volume/playback.h"
#include "xr/desktop/viewer_pick.h"
#include "xr/frame_target.h"

struct GLFWwindow;

namespace vxr::xr {

struct ViewerSetup;  // xr/desktop/viewer_setup.h
class ViewerState;
class ImGuiLayer;
class UiScriptRunner;
class ViewerTools;
struct ToolPanel;
struct MoviePanel;
struct OpenPanel;
class MovieExport;
struct MovieRequest;
enum class AnnotationKind;

// A marker or line end in voxels, with its colour (the overlay draws it).
struct OverlayPoint {
  std::array<double, 3> voxel;
  std::array<double, 4> color;
};
// What the overlay draws of the store, read again after each edit.
struct OverlayContent {
  std::vector<std::pair<OverlayPoint, uint32_t>> markers;  // with their timepoint (others: a ring)
  std::vector<std::array<OverlayPoint, 2>> lines;          // measurements, skeleton edges, track steps
  std::vector<OverlayPoint> nodes;                         // skeleton nodes
  std::vector<std::array<std::array<double, 3>, 2>> boxes; // ROI min, max
};

struct DesktopOptions {
  uint32_t width = 256, height = 256;  // per eye
  Fov fov;                              // vertical from up/down; horizontal follows the aspect
  bool stereo = false;
  double ipd_m = 0.064;
  uint64_t end_frame = 0;               // close after this many frames; 0: when the window is closed
  std::string screenshot_path;          // at exit, grab the window from the X server into this PNG
  // Prefer an sRGB window swapchain (UNORM where the window has none): the
  // eyes are then sRGB images the renderer writes linear values into, as on
  // an sRGB headset swapchain, and a mirror's blit copies the encoded bytes
  // unchanged (decode + encode).
  bool srgb_swapchain = true;
  std::shared_ptr<const ViewerSetup> viewer;  // null: the bare window (no panels)
};

// Why there is no usable window system (no DISPLAY, GLFW or Vulkan surface
// support missing), or ok.
Status desktop_available();

class DesktopTarget : public FrameTarget {
 public:
  static Result<std::unique_ptr<DesktopTarget>> create(const DesktopOptions& options);
  ~DesktopTarget() override;

  std::string describe() const override;
  Status prepare_context(gpu::ContextOptions& options) override;
  Status attach(gpu::Context& ctx) override;
  Result<FrameState> wait_frame() override;
  Result<TargetImage> acquire(size_t view) override;
  Status record_after_views(VkCommandBuffer cmd, FrameSubmit& submit) override;
  Status end_frame(const FrameState& frame, const FrameContent& content) override;
  void request_exit() override { exit_requested_ = true; }
  void detach() override;
  void use_chunk_cache(ChunkCache* cache, const ChunkSource* source) override;

  // Mouse and keyboard navigation (called from GLFW callbacks).
  void on_drag(double dx, double dy);
  void on_scroll(double dy);

  // Mirror use (MirrorTarget): blit `sources` (images on the same device, in
  // their stated layouts, left to right) into the window and present.
  Status present(const std::vector<TargetImage>& sources);
  // Polls window events; false once the user closed the window.
  bool poll();
  // Grabs what the X server shows in the window into options.screenshot_path.
  Status screenshot();

 private:
  explicit DesktopTarget(const DesktopOptions& o);
  Status create_swapchain();
  void destroy_swapchain();
  Status recreate_swapchain();
  Status create_eyes();
  Status follow_window_size();
  Pose head_pose() const;
  // The viewer's frame: script steps, panels, overlay, settings and views.
  Status viewer_frame(FrameState& f);
  // The UI script's steps due this frame; `card`, `restore`: its panel buttons.
  Status script_frame(FrameState& f, bool* card, std::optional<uint64_t>* restore);
  Status record_movie_copy(VkCommandBuffer cmd);
  // The views the window shows now (mono, or both eyes), from the viewer's camera.
  std::vector<WindowView> viewer_window_views() const;
  Fov viewer_fov() const;
  void read_overlay();
  void draw_annotation_overlay(const std::vector<WindowView>& views);
  void draw_overlay_view(const WindowView& view);
  Status write_screenshot();
  void on_viewer_cursor(double dx, double dy);
  // A left click at window pixel (x, y): the tools panel's tool places there.
  void on_viewer_click(double x, double y);
  // The ROI tool's drag: press, move, release at window pixel (x, y).
  void on_roi_drag(int action, double x, double y);
  // The voxel under window pixel (x, y) on the plane through the orbit centre facing the view clicked.
  std::optional<std::array<double, 3>> voxel_under(double x, double y) const;
  std::optional<std::array<double, 3>> traced_node_under(double x, double y) const;
  void finish_tool();
  void remove_annotation(AnnotationKind kind, uint64_t id);
  void add_keyframe();
  Status start_movie_export(const MovieRequest& request);
  Status write_movie_frame();
  Scene card_scene() const;
  // The remembered view of this dataset (ViewerSetup::view_memory): shown at start, written at close.
  void restore_remembered_view();
  void remember_view();
  Status save_panel_card(const std::string& png_path);
  Status restore_card(uint64_t id);

  DesktopOptions o_;
  GLFWwindow* window_ = nullptr;
  gpu::Context* ctx_ = nullptr;
  VkSurfaceKHR surface_ = VK_NULL_HANDLE;
  VkSwapchainKHR swapchain_ = VK_NULL_HANDLE;
  VkFormat swap_format_ = VK_FORMAT_UNDEFINED;
  VkExtent2D swap_extent_{0, 0};
  std::vector<VkImage> swap_images_;
  std::vector<gpu::Handle<VkSemaphore>> render_done_;  // one per swapchain image
  gpu::Handle<VkSemaphore> acquired_;
  gpu::Handle<VkFence> fence_;
  gpu::Handle<VkCommandPool> pool_;
  std::vector<gpu::Image> eyes_;
  uint64_t frame_ = 0;
  bool exit_requested_ = false;
  // Navigation: orbit about `focus_` at `distance_`, yaw/pitch in radians.
  glm::dvec3 focus_{0.0, 1.6, -0.5};
  double yaw_ = 0.0, pitch_ = 0.0, distance_ = 0.5;
  bool have_focus_ = false;

  // The viewer (o_.viewer set).
  std::unique_ptr<ViewerState> state_;
  std::unique_ptr<ImGuiLayer> ui_;
  std::unique_ptr<UiScriptRunner> script_;
  std::shared_ptr<const RenderSettings> drawn_settings_;  // handed to the frame loop; new when the state changed
  uint64_t drawn_revision_ = UINT64_MAX;
  bool nothing_visible_ = false;
  bool resized_ = false;       // the framebuffer size changed since the last frame
  bool user_resized_ = false;  // ... at least once: remember the size at exit  // every channel hidden: the window is cleared, no rays cast
  std::chrono::steady_clock::time_point last_frame_start_{};
  double frame_ms_ = 0.0;
  // This frame's swapchain image (acquired in record_after_views).
  bool image_acquired_ = false;
  uint32_t image_index_ = 0;
  // Screenshot of this frame's swapchain image: a host buffer the frame copies into.
  std::string screenshot_pending_;
  gpu::Buffer screenshot_buffer_;
  // The store's annotations as the overlay draws them, read again after each edit.
  uint64_t overlay_revision_ = UINT64_MAX;
  OverlayContent overlay_;
  std::unique_ptr<ViewerTools> tools_;  // with a store
  std::unique_ptr<ToolPanel> panel_;
  double press_x_ = 0, press_y_ = 0;
  bool press_on_ui_ = false;
  std::string card_shot_;  // the panel asked for a card: this frame's picture goes here first
  std::unique_ptr<TempFile> card_temp_;  // that picture when no script screenshot was due
  std::string click_error_;              // the last click's refusal (a script stops on it)
  bool roi_dragging_ = false;            // the ROI tool's box follows the cursor
  size_t roi_view_ = 0;                  // ... in this view
  int roi_axis_ = 2;                     // ... through the volume along this axis
  // Movie export: keyframes (head poses), the export running, its frame read back from eye 0.
  std::unique_ptr<MoviePanel> movie_panel_;
  std::unique_ptr<OpenPanel> open_panel_;
  // Asks the caller to open `path` next (ViewerSetup::open_request) and closes the window.
  void request_open(const std::string& path);
  std::vector<Pose> keyframes_;
  std::unique_ptr<MovieExport> export_;
  bool export_from_script_ = false;
  bool movie_frame_pending_ = false;
  bool movie_copied_ = false;  // this frame's eye 0 went into movie_buffer_
  gpu::Buffer movie_buffer_;
  uint32_t drawn_timepoint_ = 0;          // the frame's (a screenshot's log line names it)
  std::vector<TimepointPrefetcher> prefetch_;  // playback: one per channel of the view, into run_view's cache
};

}  // namespace vxr::xr
