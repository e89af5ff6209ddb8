#include "xr/script.h"

#include <fstream>
#include <sstream>

namespace vxr::xr {
namespace {

glm::dvec3 vec3_of(const nlohmann::json& j) { return {j.at(0).get<double>(), j.at(1).get<double>(), j.at(2).get<double>()}; }

void read_pose(const nlohmann::json& j, Pose& p) {
  if (j.contains("position")) p.position = vec3_of(j["position"]);
  if (j.contains("orientation")) {
    const auto& q = j["orientation"];
    p.orientation = glm::normalize(
        glm::dquat(q.at(3).get<double>(), q.at(0).get<double>(), q.at(1).get<double>(), q.at(2).get<double>()));
  }
}

void read_hand(const nlohmann::json& j, ScriptHand& h) {
  if (j.contains("tracked")) h.tracked = j["tracked"].get<bool>();
  if (j.contains("grip")) {
    read_pose(j["grip"], h.grip);
    if (!j.contains("aim")) h.aim = h.grip;
  }
  if (j.contains("aim")) read_pose(j["aim"], h.aim);
  if (j.contains("squeeze")) h.squeeze = j["squeeze"].get<double>();
  if (j.contains("trigger")) h.trigger = j["trigger"].get<double>();
  if (j.contains("thumbstick")) h.thumbstick = {j["thumbstick"].at(0).get<double>(), j["thumbstick"].at(1).get<double>()};
  if (j.contains("menu")) h.menu = j["menu"].get<bool>();
}

Pose lerp_pose(const Pose& a, const Pose& b, double w) {
  return {glm::slerp(a.orientation, b.orientation, w), a.position + w * (b.position - a.position)};
}

}  // namespace

ScriptFrame default_script_frame() {
  ScriptFrame f;
  f.head.position = {0.0, 1.6, 0.0};
  for (int h = 0; h < 2; ++h) {
    f.hands[h].grip.position = {h == 0 ? -0.15 : 0.15, 1.3, -0.3};
    f.hands[h].aim = f.hands[h].grip;
  }
  return f;
}

ScriptFrame Script::at(uint64_t frame) const {
  if (keys.empty()) return default_script_frame();
  if (frame <= keys.front().first) return keys.front().second;
  for (size_t i = 1; i < keys.size(); ++i) {
    if (frame >= keys[i].first) continue;
    const auto& [f0, a] = keys[i - 1];
    const auto& [f1, b] = keys[i];
    const double w = double(frame - f0) / double(f1 - f0);
    ScriptFrame s = a;  // buttons step at the key
    s.head = lerp_pose(a.head, b.head, w);
    for (int h = 0; h < 2; ++h) {
      s.hands[h].grip = lerp_pose(a.hands[h].grip, b.hands[h].grip, w);
      s.hands[h].aim = lerp_pose(a.hands[h].aim, b.hands[h].aim, w);
    }
    return s;
  }
  return keys.back().second;
}

bool parse_script_text(const std::string& text, Script& out, std::string& error) {
  try {
    Script s;
    s.raw = nlohmann::json::parse(text);
    if (s.raw.contains("view")) {
      const auto& v = s.raw["view"];
      if (v.contains("width")) s.width = v["width"].get<uint32_t>();
      if (v.contains("height")) s.height = v["height"].get<uint32_t>();
      if (v.contains("ipd_m")) s.ipd_m = v["ipd_m"].get<double>();
      if (v.contains("fov_deg")) {
        const auto& f = v["fov_deg"];
        const double k = 3.14159265358979323846 / 180.0;
        s.fov = {f.at("left").get<double>() * k, f.at("right").get<double>() * k, f.at("up").get<double>() * k,
                 f.at("down").get<double>() * k};
      }
      if (s.width == 0 || s.height == 0 || s.width > 4096 || s.height > 4096) {
        error = "view width/height must be 1..4096";
        return false;
      }
    }
    ScriptFrame state = default_script_frame();
    uint64_t last = 0;
    if (s.raw.contains("keys")) {
      for (const auto& k : s.raw["keys"]) {
        const uint64_t frame = k.at("frame").get<uint64_t>();
        if (!s.keys.empty() && frame <= last) {
          error = "keys must have strictly increasing \"frame\" (frame " + std::to_string(frame) + " after " +
                  std::to_string(last) + ")";
          return false;
        }
        if (k.contains("head")) read_pose(k["head"], state.head);
        if (k.contains("left")) read_hand(k["left"], state.hands[0]);
        if (k.contains("right")) read_hand(k["right"], state.hands[1]);
        s.keys.emplace_back(frame, state);
        last = frame;
      }
    }
    out = std::move(s);
    return true;
  } catch (const std::exception& e) {
    error = e.what();
    return false;
  }
}

bool load_script(const std::string& path, Script& out, std::string& error) {
  std::ifstream in(path);
  if (!in) {
    error = path + ": cannot open the pose script";
    return false;
  }
  std::stringstream ss;
  ss << in.rdbuf();
  if (!parse_script_text(ss.str(), out, error)) {
    error = path + ": " + error;
    return false;
  }
  return true;
}

}  // namespace vxr::xr
