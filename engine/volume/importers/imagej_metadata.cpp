#include "volume/importers/imagej_metadata.h"

#include <charconv>
#include <cstdlib>

namespace vxr {

std::optional<ImageJMetadata> parse_imagej_description(std::string_view text) {
  if (text.substr(0, 7) != "ImageJ=") return std::nullopt;
  ImageJMetadata m;
  bool has_images = false;
  size_t pos = 0;
  while (pos < text.size()) {
    size_t end = text.find_first_of("\n\r", pos);
    if (end == std::string_view::npos) end = text.size();
    const std::string_view line = text.substr(pos, end - pos);
    pos = end + 1;
    const size_t eq = line.find('=');
    if (eq == std::string_view::npos) continue;
    const std::string_view key = line.substr(0, eq);
    const std::string value(line.substr(eq + 1));
    auto as_count = [&](uint32_t& out) {
      char* e = nullptr;
      const long v = std::strtol(value.c_str(), &e, 10);
      if (e != value.c_str() && v > 0 && v < (1l << 31)) out = uint32_t(v);
    };
    if (key == "images") as_count(m.images), has_images = true;
    else if (key == "channels") as_count(m.channels);
    else if (key == "slices") as_count(m.slices);
    else if (key == "frames") as_count(m.frames);
    else if (key == "unit") m.unit = value;
    else if (key == "spacing") {
      char* e = nullptr;
      const double v = std::strtod(value.c_str(), &e);
      if (e != value.c_str() && v > 0) m.spacing = v;
    }
  }
  if (!has_images) m.images = m.channels * m.slices * m.frames;
  return m;
}

}  // namespace vxr
