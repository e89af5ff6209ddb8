#include "xr/desktop/viewer_state.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <optional>
#include <sstream>

#include "core/output_file.h"
#include "render/colormap.h"

namespace vxr::xr {
namespace {

constexpr double kPi = 3.14159265358979323846;
constexpr double kMaxPitch = kPi / 2 - 1e-3;
constexpr double kRadiansPerPixel = 0.01;
constexpr double kZoomPerTick = 0.9;  // distance factor per wheel notch toward the focus

constexpr OpticalModel kModels[] = {OpticalModel::kEmissionAbsorption, OpticalModel::kEmission, OpticalModel::kMip,
                                    OpticalModel::kMinIp, OpticalModel::kAverage, OpticalModel::kIsosurface};

bool parse_double(const std::string& s, double* out) {
  char* end = nullptr;
  *out = std::strtod(s.c_str(), &end);
  return !s.empty() && end == s.c_str() + s.size() && std::isfinite(*out);
}
bool parse_index(const std::string& s, size_t* out) {
  if (s.empty() || s.find_first_not_of("0123456789") != std::string::npos || s.size() > 9) return false;
  *out = std::stoul(s);
  return true;
}

}  // namespace

CameraState OrbitCamera::camera() const {
  // Eye on a sphere about the focus; yaw 0, pitch 0 looks along -z.
  const double cp = std::cos(pitch), sp = std::sin(pitch), cy = std::cos(yaw), sy = std::sin(yaw);
  const std::array<double, 3> back{sy * cp, sp, cy * cp};  // focus -> eye
  CameraState c;
  for (int i = 0; i < 3; ++i) {
    c.eye[i] = focus[i] + distance * back[i];
    c.target[i] = focus[i];
  }
  c.up = {-sy * sp, cp, -cy * sp};  // d(back)/d(pitch): orthogonal to the view direction
  c.fov_y_deg = fov_y_deg;
  return c;
}

OrbitCamera orbit_for_camera(const CameraState& c, double unit) {
  OrbitCamera o;
  std::array<double, 3> back;
  for (int i = 0; i < 3; ++i) {
    o.focus[i] = c.target[i] / unit;
    back[i] = (c.eye[i] - c.target[i]) / unit;
  }
  o.distance = std::sqrt(back[0] * back[0] + back[1] * back[1] + back[2] * back[2]);
  if (o.distance > 0) {
    o.pitch = std::asin(std::clamp(back[1] / o.distance, -1.0, 1.0));
    o.yaw = std::atan2(back[0], back[2]);
  }
  o.fov_y_deg = c.fov_y_deg;
  return o;
}

const std::vector<ShortcutHelp>& viewer_shortcuts() {
  static const std::vector<ShortcutHelp> table = {
      {"Left drag", "orbit"},           {"Right / middle drag", "pan"},
      {"Wheel", "zoom"},                {"W / S", "fly forward / back (the orbit centre travels along the view)"},
      {"A / D", "fly left / right"},    {"Q / E", "fly down / up"},
      {"R", "reset view"},
      {"1 / 2 / 3", "view along x / y / z"}, {"M", "next optical model"},
      {"C", "next colour map (channel 0)"},  {"Left / Right", "previous / next timepoint"},
      {"Space", "play / pause the timepoints"}, {", / .", "step one timepoint back / on (pauses)"},
      {"[ / ]", "play slower / faster"},
      {"H or F1", "show / hide this help"},  {"Tab", "show / hide the panels"},
      {"Enter", "finish: end the traced branch or the track"},
      {"Esc", "quit"},
  };
  return table;
}

ViewerState::ViewerState(Scene scene, uint32_t timepoints, std::array<double, 2> data_range)
    : scene_(std::move(scene)), timepoints_(std::max<uint32_t>(timepoints, 1)), data_range_(data_range),
      clock_(timepoints_) {
  if (scene_.render.channels.empty()) scene_.render.channels.emplace_back();
  if (!(data_range_[1] > data_range_[0])) data_range_ = {data_range_[0], data_range_[0] + 1.0};
  // The whole volume (longest side 1 in world units) fits the view.
  home_.fov_y_deg = scene_.has_camera ? scene_.camera.fov_y_deg : home_.fov_y_deg;
  home_.distance = 0.75 / std::tan(home_.fov_y_deg * kPi / 360.0);
  orbit_ = home_;
  scene_.timepoint = std::min(scene_.timepoint, timepoints_ - 1);
  clock_.step(int(scene_.timepoint), 0.0);
}

Status ViewerState::check_channel(size_t channel) const {
  if (channel >= scene_.render.channels.size())
    return out_of_range("channel " + std::to_string(channel) + " does not exist (" +
                        std::to_string(scene_.render.channels.size()) + " channels)");
  return Status::ok();
}

Status ViewerState::set_channel_visible(size_t channel, bool visible) {
  VXR_RETURN_IF_ERROR(check_channel(channel));
  auto& ch = scene_.render.channels[channel];
  if (ch.enabled != visible) {
    ch.enabled = visible;
    changed();
  }
  return Status::ok();
}

Status ViewerState::set_colormap(size_t channel, const std::string& name) {
  VXR_RETURN_IF_ERROR(check_channel(channel));
  if (!find_colormap(name)) return invalid_argument("unknown colour map '" + name + "'");
  auto& ch = scene_.render.channels[channel];
  // Explicit colour points override the map; choosing a map drops them.
  if (ch.colormap != name || !ch.color_points.empty()) {
    ch.colormap = name;
    ch.color_points.clear();
    changed();
  }
  return Status::ok();
}

Status ViewerState::cycle_colormap(size_t channel, int direction) {
  VXR_RETURN_IF_ERROR(check_channel(channel));
  const std::vector<std::string> names = colormap_names();
  if (names.empty()) return internal_error("no colour maps");
  auto it = std::find(names.begin(), names.end(), scene_.render.channels[channel].colormap);
  const long n = static_cast<long>(names.size());
  const long at = it == names.end() ? -1 : static_cast<long>(it - names.begin());
  const long next = ((at + (direction >= 0 ? 1 : -1)) % n + n) % n;
  return set_colormap(channel, names[static_cast<size_t>(next)]);
}

Status ViewerState::set_window(size_t channel, double lo, double hi) {
  VXR_RETURN_IF_ERROR(check_channel(channel));
  if (!std::isfinite(lo) || !std::isfinite(hi) || !(hi > lo))
    return invalid_argument("window needs lo < hi (got " + std::to_string(lo) + ", " + std::to_string(hi) + ")");
  auto& ch = scene_.render.channels[channel];
  if (ch.window_lo != lo || ch.window_hi != hi) {
    ch.window_lo = lo;
    ch.window_hi = hi;
    changed();
  }
  return Status::ok();
}

Status ViewerState::set_window_level(size_t channel, double level, double width) {
  if (!(width > 0)) return invalid_argument("window width must be > 0");
  return set_window(channel, level - width / 2, level + width / 2);
}

Status ViewerState::set_gamma(size_t channel, double gamma) {
  VXR_RETURN_IF_ERROR(check_channel(channel));
  if (!(gamma > 0) || !std::isfinite(gamma)) return invalid_argument("gamma must be > 0");
  auto& ch = scene_.render.channels[channel];
  if (ch.gamma != gamma) {
    ch.gamma = gamma;
    changed();
  }
  return Status::ok();
}

namespace {

Status check_opacity_points(const std::vector<OpacityPoint>& points) {
  double last = -1.0;
  for (const OpacityPoint& p : points) {
    if (!(p.x >= 0.0 && p.x <= 1.0) || p.x < last)
      return invalid_argument("opacity points need x rising within 0..1 (got " + std::to_string(p.x) + ")");
    if (!(p.opacity >= 0.0 && p.opacity <= 1.0))
      return invalid_argument("opacity must be in 0..1 (got " + std::to_string(p.opacity) + ")");
    last = p.x;
  }
  return Status::ok();
}

// "0:0,0.5:0.2,1:1" -> points; nullopt when malformed.
std::optional<std::vector<OpacityPoint>> parse_opacity_points(const std::string& text) {
  std::vector<OpacityPoint> points;
  std::istringstream in(text);
  for (std::string pair; std::getline(in, pair, ',');) {
    const size_t colon = pair.find(':');
    OpacityPoint p;
    if (colon == std::string::npos || !parse_double(pair.substr(0, colon), &p.x) ||
        !parse_double(pair.substr(colon + 1), &p.opacity))
      return std::nullopt;
    points.push_back(p);
  }
  if (points.empty()) return std::nullopt;
  return points;
}

}  // namespace

Status ViewerState::set_opacity_points(size_t channel, std::vector<OpacityPoint> points) {
  VXR_RETURN_IF_ERROR(check_channel(channel));
  VXR_RETURN_IF_ERROR(check_opacity_points(points));
  auto& ch = scene_.render.channels[channel];
  if (ch.opacity_points != points) {
    ch.opacity_points = std::move(points);
    changed();
  }
  return Status::ok();
}

std::vector<OpacityPoint> ViewerState::opacity_curve(size_t channel) const {
  if (channel >= scene_.render.channels.size()) return {};
  const auto& points = scene_.render.channels[channel].opacity_points;
  // No points: opacity equals the windowed value (transfer_function.cpp), the ramp.
  return points.empty() ? std::vector<OpacityPoint>{{0.0, 0.0}, {1.0, 1.0}} : points;
}

Result<size_t> ViewerState::add_opacity_point(size_t channel, double x, double opacity) {
  VXR_RETURN_IF_ERROR(check_channel(channel));
  std::vector<OpacityPoint> points = opacity_curve(channel);
  const auto at = std::upper_bound(points.begin(), points.end(), x,
                                   [](double v, const OpacityPoint& p) { return v < p.x; });
  const size_t index = size_t(at - points.begin());
  points.insert(at, OpacityPoint{x, opacity});
  VXR_RETURN_IF_ERROR(set_opacity_points(channel, std::move(points)));
  return index;
}

Status ViewerState::move_opacity_point(size_t channel, size_t index, double x, double opacity) {
  VXR_RETURN_IF_ERROR(check_channel(channel));
  std::vector<OpacityPoint> points = opacity_curve(channel);
  if (index >= points.size())
    return out_of_range("opacity point " + std::to_string(index) + " does not exist (" +
                        std::to_string(points.size()) + " points)");
  // A dragged point stops at its neighbours: the order, and so the indices, stay.
  const double lo = index > 0 ? points[index - 1].x : 0.0;
  const double hi = index + 1 < points.size() ? points[index + 1].x : 1.0;
  points[index] = {std::clamp(x, lo, hi), std::clamp(opacity, 0.0, 1.0)};
  return set_opacity_points(channel, std::move(points));
}

Status ViewerState::remove_opacity_point(size_t channel, size_t index) {
  VXR_RETURN_IF_ERROR(check_channel(channel));
  std::vector<OpacityPoint> points = opacity_curve(channel);
  if (index >= points.size())
    return out_of_range("opacity point " + std::to_string(index) + " does not exist (" +
                        std::to_string(points.size()) + " points)");
  if (points.size() <= 2) return invalid_argument("an opacity curve keeps at least two points");
  points.erase(points.begin() + std::ptrdiff_t(index));
  return set_opacity_points(channel, std::move(points));
}

Status ViewerState::set_cut_axis(int axis, bool keep_above, double position) {
  if (axis < 0 || axis > 2) return invalid_argument("cut axis must be x, y or z");
  if (!(position >= 0.0 && position <= 1.0)) return out_of_range("cut position must be in 0..1");
  std::array<double, 3> n{0, 0, 0};
  n[size_t(axis)] = keep_above ? 1.0 : -1.0;
  // Keeps n * f + offset >= 0: f >= position above, f <= position below.
  return set_cut_plane(n, keep_above ? -position : position);
}

Status ViewerState::set_cut_plane(std::array<double, 3> normal, double offset) {
  const double len = std::sqrt(normal[0] * normal[0] + normal[1] * normal[1] + normal[2] * normal[2]);
  if (!(len > 0) || !std::isfinite(len) || !std::isfinite(offset))
    return invalid_argument("a cut plane needs a non-zero normal and a finite offset");
  ClipSettings& c = scene_.render.clip;
  for (double& v : normal) v /= len;
  if (!c.cut || c.cut_normal != normal || c.cut_offset != offset) {
    c.cut = true;
    c.cut_normal = normal;
    c.cut_offset = offset;
    changed();
  }
  return Status::ok();
}

void ViewerState::set_cut_enabled(bool on) {
  if (scene_.render.clip.cut != on) {
    scene_.render.clip.cut = on;
    changed();
  }
}

Status ViewerState::set_roi(std::array<double, 3> lo, std::array<double, 3> hi) {
  for (int a = 0; a < 3; ++a)
    if (!(lo[a] >= 0.0 && hi[a] <= 1.0 && lo[a] < hi[a]))
      return invalid_argument("the clip box needs 0 <= lo < hi <= 1 along each axis");
  ClipSettings& c = scene_.render.clip;
  if (!c.roi || c.roi_lo != lo || c.roi_hi != hi) {
    c.roi = true;
    c.roi_lo = lo;
    c.roi_hi = hi;
    changed();
  }
  return Status::ok();
}

void ViewerState::set_roi_enabled(bool on) {
  if (scene_.render.clip.roi != on) {
    scene_.render.clip.roi = on;
    changed();
  }
}

// "cut off|on", "cut x|y|z|-x|-y|-z POS", "cut NX NY NZ OFFSET", "clip off|on", "clip X0 Y0 Z0 X1 Y1 Z1".
Status ViewerState::apply_clip_command(const std::vector<std::string>& w, const std::string& line) {
  auto bad = [&](const std::string& why) { return invalid_argument("'" + line + "': " + why); };
  auto wrap = [&](Status s) { return s.is_ok() ? s : bad(s.message()); };
  std::vector<double> v;
  for (size_t i = 1; i < w.size(); ++i) {
    double d = 0;
    if (!parse_double(w[i], &d)) break;
    v.push_back(d);
  }
  if (w[0] == "cut") {
    const char* usage = "usage: cut off|on, cut x|y|z|-x|-y|-z POSITION (0..1), or cut NX NY NZ OFFSET";
    if (w.size() == 2 && (w[1] == "off" || w[1] == "on")) {
      set_cut_enabled(w[1] == "on");
      return Status::ok();
    }
    if (w.size() == 3 && v.empty()) {
      static const std::string axes[] = {"x", "y", "z", "-x", "-y", "-z"};
      const auto* a = std::find(std::begin(axes), std::end(axes), w[1]);
      double position = 0;
      if (a == std::end(axes) || !parse_double(w[2], &position)) return bad(usage);
      const int index = int(a - std::begin(axes));
      return wrap(set_cut_axis(index % 3, index < 3, position));
    }
    if (w.size() == 5 && v.size() == 4) return wrap(set_cut_plane({v[0], v[1], v[2]}, v[3]));
    return bad(usage);
  }
  const char* usage = "usage: clip off|on, or clip X0 Y0 Z0 X1 Y1 Z1 (volume fractions)";
  if (w.size() == 2 && (w[1] == "off" || w[1] == "on")) {
    set_roi_enabled(w[1] == "on");
    return Status::ok();
  }
  if (w.size() == 7 && v.size() == 6) return wrap(set_roi({v[0], v[1], v[2]}, {v[3], v[4], v[5]}));
  return bad(usage);
}

void ViewerState::set_model(OpticalModel model) {
  if (scene_.render.model != model) {
    scene_.render.model = model;
    changed();
  }
}

void ViewerState::cycle_model(int direction) {
  const long n = static_cast<long>(std::size(kModels));
  long at = 0;
  for (long i = 0; i < n; ++i)
    if (kModels[i] == scene_.render.model) at = i;
  set_model(kModels[((at + (direction >= 0 ? 1 : -1)) % n + n) % n]);
}

Status ViewerState::set_step(double step_voxels) {
  // Below 1/64 voxel the ray march costs without changing the picture.
  if (!std::isfinite(step_voxels) || step_voxels < 1.0 / 64 || step_voxels > 8)
    return invalid_argument("step must be in [1/64, 8] voxels");
  if (scene_.render.step_voxels != step_voxels) {
    scene_.render.step_voxels = step_voxels;
    changed();
  }
  return Status::ok();
}

Status ViewerState::set_density(double density) {
  if (!std::isfinite(density) || density <= 0) return invalid_argument("density must be > 0");
  if (scene_.render.density != density) {
    scene_.render.density = density;
    changed();
  }
  return Status::ok();
}

Status ViewerState::set_iso_value(double value) {
  if (!std::isfinite(value)) return invalid_argument("iso value must be a finite number");
  if (scene_.render.iso_value != value) {
    scene_.render.iso_value = value;
    changed();
  }
  return Status::ok();
}

Status ViewerState::set_timepoint(uint32_t t) {
  if (t >= timepoints_)
    return out_of_range("timepoint " + std::to_string(t) + " does not exist (" + std::to_string(timepoints_) +
                        " timepoints)");
  clock_.step(int(t) - int(clock_.timepoint()), now_s_);
  if (scene_.timepoint != t) {
    scene_.timepoint = t;
    changed();
  }
  return Status::ok();
}

void ViewerState::note_motion() {
  moved_ = true;
  motion_tick_ = ticks_;
  motion_s_ = now_s_;
}

bool ViewerState::moving() const {
  return moved_ && (ticks_ - motion_tick_ < kStillFrames || now_s_ - motion_s_ < kStillSeconds);
}

void ViewerState::tick(double now_s, const std::function<bool(uint32_t)>& ready) {
  now_s_ = now_s;
  ++ticks_;
  if (!clock_.playing()) return;
  const PlaybackFrame f = clock_.tick(now_s, ready);
  if (f.timepoint != scene_.timepoint) {
    scene_.timepoint = f.timepoint;
    changed();
  }
}

void ViewerState::play() {
  if (timepoints_ > 1) clock_.play(now_s_);
}

void ViewerState::pause() { clock_.pause(now_s_); }

void ViewerState::step_time(int delta) {
  clock_.step(delta, now_s_);
  if (clock_.timepoint() != scene_.timepoint) {
    scene_.timepoint = clock_.timepoint();
    changed();
  }
}

Status ViewerState::set_speed(double speed) {
  if (!(speed >= 1.0 / 16.0 && speed <= 16.0))
    return out_of_range("playback speed " + std::to_string(speed) + " is outside 1/16 .. 16");
  clock_.set_speed(speed, now_s_);
  return Status::ok();
}

void ViewerState::orbit_drag(double dx_px, double dy_px) {
  orbit_.yaw = std::remainder(orbit_.yaw - dx_px * kRadiansPerPixel, 2 * kPi);
  orbit_.pitch = std::clamp(orbit_.pitch + dy_px * kRadiansPerPixel, -kMaxPitch, kMaxPitch);
  changed();
}

void ViewerState::pan_drag(double dx_px, double dy_px, double view_height_px) {
  if (!(view_height_px > 0)) return;
  // World units per pixel at the focus distance: the focus follows the cursor.
  const double per_px = 2 * orbit_.distance * std::tan(orbit_.fov_y_deg * kPi / 360.0) / view_height_px;
  const CameraState c = orbit_.camera();
  std::array<double, 3> fwd, right;
  for (int i = 0; i < 3; ++i) fwd[i] = (c.target[i] - c.eye[i]) / orbit_.distance;
  right = {fwd[1] * c.up[2] - fwd[2] * c.up[1], fwd[2] * c.up[0] - fwd[0] * c.up[2],
           fwd[0] * c.up[1] - fwd[1] * c.up[0]};
  for (int i = 0; i < 3; ++i) orbit_.focus[i] += (-dx_px * right[i] + dy_px * c.up[i]) * per_px;
  changed();
}

void ViewerState::zoom(double wheel_ticks) {
  orbit_.distance = std::clamp(orbit_.distance * std::pow(kZoomPerTick, wheel_ticks), 0.01, 100.0);
  changed();
}

void ViewerState::fly(const FlyInput& d, double amount) {
  if (!d.any() || !(amount > 0) || !std::isfinite(amount)) return;
  const CameraState c = orbit_.camera();
  std::array<double, 3> fwd, right;
  for (int i = 0; i < 3; ++i) fwd[i] = (c.target[i] - c.eye[i]) / orbit_.distance;
  right = {fwd[1] * c.up[2] - fwd[2] * c.up[1], fwd[2] * c.up[0] - fwd[0] * c.up[2],
           fwd[0] * c.up[1] - fwd[1] * c.up[0]};
  // The focus moves and the eye with it: the view turns nowhere, it travels.
  for (int i = 0; i < 3; ++i) orbit_.focus[i] += amount * (d.forward * fwd[i] + d.right * right[i] + d.up * c.up[i]);
  changed();
}

void ViewerState::fly_for(const FlyInput& held, double seconds) {
  fly(held, 0.5 * orbit_.distance * std::clamp(seconds, 0.0, 0.1));  // a stalled frame is not a jump
}

void ViewerState::reset_view() {
  orbit_ = home_;
  changed();
}

Status ViewerState::axis_view(int axis) {
  OrbitCamera o = home_;
  switch (axis) {
    case 0: o.yaw = kPi / 2; break;     // eye on +x
    case 1: o.pitch = kMaxPitch; break;  // eye above, on +y
    case 2: break;                       // eye on +z
    default: return invalid_argument("axis view needs 1, 2 or 3");
  }
  orbit_ = o;
  changed();
  return Status::ok();
}

Status ViewerState::restore(const RenderSettings& render, uint32_t timepoint, const OrbitCamera& orbit) {
  if (render.channels.size() != scene_.render.channels.size())
    return invalid_argument("the card draws " + std::to_string(render.channels.size()) + " channel(s), this view " +
                            std::to_string(scene_.render.channels.size()));
  if (timepoint >= timepoints_)
    return out_of_range("the card's timepoint " + std::to_string(timepoint) + " does not exist (" +
                        std::to_string(timepoints_) + " timepoints)");
  if (!(orbit.distance > 0) || !std::isfinite(orbit.yaw) || !std::isfinite(orbit.pitch))
    return invalid_argument("the card's camera cannot be shown as an orbit");
  scene_.render = render;
  clock_.step(int(timepoint) - int(clock_.timepoint()), now_s_);
  scene_.timepoint = timepoint;
  orbit_ = orbit;
  orbit_.pitch = std::clamp(orbit_.pitch, -kMaxPitch, kMaxPitch);
  changed();
  return Status::ok();
}

void ViewerState::handle_key(ViewerKey key) {
  switch (key) {
    case ViewerKey::kResetView: reset_view(); break;
    case ViewerKey::kAxisX: (void)axis_view(0); break;
    case ViewerKey::kAxisY: (void)axis_view(1); break;
    case ViewerKey::kAxisZ: (void)axis_view(2); break;
    case ViewerKey::kNextModel: cycle_model(1); break;
    case ViewerKey::kNextColormap: (void)cycle_colormap(0, 1); break;
    case ViewerKey::kTimeNext:
      if (scene_.timepoint + 1 < timepoints_) (void)set_timepoint(scene_.timepoint + 1);
      break;
    case ViewerKey::kTimePrev:
      if (scene_.timepoint > 0) (void)set_timepoint(scene_.timepoint - 1);
      break;
    case ViewerKey::kPlayPause: clock_.playing() ? pause() : play(); break;
    case ViewerKey::kStepBack: step_time(-1); break;
    case ViewerKey::kStepForward: step_time(1); break;
    case ViewerKey::kSlower: (void)set_speed(std::max(1.0 / 16.0, clock_.speed() / 2.0)); break;
    case ViewerKey::kFaster: (void)set_speed(std::min(16.0, clock_.speed() * 2.0)); break;
    case ViewerKey::kToggleHelp: help_visible_ = !help_visible_; break;
    case ViewerKey::kToggleUi: ui_visible_ = !ui_visible_; break;
    case ViewerKey::kQuit: quit_requested_ = true; break;
    case ViewerKey::kFinishTool: break;  // the tools' key: the window hands it to ViewerTools
  }
}

Status ViewerState::apply_command(const std::string& line) {
  std::istringstream in(line);
  std::vector<std::string> w;
  for (std::string tok; in >> tok;) w.push_back(tok);
  if (w.empty() || w[0][0] == '#') return Status::ok();
  const std::string& cmd = w[0];
  auto bad = [&](const std::string& why) { return invalid_argument("'" + line + "': " + why); };
  auto wrap = [&](Status s) { return s.is_ok() ? s : bad(s.message()); };
  auto need = [&](size_t n) { return w.size() == n + 1; };
  size_t ch = 0;
  double a = 0, b = 0;
  if (cmd == "visible") {
    if (!need(2) || !parse_index(w[1], &ch) || (w[2] != "on" && w[2] != "off")) return bad("usage: visible CH on|off");
    return wrap(set_channel_visible(ch, w[2] == "on"));
  }
  if (cmd == "colormap") {
    if (!need(2) || !parse_index(w[1], &ch)) return bad("usage: colormap CH NAME");
    return wrap(set_colormap(ch, w[2]));
  }
  if (cmd == "window") {
    if (!need(3) || !parse_index(w[1], &ch) || !parse_double(w[2], &a) || !parse_double(w[3], &b))
      return bad("usage: window CH LO HI");
    return wrap(set_window(ch, a, b));
  }
  if (cmd == "gamma") {
    if (!need(2) || !parse_index(w[1], &ch) || !parse_double(w[2], &a)) return bad("usage: gamma CH G");
    return wrap(set_gamma(ch, a));
  }
  if (cmd == "opacity") {
    if (!need(2) || !parse_index(w[1], &ch)) return bad("usage: opacity CH X:A,X:A,... (x rising in 0..1) or opacity CH ramp");
    if (w[2] == "ramp") return wrap(set_opacity_points(ch, {}));
    const auto points = parse_opacity_points(w[2]);
    if (!points) return bad("usage: opacity CH X:A,X:A,... (x rising in 0..1) or opacity CH ramp");
    return wrap(set_opacity_points(ch, *points));
  }
  if (cmd == "cut" || cmd == "clip") return apply_clip_command(w, line);
  if (cmd == "fly") {
    double c = 0;
    if (!need(3) || !parse_double(w[1], &a) || !parse_double(w[2], &b) || !parse_double(w[3], &c))
      return bad("usage: fly FORWARD RIGHT UP (volume lengths)");
    const double len = std::sqrt(a * a + b * b + c * c);
    if (len > 0) fly({a / len, b / len, c / len}, len);
    return Status::ok();
  }
  if (cmd == "model") {
    OpticalModel m;
    if (!need(1) || !optical_model_from_name(w[1], &m)) return bad("usage: model ea|emission|mip|minip|average|iso");
    set_model(m);
    return Status::ok();
  }
  if (cmd == "step") {
    if (!need(1) || !parse_double(w[1], &a)) return bad("usage: step VOXELS");
    return wrap(set_step(a));
  }
  if (cmd == "density") {
    if (!need(1) || !parse_double(w[1], &a)) return bad("usage: density D");
    return wrap(set_density(a));
  }
  if (cmd == "iso") {
    if (!need(1) || !parse_double(w[1], &a)) return bad("usage: iso VALUE (data units)");
    return wrap(set_iso_value(a));
  }
  if (cmd == "time") {
    if (!need(1) || !parse_index(w[1], &ch)) return bad("usage: time T");
    return wrap(set_timepoint(static_cast<uint32_t>(ch)));
  }
  if (cmd == "play" || cmd == "pause") {
    if (!need(0)) return bad("usage: " + cmd);
    if (cmd == "play" && timepoints_ < 2) return bad("one timepoint: nothing to play");
    cmd == "play" ? play() : pause();
    return Status::ok();
  }
  if (cmd == "speed") {
    if (!need(1) || !parse_double(w[1], &a)) return bad("usage: speed X (1/16 .. 16)");
    return wrap(set_speed(a));
  }
  if (cmd == "loop") {
    if (!need(1) || (w[1] != "on" && w[1] != "off")) return bad("usage: loop on|off");
    set_loop(w[1] == "on");
    return Status::ok();
  }
  if (cmd == "orbit" || cmd == "pan") {
    if (!need(2) || !parse_double(w[1], &a) || !parse_double(w[2], &b)) return bad("usage: " + cmd + " DX DY");
    if (cmd == "orbit")
      orbit_drag(a, b);
    else
      pan_drag(a, b, 800);
    return Status::ok();
  }
  if (cmd == "zoom") {
    if (!need(1) || !parse_double(w[1], &a)) return bad("usage: zoom TICKS");
    zoom(a);
    return Status::ok();
  }
  if (cmd == "reset") {
    if (!need(0)) return bad("usage: reset");
    reset_view();
    return Status::ok();
  }
  if (cmd == "view") {
    if (!need(1) || !parse_index(w[1], &ch) || ch < 1 || ch > 3) return bad("usage: view 1|2|3");
    return axis_view(static_cast<int>(ch) - 1);
  }
  return bad("unknown command '" + cmd + "'");
}

std::string viewer_config_path() {
  std::filesystem::path base;
  if (const char* x = std::getenv("XDG_CONFIG_HOME"); x && *x)
    base = x;
  else if (const char* h = std::getenv("HOME"); h && *h)
    base = std::filesystem::path(h) / ".config";
  else
    return {};
  return (base / "vxr" / "desktop.json").string();
}

Result<WindowGeometry> load_window_geometry(const std::string& path) {
  WindowGeometry g;
  std::ifstream in(path);
  if (!in) return g;  // first run
  std::stringstream text;
  text << in.rdbuf();
  nlohmann::json j = nlohmann::json::parse(text.str(), nullptr, false);
  if (j.is_discarded() || !j.is_object()) return invalid_argument(path + ": not a JSON object");
  for (const char* key : {"width", "height"}) {
    if (!j.contains(key)) continue;
    if (!j[key].is_number_unsigned() || j[key].get<uint64_t>() < 64 || j[key].get<uint64_t>() > 16384)
      return invalid_argument(path + ": '" + key + "' must be an integer in 64..16384");
    (std::string(key) == "width" ? g.width : g.height) = j[key].get<uint32_t>();
  }
  return g;
}

std::string remembered_view_path(const std::string& input) {
  namespace fs = std::filesystem;
  std::error_code ec;
  // A project keeps its view inside it, so it travels with the project.
  for (fs::path p = fs::absolute(input, ec); !ec && !p.empty(); p = p.parent_path()) {
    if (p.extension() == ".vxr" && fs::is_regular_file(p / "project.json", ec)) return (p / "viewer.json").string();
    if (p == p.parent_path()) break;
  }
  const std::string config = viewer_config_path();
  if (config.empty()) return {};
  uint64_t h = 1469598103934665603ull;  // FNV-1a 64 of the input's absolute path (or name, procedural:...)
  const std::string key = input.rfind("procedural:", 0) == 0 || input.empty() ? input : fs::absolute(input, ec).string();
  for (unsigned char c : key) h = (h ^ c) * 1099511628211ull;
  char name[32];
  std::snprintf(name, sizeof name, "%016llx.json", static_cast<unsigned long long>(h));
  return (fs::path(config).parent_path() / "views" / name).string();
}

Status save_remembered_view(const std::string& path, const Scene& scene) {
  std::error_code ec;
  std::filesystem::create_directories(std::filesystem::path(path).parent_path(), ec);
  if (ec) return io_error(path + ": " + ec.message());
  return write_file_atomically(path, scene_to_json(scene) + "\n");
}

Result<std::optional<Scene>> load_remembered_view(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  if (!in) return std::optional<Scene>();  // nothing remembered yet
  std::stringstream text;
  text << in.rdbuf();
  auto scene = scene_from_json(text.str());
  if (!scene) return invalid_argument(path + ": not a remembered view (" + scene.status().message() + ")");
  return std::optional<Scene>(std::move(scene).value());
}

Status save_window_geometry(const std::string& path, const WindowGeometry& g) {
  std::error_code ec;
  std::filesystem::create_directories(std::filesystem::path(path).parent_path(), ec);
  if (ec) return io_error(path + ": " + ec.message());
  nlohmann::json j = {{"width", g.width}, {"height", g.height}};
  return write_file_atomically(path, j.dump(2) + "\n");
}

}  // namespace vxr::xr
