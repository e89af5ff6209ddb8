#include "volume/importers/units.h"

#include <cctype>

namespace vxr {

std::optional<LengthUnit> parse_length_unit(std::string_view s) {
  while (!s.empty() && std::isspace(static_cast<unsigned char>(s.front()))) s.remove_prefix(1);
  while (!s.empty() && std::isspace(static_cast<unsigned char>(s.back()))) s.remove_suffix(1);
  // Micro signs first: they are not ASCII, so compare bytes.
  if (s == "\xC2\xB5m" || s == "\xCE\xBCm" || s == "\xB5m" || s == "\\u00B5m" || s == "\\u00b5m" || s == "\\u03BCm")
    return LengthUnit{"um", 1.0};
  if (s == "\xC3\x85" || s == "\xC5" || s == "\xE2\x84\xAB") return LengthUnit{"A", 1e-4};  // Å
  std::string l;
  for (char c : s) l += static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
  if (l.size() > 1 && l.back() == 's' && l != "ms") l.pop_back();  // plural
  struct Entry {
    const char* spelling;
    const char* name;
    double um;
  };
  static const Entry kUnits[] = {
      {"um", "um", 1.0},          {"micron", "um", 1.0},       {"micrometer", "um", 1.0},
      {"micrometre", "um", 1.0},  {"nm", "nm", 1e-3},          {"nanometer", "nm", 1e-3},
      {"nanometre", "nm", 1e-3},  {"mm", "mm", 1e3},           {"millimeter", "mm", 1e3},
      {"millimetre", "mm", 1e3},  {"cm", "cm", 1e4},           {"centimeter", "cm", 1e4},
      {"centimetre", "cm", 1e4},  {"m", "m", 1e6},             {"meter", "m", 1e6},
      {"metre", "m", 1e6},        {"pm", "pm", 1e-6},          {"picometer", "pm", 1e-6},
      {"picometre", "pm", 1e-6},  {"a", "A", 1e-4},            {"angstrom", "A", 1e-4},
      {"in", "in", 25400.0},      {"inch", "in", 25400.0},     {"inche", "in", 25400.0},
      {"km", "km", 1e9},          {"kilometer", "km", 1e9},    {"kilometre", "km", 1e9},
  };
  for (const Entry& e : kUnits)
    if (l == e.spelling) return LengthUnit{e.name, e.um};
  return std::nullopt;
}

}  // namespace vxr
