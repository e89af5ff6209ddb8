// PNG and JPEG pictures for slice-series import: header probing (cheap, for
// size checks across thousands of files) and full decoding with the samples
// kept as stored (no gamma or colour conversion; 16-bit PNG stays 16-bit).
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include "core/status.h"
#include "volume/dtype.h"

namespace vxr {

enum class PictureFormat { kPng, kJpeg };

struct PictureHeader {
  PictureFormat format = PictureFormat::kPng;
  uint32_t width = 0, height = 0;
  uint32_t channels = 1;  // grey 1, grey+alpha 2, RGB 3, RGBA 4 (palette PNG: 3 or 4)
  DType dtype = DType::kU8;
};

// Sniffs the magic bytes; kUnsupported when `path` is neither PNG nor JPEG.
Result<PictureHeader> probe_picture(const std::string& path);

// Decodes the whole picture: interleaved samples, rows top first, native byte order.
Status decode_picture(const std::string& path, const PictureHeader& header, std::vector<uint8_t>& out);

}  // namespace vxr
