// The desktop viewer's UI state as a device-independent model: every edit the
// ImGui panels, the keyboard or a test script can make goes through here and
// lands in the Scene / RenderSettings the renderer already takes. No ImGui,
// GLFW or Vulkan in it, so the logic is unit-tested on its own.
#pragma once

#include <array>
#include <cstdint>
#include <string>
#include <vector>

#include "core/status.h"
#include "scene/render_settings.h"
#include "volume/playback.h"

namespace vxr::xr {

// Orbit camera about a focus point in the volume's frame (world units, volume
// centred at 0). yaw about +y, pitch about the camera's right axis.
struct OrbitCamera {
  std::array<double, 3> focus{0, 0, 0};
  double yaw = 0.0;        // radians
  double pitch = 0.0;      // radians, kept inside (-pi/2, pi/2)
  double distance = 2.0;   // focus to eye
  double fov_y_deg = 40.0;
  bool operator==(const OrbitCamera&) const = default;
  CameraState camera() const;
};
// The orbit whose camera() is `c` scaled by 1 / `unit` (a card's camera in
// world units back to the viewer's orbit, in units of the volume's longest side).
OrbitCamera orbit_for_camera(const CameraState& c, double unit);

// Keys the viewer reacts to, independent of the window system.
enum class ViewerKey { kResetView, kAxisX, kAxisY, kAxisZ, kNextModel, kNextColormap, kTimeNext, kTimePrev,
                       kPlayPause, kStepBack, kStepForward, kSlower, kFaster, kToggleHelp, kToggleUi, kQuit,
                       kFinishTool };  // ends the trace chain or the track (the window's tools act on it)

struct ShortcutHelp {
  const char* keys;
  const char* action;
};
// The shortcut table the help panel lists (one source for help and handling).
const std::vector<ShortcutHelp>& viewer_shortcuts();

class ViewerState {
 public:
  // `settings` as the viewer starts; `timepoints` >= 1; `data_range` the
  // value range of the data (windows are clamped to nothing, but the panel's
  // slider spans it).
  ViewerState(Scene scene, uint32_t timepoints, std::array<double, 2> data_range);

  const Scene& scene() const { return scene_; }
  const RenderSettings& render() const { return scene_.render; }
  // Bumped on every effective change: the frame loop re-uploads settings only then.
  uint64_t revision() const { return revision_; }
  uint32_t timepoints() const { return timepoints_; }
  std::array<double, 2> data_range() const { return data_range_; }
  size_t channel_count() const { return scene_.render.channels.size(); }

  Status set_channel_visible(size_t channel, bool visible);
  Status set_colormap(size_t channel, const std::string& name);
  Status cycle_colormap(size_t channel, int direction);
  Status set_window(size_t channel, double lo, double hi);
  // Window as centre (level) and width.
  Status set_window_level(size_t channel, double level, double width);
  Status set_gamma(size_t channel, double gamma);
  void set_model(OpticalModel model);
  void cycle_model(int direction);
  Status set_step(double step_voxels);
  Status set_density(double density);
  // Shows timepoint t (pauses playback).
  Status set_timepoint(uint32_t t);

  // Timepoint playback through the PlaybackClock of `vxr play`
  // (volume/playback.h): the window passes its frame times to tick(); keys,
  // commands and the panel act at the latest of them.
  // `ready(t)`: timepoint t's data is loaded (else the clock waits on the current one).
  void tick(double now_s, const std::function<bool(uint32_t)>& ready = [](uint32_t) { return true; });
  const PlaybackClock& playback() const { return clock_; }
  void play();
  void pause();
  // By `delta` timepoints, paused (wraps when looping).
  void step_time(int delta);
  Status set_speed(double speed);  // 1/16 .. 16
  void set_loop(bool loop) { clock_.set_loop(loop); }

  // Navigation: drags in pixels of a view `view_height` pixels tall.
  const OrbitCamera& orbit() const { return orbit_; }
  void orbit_drag(double dx_px, double dy_px);
  void pan_drag(double dx_px, double dy_px, double view_height_px);
  void zoom(double wheel_ticks);
  void reset_view();
  // Looks along -x, -y or -z (axis 0, 1, 2) at the whole volume.
  Status axis_view(int axis);
  CameraState camera() const { return orbit_.camera(); }

  // Back to what a card saved: its settings (same channel count), timepoint
  // and the orbit that shows its camera. Nothing changes when it is refused.
  Status restore(const RenderSettings& render, uint32_t timepoint, const OrbitCamera& orbit);

  // Keys edit the state; quit and the help/UI toggles are only recorded here
  // (the window acts on them).
  void handle_key(ViewerKey key);
  bool help_visible() const { return help_visible_; }
  bool ui_visible() const { return ui_visible_; }
  bool quit_requested() const { return quit_requested_; }

  // One script/console command, e.g. "colormap 0 viridis", "window 0 10 200",
  // "model mip", "step 0.25", "time 2", "visible 1 off", "orbit 40 0",
  // "zoom 2", "reset", "view 3", "play", "pause", "speed 2", "loop on". Errors name the command.
  Status apply_command(const std::string& line);

 private:
  Status check_channel(size_t channel) const;
  void changed() { ++revision_; }

  Scene scene_;
  uint32_t timepoints_;
  std::array<double, 2> data_range_;
  OrbitCamera orbit_;
  OrbitCamera home_;
  uint64_t revision_ = 0;
  bool help_visible_ = false;
  bool ui_visible_ = true;
  bool quit_requested_ = false;
  PlaybackClock clock_;
  double now_s_ = 0.0;  // the latest tick
};

// The window size the viewer remembers between runs: a small JSON under
// $XDG_CONFIG_HOME/vxr/ (else ~/.config/vxr/). Missing or unreadable files give
// the default; a malformed one is reported and the default used.
struct WindowGeometry {
  uint32_t width = 1280, height = 800;
  bool operator==(const WindowGeometry&) const = default;
};
std::string viewer_config_path();
Result<WindowGeometry> load_window_geometry(const std::string& path);
Status save_window_geometry(const std::string& path, const WindowGeometry& g);

}  // namespace vxr::xr
