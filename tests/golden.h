// Golden-image comparison.
//
// golden_images/<name>.png is the expected image; <name>.json beside it holds
// the driver fingerprint it was made with, the tolerance for other drivers and
// why the image is right. Same fingerprint: bit-for-bit. Other fingerprint:
// max-abs difference <= tolerance (8-bit units). On failure the actual image
// and a diff go to the build folder (test_out/). VXR_BLESS=1 rewrites goldens.
#pragma once

#include <string>

#include "core/image.h"

namespace vxr::test {

struct ImageDiff {
  int max_abs = 0;       // largest channel difference, 0..255
  double rmse = 0.0;     // over all channels, 8-bit units
  uint64_t differing = 0;  // pixels with any channel different
  bool size_mismatch = false;
};

ImageDiff diff_images(const ImageRgba8& a, const ImageRgba8& b, ImageRgba8* diff_out = nullptr);

struct GoldenResult {
  bool passed = false;
  bool exact_required = false;  // the fingerprint matched
  ImageDiff diff;
  std::string message;
};

// `why`: one sentence on why this picture is right (stored when blessing).
GoldenResult check_golden(const std::string& name, const ImageRgba8& actual, const std::string& fingerprint,
                          int tolerance_other_driver, const std::string& why);

// A picture that is not blank: not all one colour, and some pixels lit.
bool looks_non_blank(const ImageRgba8& image);

}  // namespace vxr::test
