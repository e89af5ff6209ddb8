#include "render/colormap.h"

#include <algorithm>

namespace vxr {
namespace {

ColormapTable make(glm::vec3 (*f)(float)) {
  ColormapTable t;
  for (int i = 0; i < 256; ++i) t[i] = glm::clamp(f(static_cast<float>(i) / 255.0f), 0.0f, 1.0f);
  return t;
}

glm::vec3 gray(float x) { return glm::vec3(x); }
// Black-red-yellow-white, the classic "hot" of MATLAB/ImageJ (piecewise linear).
glm::vec3 hot(float x) { return {x * 3.0f, x * 3.0f - 1.0f, x * 3.0f - 2.0f}; }

}  // namespace

std::optional<ColormapTable> find_colormap(std::string_view name) {
  if (name == "gray" || name == "grey") return make(gray);
  if (name == "hot") return make(hot);
  return std::nullopt;
}

std::vector<std::string> colormap_names() { return {"gray", "hot"}; }

}  // namespace vxr
