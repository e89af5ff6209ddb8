#include "annotate/tool_script.h"

#include <algorithm>
#include <cmath>
#include <nlohmann/json.hpp>

namespace vxr::annotate {
namespace {

using nlohmann::json;

std::optional<std::vector<double>> numbers(const json& j, size_t n) {
  if (!j.is_array() || j.size() != n) return std::nullopt;
  std::vector<double> v;
  for (const json& x : j) {
    if (!x.is_number()) return std::nullopt;
    const double d = x.get<double>();
    if (!std::isfinite(d)) return std::nullopt;
    v.push_back(d);
  }
  return v;
}

}  // namespace

Result<std::vector<ToolStep>> parse_tool_script(const std::string& text, const std::string& source) {
  json root;
  try {
    root = json::parse(text);
  } catch (const json::exception& e) {
    return invalid_argument(source + ": not JSON (" + std::string(e.what()) + ")");
  }
  if (!root.is_object() || !root.contains("events") || !root["events"].is_array())
    return invalid_argument(source + ": needs an \"events\" array");
  std::vector<ToolStep> steps;
  for (size_t i = 0; i < root["events"].size(); ++i) {
    const json& e = root["events"][i];
    const std::string where = source + ": event " + std::to_string(i);
    if (!e.is_object()) return invalid_argument(where + ": is not an object");
    ToolStep s;
    s.index = i;
    for (const auto& [key, value] : e.items()) {
      if (key == "tool") {
        s.tool = value.is_string() ? tool_from_name(value.get<std::string>()) : std::nullopt;
        if (!s.tool) return invalid_argument(where + ": \"tool\" must be count, measure, trace, track or roi");
      } else if (key == "class") {
        if (!value.is_string() || value.get<std::string>().empty())
          return invalid_argument(where + ": \"class\" must be a non-empty string");
        s.cls = value.get<std::string>();
      } else if (key == "color") {
        auto c = numbers(value, 4);
        if (!c || *std::min_element(c->begin(), c->end()) < 0 || *std::max_element(c->begin(), c->end()) > 1)
          return invalid_argument(where + ": \"color\" must be [r, g, b, a] in 0..1");
        s.color = std::array<double, 4>{(*c)[0], (*c)[1], (*c)[2], (*c)[3]};
      } else if (key == "timepoint") {
        if (!value.is_number_unsigned() || value.get<uint64_t>() > 0xffffffffull)
          return invalid_argument(where + ": \"timepoint\" must be a whole number >= 0");
        s.timepoint = value.get<uint32_t>();
      } else if (key == "radius") {
        if (!value.is_number() || !(value.get<double>() >= 0) || !std::isfinite(value.get<double>()))
          return invalid_argument(where + ": \"radius\" must be a number >= 0");
        s.radius = value.get<double>();
      } else if (auto action = tool_action_from_name(key)) {
        if (s.action) return invalid_argument(where + ": holds two actions; give one per event");
        s.action = action;
        if (*action != ToolAction::kFinish) {
          auto p = numbers(value, 3);
          if (!p) return invalid_argument(where + ": \"" + key + "\" needs the cursor [x, y, z] in voxels");
          s.cursor = {(*p)[0], (*p)[1], (*p)[2]};
        }
      } else {
        return invalid_argument(where + ": unknown key \"" + key +
                                "\" (tool, class, color, timepoint, radius, press, move, release, pick, remove, finish)");
      }
    }
    steps.push_back(std::move(s));
  }
  return steps;
}

Status run_tool_script(ToolPalette& palette, const std::vector<ToolStep>& steps,
                       const std::function<void(const ToolStep&, const ToolLiveState&)>& after) {
  uint32_t timepoint = 0;
  std::string cls = "default";
  std::array<double, 4> color{1, 1, 0, 1};
  for (const ToolStep& s : steps) {
    if (s.tool) palette.select_tool(*s.tool);
    if (s.cls || s.color) {
      if (s.cls) cls = *s.cls;
      if (s.color) color = *s.color;
      palette.set_class(cls, color);
    }
    if (s.timepoint) timepoint = *s.timepoint;
    if (s.radius) palette.set_node_radius(*s.radius);
    if (!s.action) continue;
    Status st = palette.apply(ToolEvent{*s.action, s.cursor, timepoint});
    if (!st) return Status(st.code(), "event " + std::to_string(s.index) + " (" + tool_name(palette.tool()) + "): " +
                                          st.message());
    if (after) after(s, palette.live());
  }
  return Status::ok();
}

}  // namespace vxr::annotate
