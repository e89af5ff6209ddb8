// The desktop viewer's UI state as a device-independent model: every edit the
// ImGui panels, the keyboard or a test script can make goes through here and
// lands in the Scene / RenderSettings the renderer already takes. No ImGui,
// GLFW or Vulkan in it, so the logic is unit-tested on its own.
#pragma once

#include <array>
#include <cstdint>
#include <optional>
#include <functional>
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

// Fly directions held down (W/S, D/A, E/Q): -1, 0 or 1 along the view, to the
// right and up; the window polls them each frame (viewer_keys.h).
struct FlyInput {
  double forward = 0, right = 0, up = 0;
  bool any() const { return forward != 0 || right != 0 || up != 0; }
};

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

  // The opacity curve over the window (ChannelSettings::opacity_points:
  // piecewise linear, x rising in 0..1, opacity 0..1). Empty: opacity equals
  // the windowed value, the ramp (0,0)-(1,1) every edit below starts from.
  Status set_opacity_points(size_t channel, std::vector<OpacityPoint> points);
  // The channel's curve as points (the ramp's two when it has none).
  std::vector<OpacityPoint> opacity_curve(size_t channel) const;
  // Adds a point (kept in x order); returns its index.
  Result<size_t> add_opacity_point(size_t channel, double x, double opacity);
  // Moves point `index` to (x, opacity); x stays between its neighbours' x.
  Status move_opacity_point(size_t channel, size_t index, double x, double opacity);
  // Removes point `index`; a curve keeps at least two.
  Status remove_opacity_point(size_t channel, size_t index);

  // Clipping (RenderSettings::clip, volume fractions 0..1 per axis).
  // A cut plane along axis 0/1/2 at `position`: `keep_above` keeps the side
  // the axis points to (coordinate >= position), else the other side.
  Status set_cut_axis(int axis, bool keep_above, double position);
  // Any plane: keeps the points f with dot(n, f) / |n| + offset >= 0.
  Status set_cut_plane(std::array<double, 3> normal, double offset);
  void set_cut_enabled(bool on);
  // The box kept, lo < hi within 0..1 per axis.
  Status set_roi(std::array<double, 3> lo, std::array<double, 3> hi);
  void set_roi_enabled(bool on);
  void set_model(OpticalModel model);
  void cycle_model(int direction);
  Status set_step(double step_voxels);
  Status set_density(double density);
  // The isosurface's value (RenderSettings::iso_value, data units of the iso channel).
  Status set_iso_value(double value);
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
  // Flies the orbit centre (and with it the eye) by `amount` orbit units
  // (the volume's longest side is 1) along the view, its right and its up.
  void fly(const FlyInput& direction, double amount);
  // Held keys over `seconds`: half the orbit distance per second, so the
  // speed follows the zoom.
  void fly_for(const FlyInput& held, double seconds);
  void reset_view();
  // Looks along -x, -y or -z (axis 0, 1, 2) at the whole volume.
  Status axis_view(int axis);
  CameraState camera() const { return orbit_.camera(); }

  // Progressive refinement: the window calls note_motion() when the user
  // moves the view (drag, wheel, fly keys); while moving() the window draws
  // at a coarser level of detail, and at full detail once the view has been
  // still for kStillFrames ticks and kStillSeconds. Script commands do not
  // count: a scripted picture is always at full detail.
  static constexpr uint64_t kStillFrames = 2;
  static constexpr double kStillSeconds = 0.2;
  void note_motion();
  bool moving() const;

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
  // "zoom 2", "reset", "view 3", "play", "pause", "speed 2", "loop on",
  // "opacity 0 0:0,0.5:0.2,1:1", "opacity 0 ramp", "cut z 0.5", "cut -x 0.3",
  // "cut 1 1 0 -0.8", "cut off", "clip 0.1 0.1 0 0.9 0.9 1", "clip off",
  // "fly 0.1 0 0". Errors name the command.
  Status apply_command(const std::string& line);

 private:
  Status check_channel(size_t channel) const;
  Status apply_clip_command(const std::vector<std::string>& w, const std::string& line);
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
  uint64_t ticks_ = 0;
  bool moved_ = false;  // note_motion() was called at least once
  uint64_t motion_tick_ = 0;
  double motion_s_ = 0.0;
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

// The view the viewer remembers per dataset: its Scene (camera, transfer
// functions, model, step, channels, clipping, timepoint) written when the
// window closes, shown again the next time the same input opens.
// A project (NAME.vxr/, or a file inside one): NAME.vxr/viewer.json; any other
// input: views/<FNV-1a of the input as given>.json beside the window size's
// file. Empty when there is no config folder.
std::string remembered_view_path(const std::string& input);
// Written atomically (a crash leaves the old file or the new one).
Status save_remembered_view(const std::string& path, const Scene& scene);
// nullopt when there is none yet; a file that is not a Scene is an error naming it.
Result<std::optional<Scene>> load_remembered_view(const std::string& path);

}  // namespace vxr::xr
