// ImageJ's TIFF ImageDescription ("ImageJ=1.54f\nimages=27\nslices=27\n...",
// ij/io/FileSaver.getDescriptionString): hyperstack shape and calibration.
#pragma once

#include <cstdint>
#include <optional>
#include <string>
#include <string_view>

namespace vxr {

struct ImageJMetadata {
  uint32_t images = 1;    // planes in the file (may exceed the IFD count for > 4 GB files)
  uint32_t channels = 1;
  uint32_t slices = 1;
  uint32_t frames = 1;
  double spacing = 1.0;   // z step; ImageJ omits it when 0 or 1
  std::string unit;       // as written ("micron", "\u00B5m", ...); empty when uncalibrated
};

// nullopt when the text does not start with "ImageJ=".
std::optional<ImageJMetadata> parse_imagej_description(std::string_view text);

}  // namespace vxr
