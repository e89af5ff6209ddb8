// 8-bit RGBA images in memory and as PNG files.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include "core/status.h"

namespace vxr {

// Row-major, top row first, 4 bytes per pixel (R, G, B, A).
struct ImageRgba8 {
  uint32_t width = 0;
  uint32_t height = 0;
  std::vector<uint8_t> pixels;

  ImageRgba8() = default;
  ImageRgba8(uint32_t w, uint32_t h) : width(w), height(h), pixels(size_t(w) * h * 4, 0) {}
  uint8_t* at(uint32_t x, uint32_t y) { return &pixels[(size_t(y) * width + x) * 4]; }
  const uint8_t* at(uint32_t x, uint32_t y) const { return &pixels[(size_t(y) * width + x) * 4]; }
};

// Premultiplied RGBA floats, row-major, top row first: a renderer's pixels
// before the one rounding to 8 bits.
struct ImageRgbaF {
  uint32_t width = 0, height = 0;
  std::vector<float> rgba;
};

// Rounds to nearest (v * 255 + 0.5, clamped; NaN -> 0): the one float -> 8-bit
// rule, the GPU's (brick_raycast.comp) and the CPU reference's.
ImageRgba8 to_rgba8(const ImageRgbaF& image);

// Premultiplied RGBA over an opaque black background (what PNG viewers show).
ImageRgba8 over_black(const ImageRgba8& premultiplied);

// How two equally sized 8-bit pixel arrays differ, every byte (R, G, B, A)
// counted, in 8-bit units: what `vxr compare` reports.
struct PixelDifference {
  int max_abs = 0;
  double rmse = 0.0;
};
PixelDifference compare_pixels(const std::vector<uint8_t>& a, const std::vector<uint8_t>& b);

// Writes `path` atomically (temp file then rename): a failed write leaves no
// file that looks like a finished PNG.
Status write_png(const std::string& path, const ImageRgba8& image);
// Reads any 8-bit or 16-bit PNG, converted to RGBA8.
Result<ImageRgba8> read_png(const std::string& path);

}  // namespace vxr
