#include "render/colormap.h"

#include <algorithm>
#include <sstream>

#include "assets/assets.h"
#include "volume/channel_display.h"

namespace vxr {
namespace {

ColormapTable make(glm::dvec3 (*f)(double)) {
  ColormapTable t;
  for (int i = 0; i < 256; ++i) t[i] = glm::clamp(f(i / 255.0), 0.0, 1.0);
  return t;
}

ColormapTable hue(glm::dvec3 full) {
  ColormapTable t;
  for (int i = 0; i < 256; ++i) t[i] = full * (i / 255.0);
  return t;
}

// Black-red-yellow-white, the classic "hot" of MATLAB/ImageJ (piecewise linear).
glm::dvec3 hot(double x) { return {x * 3.0, x * 3.0 - 1.0, x * 3.0 - 2.0}; }

// Parses assets/colormaps/<name>.txt: '#' comment lines, then 256 "r g b" lines.
std::optional<ColormapTable> embedded(std::string_view name) {
  auto bytes = assets::find("colormaps/" + std::string(name) + ".txt");
  if (!bytes) return std::nullopt;
  std::istringstream in(std::string(reinterpret_cast<const char*>(bytes->data()), bytes->size()));
  ColormapTable t;
  std::string line;
  int i = 0;
  while (std::getline(in, line) && i < 256) {
    if (line.empty() || line[0] == '#') continue;
    std::istringstream ls(line);
    ls >> t[i].r >> t[i].g >> t[i].b;
    if (!ls) return std::nullopt;
    ++i;
  }
  if (i != 256) return std::nullopt;
  return t;
}

// "#rrggbb" (the '#' required, so a colormap name is never taken for hex).
std::optional<Rgb8> color_hex_name(std::string_view name) {
  return name.size() == 7 && name[0] == '#' ? color_from_hex(name) : std::nullopt;
}

}  // namespace

std::optional<ColormapTable> find_colormap(std::string_view name) {
  if (name == "gray" || name == "grey") return hue({1, 1, 1});
  if (name == "hot") return make(hot);
  if (name == "red") return hue({1, 0, 0});
  if (name == "green") return hue({0, 1, 0});
  if (name == "blue") return hue({0, 0, 1});
  if (name == "cyan") return hue({0, 1, 1});
  if (name == "magenta") return hue({1, 0, 1});
  if (name == "yellow") return hue({1, 1, 0});
  if (auto rgb = color_hex_name(name)) return hue(glm::dvec3((*rgb)[0], (*rgb)[1], (*rgb)[2]) / 255.0);
  if (name == "viridis" || name == "magma" || name == "inferno" || name == "plasma" || name == "turbo")
    return embedded(name);
  return std::nullopt;
}

std::vector<std::string> colormap_names() {
  return {"gray", "viridis", "magma", "inferno", "plasma", "turbo", "hot",
          "red",  "green",   "blue",  "cyan",    "magenta", "yellow"};
}

}  // namespace vxr
