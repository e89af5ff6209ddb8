#include "xr/script.h"

#include <cmath>
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
  if (j.contains("thumbstick_click")) h.thumbstick_click = j["thumbstick_click"].get<bool>();
  if (j.contains("trackpad_click")) h.trackpad_click = j["trackpad_click"].get<bool>();
  if (j.contains("a")) h.a = j["a"].get<bool>();
  if (j.contains("b")) h.b = j["b"].get<bool>();
}

Pose lerp_pose(const Pose& a, const Pose& b, double w) {
  return {glm::slerp(a.orientation, b.orientation, w), a.position + w * (b.position - a.position)};
}

// q or -q, whichever is nearer `ref` (the same rotation; keeps SQUAD on the short arc).
glm::dquat same_hemisphere(const glm::dquat& q, const glm::dquat& ref) { return glm::dot(q, ref) < 0.0 ? -q : q; }

glm::dquat quat_log(const glm::dquat& q) {  // unit q -> (0, axis * half-angle)
  const glm::dvec3 v(q.x, q.y, q.z);
  const double s = glm::length(v);
  if (s < 1e-12) return {0.0, 0.0, 0.0, 0.0};
  const double a = std::atan2(s, q.w);
  return {0.0, v.x / s * a, v.y / s * a, v.z / s * a};
}

glm::dquat quat_exp(const glm::dquat& q) {  // (0, v) -> unit quaternion
  const glm::dvec3 v(q.x, q.y, q.z);
  const double a = glm::length(v);
  if (a < 1e-12) return {1.0, 0.0, 0.0, 0.0};
  const glm::dvec3 u = v / a * std::sin(a);
  return {std::cos(a), u.x, u.y, u.z};
}

// One pose track (head, a grip or an aim) sampled between keys i and i+1 at
// w in [0, 1]. Position: cubic Hermite with Catmull-Rom tangents over the key
// frames (per frame, so uneven key spacing keeps velocity continuous), zero
// at the ends. Orientation: SQUAD whose inner control points are chosen per
// side of each key so that the angular velocity per frame, T_k = (log(q_k^-1
// q_k+1) - log(q_k^-1 q_k-1)) / (t_k+1 - t_k-1), is the same leaving and
// entering the key. (With uniform spacing this is the textbook SQUAD.)
Pose smooth_pose(const std::vector<double>& t, std::vector<Pose> p, size_t i, double w) {
  const size_t n = p.size();
  for (size_t k = 1; k < n; ++k) p[k].orientation = same_hemisphere(p[k].orientation, p[k - 1].orientation);
  auto tangent = [&](size_t k) -> glm::dvec3 {
    if (k == 0 || k + 1 == n) return glm::dvec3(0.0);
    return (p[k + 1].position - p[k - 1].position) / (t[k + 1] - t[k - 1]);
  };
  const double dt = t[i + 1] - t[i];
  const double w2 = w * w, w3 = w2 * w;
  const glm::dvec3 pos = (2 * w3 - 3 * w2 + 1) * p[i].position + (w3 - 2 * w2 + w) * dt * tangent(i) +
                         (-2 * w3 + 3 * w2) * p[i + 1].position + (w3 - w2) * dt * tangent(i + 1);

  auto q = [&](size_t k) { return p[k].orientation; };
  auto log_to = [&](size_t k, size_t j) { return quat_log(glm::conjugate(q(k)) * q(j)); };  // at q_k, body frame
  auto spin = [&](size_t k) -> glm::dquat {  // T_k
    if (k == 0 || k + 1 == n) return {0.0, 0.0, 0.0, 0.0};
    return (log_to(k, k + 1) - log_to(k, k - 1)) * (1.0 / (t[k + 1] - t[k - 1]));
  };
  // Leaving key k: d/dw at w=0 is q_k (L+ + 2 log(q_k^-1 s)) and must equal q_k T_k dt_k.
  const glm::dquat s_out = q(i) * quat_exp((spin(i) * dt - log_to(i, i + 1)) * 0.5);
  // Entering key k=i+1: d/dw at w=1 is q_k (-L- - 2 log(q_k^-1 s)) and must equal q_k T_k dt_{k-1}.
  const glm::dquat s_in = q(i + 1) * quat_exp((log_to(i + 1, i) + spin(i + 1) * dt) * -0.5);
  const glm::dquat rot =
      glm::slerp(glm::slerp(q(i), q(i + 1), w), glm::slerp(s_out, same_hemisphere(s_in, s_out), w), 2.0 * w * (1.0 - w));
  return {glm::normalize(rot), pos};
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

ScriptFrame Script::at(double frame) const {
  if (keys.empty()) return default_script_frame();
  if (frame <= double(keys.front().first)) return keys.front().second;
  for (size_t i = 1; i < keys.size(); ++i) {
    if (frame >= double(keys[i].first)) continue;
    const auto& [f0, a] = keys[i - 1];
    const auto& [f1, b] = keys[i];
    const double w = (frame - double(f0)) / double(f1 - f0);
    ScriptFrame s = a;  // buttons step at the key
    if (interpolation == Interpolation::kLinear) {
      s.head = lerp_pose(a.head, b.head, w);
      for (int h = 0; h < 2; ++h) {
        s.hands[h].grip = lerp_pose(a.hands[h].grip, b.hands[h].grip, w);
        s.hands[h].aim = lerp_pose(a.hands[h].aim, b.hands[h].aim, w);
      }
      return s;
    }
    std::vector<double> t(keys.size());
    std::vector<Pose> track(keys.size());
    for (size_t k = 0; k < keys.size(); ++k) t[k] = double(keys[k].first);
    auto smooth = [&](auto pose_of) {
      for (size_t k = 0; k < keys.size(); ++k) track[k] = pose_of(keys[k].second);
      return smooth_pose(t, track, i - 1, w);
    };
    s.head = smooth([](const ScriptFrame& f) { return f.head; });
    for (int h = 0; h < 2; ++h) {
      s.hands[h].grip = smooth([h](const ScriptFrame& f) { return f.hands[h].grip; });
      s.hands[h].aim = smooth([h](const ScriptFrame& f) { return f.hands[h].aim; });
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
    if (s.raw.contains("interpolation")) {
      const std::string mode = s.raw["interpolation"].get<std::string>();
      if (mode == "smooth") s.interpolation = Interpolation::kSmooth;
      else if (mode != "linear") {
        error = "\"interpolation\" is \"" + mode + "\"; use \"linear\" or \"smooth\"";
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
