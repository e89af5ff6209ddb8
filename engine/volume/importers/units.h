// Length units as microscopy files spell them (ImageJ, OME, Imaris).
#pragma once

#include <optional>
#include <string>
#include <string_view>

namespace vxr {

struct LengthUnit {
  std::string name;  // canonical short name: "um", "nm", "mm", ...
  double um = 1.0;   // micrometres per unit
};

// "um", "µm" (UTF-8 or Latin-1), "μm", "\u00B5m" (literal escape), "micron",
// "micrometer", "micrometre", "nm", "nanometer", "mm", "cm", "m", "Å",
// "angstrom", "pm", "inch", ... Case-insensitive for words; nullopt when not a
// length (e.g. "pixel", "").
std::optional<LengthUnit> parse_length_unit(std::string_view spelling);

}  // namespace vxr
