// Colour lookup tables by name: 256 entries, entry i at x = i / 255.
//
// viridis, magma, inferno, plasma and turbo are matplotlib's published tables
// (assets/colormaps/, licences in LICENSE.md there), embedded in the binary;
// gray, hot and the single-hue maps (black to the full hue) are generated;
// "#rrggbb" names the single hue of that colour (a file's channel colour).
#pragma once

#include <array>
#include <glm/glm.hpp>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

namespace vxr {

using ColormapTable = std::array<glm::dvec3, 256>;

// nullopt for an unknown name.
std::optional<ColormapTable> find_colormap(std::string_view name);
std::vector<std::string> colormap_names();

}  // namespace vxr
