#include "scene/render_settings.h"

#include <nlohmann/json.hpp>

#include <cmath>
#include "core/json_number.h"

namespace vxr {
namespace {

using nlohmann::json;

const char* blend_name(ChannelBlend b) { return b == ChannelBlend::kAdditive ? "additive" : "composite"; }
const char* depth_name(DepthColorMode m) {
  switch (m) {
    case DepthColorMode::kOff: return "off";
    case DepthColorMode::kView: return "view";
    case DepthColorMode::kAxisX: return "x";
    case DepthColorMode::kAxisY: return "y";
    case DepthColorMode::kAxisZ: return "z";
  }
  return "off";
}

json clip_j(const ClipSettings& c) {
  json j = json::object();
  if (c.cut) j["cut"] = {{"normal", c.cut_normal}, {"offset", c.cut_offset}};
  if (c.roi) j["roi"] = {{"lo", c.roi_lo}, {"hi", c.roi_hi}};
  return j;
}

json to_j(const RenderSettings& s) {
  json channels = json::array();
  for (const auto& c : s.channels) {
    json cp = json::array(), op = json::array();
    for (const auto& p : c.color_points) cp.push_back({{"x", p.x}, {"rgb", p.rgb}});
    for (const auto& p : c.opacity_points) op.push_back({{"x", p.x}, {"opacity", p.opacity}});
    channels.push_back({{"enabled", c.enabled},
                        {"window", {c.window_lo, c.window_hi}},
                        {"gamma", c.gamma},
                        {"colormap", c.colormap},
                        {"color_points", cp},
                        {"opacity_points", op}});
  }
  json out = {{"model", optical_model_name(s.model)},
          {"channels", channels},
          {"blend", blend_name(s.blend)},
          {"step_voxels", s.step_voxels},
          {"density", s.density},
          {"opacity_unit_distance", s.opacity_unit_distance},
          {"early_termination", s.early_termination},
          {"opacity_correction", s.opacity_correction},
          {"jitter", s.jitter},
          {"sample_offset", s.sample_offset},
          {"iso_value", s.iso_value},
          {"iso_channel", s.iso_channel},
          {"shading",
           {{"ambient", s.shading.ambient},
            {"diffuse", s.shading.diffuse},
            {"specular", s.shading.specular},
            {"shininess", s.shading.shininess}}},
          {"depth_color", depth_name(s.depth_color)},
          {"gradient_opacity",
           {{"enabled", s.gradient_opacity.enabled}, {"lo", s.gradient_opacity.lo}, {"hi", s.gradient_opacity.hi}}},
          {"max_steps", s.max_steps}};
  // Only when clipping is on: files and cards written before clipping existed stay byte for byte the same.
  if (s.clip.cut || s.clip.roi) out["clip"] = clip_j(s.clip);
  return out;
}

// Reads j[key] into out when present; a wrong type throws json::type_error,
// which the callers turn into a message naming `key`.
struct KeyError {
  std::string message;
};

// Numbers go through json_number: a value the field's type cannot hold
// (1e300 for an integer) is an error naming the key, not a wrapped value.
template <typename T>
void get(const json& j, const char* key, T& out) {
  if (!j.contains(key)) return;
  if constexpr (std::is_arithmetic_v<T> && !std::is_same_v<T, bool>) {
    const std::optional<T> v = json_number<T>(j.at(key));
    if (!v)
      throw KeyError{"\"" + std::string(key) + "\": " + (j.at(key).is_number() ? j.at(key).dump() : "the value") +
                     " is not " + (std::is_integral_v<T> ? "a non-negative integer in range" : "a finite number")};
    out = *v;
  } else {
    out = j.at(key).get<T>();
  }
}

void from_j(const json& j, RenderSettings& s) {
  if (!j.is_object()) throw KeyError{"the settings must be a JSON object"};
  if (j.contains("model")) {
    const std::string m = j.at("model").get<std::string>();
    if (!optical_model_from_name(m, &s.model))
      throw KeyError{"\"model\": unknown optical model '" + m + "' (use ea, emission, mip, minip, average or iso)"};
  }
  if (j.contains("channels")) {
    const json& chs = j.at("channels");
    if (!chs.is_array()) throw KeyError{"\"channels\" must be an array"};
    s.channels.clear();
    for (const json& c : chs) {
      ChannelSettings ch;
      get(c, "enabled", ch.enabled);
      if (c.contains("window")) {
        const auto w = c.at("window").get<std::vector<double>>();
        if (w.size() != 2) throw KeyError{"\"window\" must be [lo, hi]"};
        ch.window_lo = w[0];
        ch.window_hi = w[1];
      }
      get(c, "gamma", ch.gamma);
      get(c, "colormap", ch.colormap);
      if (c.contains("color_points"))
        for (const json& p : c.at("color_points")) ch.color_points.push_back({p.at("x").get<double>(), p.at("rgb").get<std::array<double, 3>>()});
      if (c.contains("opacity_points"))
        for (const json& p : c.at("opacity_points"))
          ch.opacity_points.push_back({p.at("x").get<double>(), p.at("opacity").get<double>()});
      s.channels.push_back(std::move(ch));
    }
  }
  if (j.contains("blend")) {
    const std::string b = j.at("blend").get<std::string>();
    if (b == "additive") s.blend = ChannelBlend::kAdditive;
    else if (b == "composite") s.blend = ChannelBlend::kComposite;
    else throw KeyError{"\"blend\": unknown channel blend '" + b + "' (use additive or composite)"};
  }
  get(j, "step_voxels", s.step_voxels);
  get(j, "density", s.density);
  get(j, "opacity_unit_distance", s.opacity_unit_distance);
  get(j, "early_termination", s.early_termination);
  get(j, "opacity_correction", s.opacity_correction);
  get(j, "jitter", s.jitter);
  get(j, "sample_offset", s.sample_offset);
  get(j, "iso_value", s.iso_value);
  get(j, "iso_channel", s.iso_channel);
  if (j.contains("shading")) {
    const json& sh = j.at("shading");
    get(sh, "ambient", s.shading.ambient);
    get(sh, "diffuse", s.shading.diffuse);
    get(sh, "specular", s.shading.specular);
    get(sh, "shininess", s.shading.shininess);
  }
  if (j.contains("depth_color")) {
    const std::string d = j.at("depth_color").get<std::string>();
    bool found = false;
    for (DepthColorMode m : {DepthColorMode::kOff, DepthColorMode::kView, DepthColorMode::kAxisX,
                             DepthColorMode::kAxisY, DepthColorMode::kAxisZ})
      if (d == depth_name(m)) s.depth_color = m, found = true;
    if (!found) throw KeyError{"\"depth_color\": unknown mode '" + d + "' (use off, view, x, y or z)"};
  }
  if (j.contains("gradient_opacity")) {
    const json& g = j.at("gradient_opacity");
    get(g, "enabled", s.gradient_opacity.enabled);
    get(g, "lo", s.gradient_opacity.lo);
    get(g, "hi", s.gradient_opacity.hi);
  }
  get(j, "max_steps", s.max_steps);
  if (j.contains("clip")) {
    const json& c = j.at("clip");
    if (!c.is_object()) throw KeyError{"\"clip\" must be an object"};
    if (c.contains("cut")) {
      const json& cut = c.at("cut");
      if (!cut.is_object() || !cut.contains("normal") || !cut.contains("offset"))
        throw KeyError{"clip.cut must be an object {normal: [x, y, z], offset} (volume fractions)"};
      if (!cut.at("normal").is_array() || cut.at("normal").size() != 3)
        throw KeyError{"clip.cut.normal must be [x, y, z] (volume fractions)"};
      s.clip.cut = true;
      get(cut, "normal", s.clip.cut_normal);
      get(cut, "offset", s.clip.cut_offset);
      double n2 = 0.0;
      for (double v : s.clip.cut_normal) n2 += v * v;
      if (!(std::isfinite(n2) && n2 > 0.0 && std::isfinite(s.clip.cut_offset)))
        throw KeyError{"clip.cut.normal must be a finite non-zero vector and clip.cut.offset a finite number"};
    }
    if (c.contains("roi")) {
      s.clip.roi = true;
      get(c.at("roi"), "lo", s.clip.roi_lo);
      get(c.at("roi"), "hi", s.clip.roi_hi);
      for (int a = 0; a < 3; ++a)
        if (!(std::isfinite(s.clip.roi_lo[a]) && std::isfinite(s.clip.roi_hi[a]) && s.clip.roi_lo[a] < s.clip.roi_hi[a]))
          throw KeyError{"clip.roi must have finite lo < hi on every axis (volume fractions)"};
    }
  }
}

template <typename T, typename F>
Result<T> parse(const std::string& text, F&& fill) {
  json j = json::parse(text, nullptr, false);
  if (j.is_discarded()) return invalid_argument("malformed JSON");
  T out;
  try {
    fill(j, out);
  } catch (const KeyError& e) {
    return invalid_argument(e.message);
  } catch (const json::exception& e) {
    return invalid_argument(std::string("wrong value type: ") + e.what());
  }
  return out;
}

}  // namespace

const char* optical_model_name(OpticalModel m) {
  switch (m) {
    case OpticalModel::kEmissionAbsorption: return "ea";
    case OpticalModel::kEmission: return "emission";
    case OpticalModel::kMip: return "mip";
    case OpticalModel::kMinIp: return "minip";
    case OpticalModel::kAverage: return "average";
    case OpticalModel::kIsosurface: return "iso";
  }
  return "ea";
}

bool optical_model_from_name(const std::string& name, OpticalModel* out) {
  for (OpticalModel m : {OpticalModel::kEmissionAbsorption, OpticalModel::kEmission, OpticalModel::kMip,
                         OpticalModel::kMinIp, OpticalModel::kAverage, OpticalModel::kIsosurface})
    if (name == optical_model_name(m)) {
      *out = m;
      return true;
    }
  return false;
}

std::string render_settings_to_json(const RenderSettings& s) { return to_j(s).dump(2); }

Result<RenderSettings> render_settings_from_json(const std::string& text) {
  return parse<RenderSettings>(text, [](const json& j, RenderSettings& s) { from_j(j, s); });
}

std::string scene_to_json(const Scene& s) {
  json j = {{"volume", s.volume},
            {"timepoint", s.timepoint},
            {"channels", s.channels},
            {"transform", {{"position", s.transform.position}, {"rotation", s.transform.rotation}, {"scale", s.transform.scale}}},
            {"viewport", s.viewport},
            {"renderer", s.renderer},
            {"path", s.path},
            {"lod_bias", s.lod_bias},
            {"render", to_j(s.render)}};
  if (!s.annotations.empty()) j["annotations"] = s.annotations;
  if (s.has_camera)
    j["camera"] = {{"eye", s.camera.eye}, {"target", s.camera.target}, {"up", s.camera.up}, {"fov_y_deg", s.camera.fov_y_deg}};
  if (s.voxel_size != std::array<double, 3>{0, 0, 0}) j["voxel_size"] = s.voxel_size;  // older readers ignore it
  return j.dump(2);
}

Result<Scene> scene_from_json(const std::string& text) {
  return parse<Scene>(text, [](const json& j, Scene& s) {
    if (!j.is_object()) throw KeyError{"the scene must be a JSON object"};
    get(j, "volume", s.volume);
    get(j, "timepoint", s.timepoint);
    get(j, "channels", s.channels);
    if (j.contains("transform")) {
      const json& t = j.at("transform");
      if (!t.is_object()) throw KeyError{"\"transform\" must be an object {position, rotation, scale}"};
      get(t, "position", s.transform.position);
      get(t, "rotation", s.transform.rotation);
      get(t, "scale", s.transform.scale);
      double n2 = 0.0;
      for (double v : s.transform.position)
        if (!std::isfinite(v)) throw KeyError{"transform.position must be finite numbers"};
      for (double v : s.transform.rotation) {
        if (!std::isfinite(v)) throw KeyError{"transform.rotation must be finite numbers"};
        n2 += v * v;
      }
      if (!(n2 > 0.0)) throw KeyError{"transform.rotation is the zero quaternion; use [1, 0, 0, 0] for no rotation"};
      if (!(s.transform.scale > 0.0 && std::isfinite(s.transform.scale)))
        throw KeyError{"transform.scale must be a positive finite number"};
    }
    get(j, "viewport", s.viewport);
    if (s.viewport[0] > 16384 || s.viewport[1] > 16384 || (s.viewport[0] == 0) != (s.viewport[1] == 0))
      throw KeyError{"viewport must be [width, height] of 1..16384 pixels each (or [0, 0])"};
    get(j, "renderer", s.renderer);
    if (!s.renderer.empty() && s.renderer != "lod" && s.renderer != "dense")
      throw KeyError{"\"renderer\": use lod, dense or \"\", not '" + s.renderer + "'"};
    get(j, "path", s.path);
    if (!s.path.empty() && s.path != "compute" && s.path != "fragment")
      throw KeyError{"\"path\": use compute, fragment or \"\", not '" + s.path + "'"};
    get(j, "annotations", s.annotations);
    get(j, "lod_bias", s.lod_bias);
    if (!(std::isfinite(s.lod_bias) && std::abs(s.lod_bias) <= 16.0))
      throw KeyError{"lod_bias must be within -16..16"};
    get(j, "voxel_size", s.voxel_size);
    if (s.voxel_size != std::array<double, 3>{0, 0, 0})
      for (double v : s.voxel_size)
        if (!(v > 0.0 && std::isfinite(v)))
          throw KeyError{"voxel_size must be three positive finite numbers (world units per voxel), or absent"};
    if (j.contains("camera")) {
      const json& c = j.at("camera");
      s.has_camera = true;
      get(c, "eye", s.camera.eye);
      get(c, "target", s.camera.target);
      get(c, "up", s.camera.up);
      get(c, "fov_y_deg", s.camera.fov_y_deg);
      // A degenerate camera draws a black picture and says nothing: refuse it here.
      if (!(s.camera.fov_y_deg > 0.0 && s.camera.fov_y_deg < 179.0))
        throw KeyError{"camera.fov_y_deg must be in (0, 179) degrees"};
      for (double v : {s.camera.eye[0], s.camera.eye[1], s.camera.eye[2], s.camera.target[0], s.camera.target[1],
                       s.camera.target[2], s.camera.up[0], s.camera.up[1], s.camera.up[2]})
        if (!std::isfinite(v)) throw KeyError{"camera: eye, target and up must be finite numbers"};
      const double d[3] = {s.camera.target[0] - s.camera.eye[0], s.camera.target[1] - s.camera.eye[1],
                           s.camera.target[2] - s.camera.eye[2]};
      const double* u = s.camera.up.data();
      const double cross[3] = {d[1] * u[2] - d[2] * u[1], d[2] * u[0] - d[0] * u[2], d[0] * u[1] - d[1] * u[0]};
      if (cross[0] == 0.0 && cross[1] == 0.0 && cross[2] == 0.0)
        throw KeyError{"camera: eye and target coincide, or up is parallel to the view direction"};
    }
    if (j.contains("render")) from_j(j.at("render"), s.render);
  });
}

CameraState camera_in_volume_frame(const CameraState& camera, const VolumeTransform& t) {
  const auto& q = t.rotation;
  const double n = std::sqrt(q[0] * q[0] + q[1] * q[1] + q[2] * q[2] + q[3] * q[3]);
  // The inverse rotation is the conjugate of the normalised quaternion.
  const double w = q[0] / n, x = -q[1] / n, y = -q[2] / n, z = -q[3] / n;
  auto rotate = [&](const std::array<double, 3>& v) {  // v' = v + 2w(u x v) + 2u x (u x v), u = (x, y, z)
    const double cx = y * v[2] - z * v[1], cy = z * v[0] - x * v[2], cz = x * v[1] - y * v[0];
    const double ccx = y * cz - z * cy, ccy = z * cx - x * cz, ccz = x * cy - y * cx;
    return std::array<double, 3>{v[0] + 2 * (w * cx + ccx), v[1] + 2 * (w * cy + ccy), v[2] + 2 * (w * cz + ccz)};
  };
  auto to_volume = [&](const std::array<double, 3>& p) {
    auto r = rotate({p[0] - t.position[0], p[1] - t.position[1], p[2] - t.position[2]});
    return std::array<double, 3>{r[0] / t.scale, r[1] / t.scale, r[2] / t.scale};
  };
  CameraState out = camera;
  out.eye = to_volume(camera.eye);
  out.target = to_volume(camera.target);
  out.up = rotate(camera.up);
  return out;
}

}  // namespace vxr
