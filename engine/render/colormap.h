// Colour lookup tables by name.
#pragma once

#include <array>
#include <glm/glm.hpp>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

namespace vxr {

using ColormapTable = std::array<glm::vec3, 256>;

// nullopt for an unknown name.
std::optional<ColormapTable> find_colormap(std::string_view name);
std::vector<std::string> colormap_names();

}  // namespace vxr
