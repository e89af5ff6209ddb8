#include "scene/render_settings.h"

#include <nlohmann/json.hpp>

#include <cmath>

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
  return {{"model", optical_model_name(s.model)},
          {"channels", channels},
          {"blend", blend_name(s.blend)},
          {"step_voxels", s.step_voxels},
          {"density", s.density},
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
}

// Reads j[key] into out when present; a wrong type throws json::type_error,
// which the callers turn into a message naming `key`.
template <typename T>
void get(const json& j, const char* key, T& out) {
  if (j.contains(key)) out = j.at(key).get<T>();
}

struct KeyError {
  std::string message;
};

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
  json j = {{"volume", s.volume}, {"render", to_j(s.render)}};
  if (s.has_camera)
    j["camera"] = {{"eye", s.camera.eye}, {"target", s.camera.target}, {"up", s.camera.up}, {"fov_y_deg", s.camera.fov_y_deg}};
  return j.dump(2);
}

Result<Scene> scene_from_json(const std::string& text) {
  return parse<Scene>(text, [](const json& j, Scene& s) {
    if (!j.is_object()) throw KeyError{"the scene must be a JSON object"};
    get(j, "volume", s.volume);
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

}  // namespace vxr
