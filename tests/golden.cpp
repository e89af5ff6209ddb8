#include "golden.h"

#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>

namespace vxr::test {

ImageDiff diff_images(const ImageRgba8& a, const ImageRgba8& b, ImageRgba8* diff_out) {
  ImageDiff d;
  if (a.width != b.width || a.height != b.height) {
    d.size_mismatch = true;
    d.max_abs = 255;
    return d;
  }
  if (diff_out) *diff_out = ImageRgba8(a.width, a.height);
  double sq = 0.0;
  for (size_t p = 0; p < a.pixels.size() / 4; ++p) {
    int pix_max = 0;
    for (int c = 0; c < 4; ++c) {
      const int e = std::abs(int(a.pixels[p * 4 + c]) - int(b.pixels[p * 4 + c]));
      pix_max = std::max(pix_max, e);
      sq += double(e) * e;
    }
    d.max_abs = std::max(d.max_abs, pix_max);
    if (pix_max) ++d.differing;
    if (diff_out) {
      // Red where images differ, scaled so 1/255 is visible; grey copy of a otherwise.
      uint8_t* o = &diff_out->pixels[p * 4];
      const uint8_t g = static_cast<uint8_t>(a.pixels[p * 4] / 4);
      o[0] = pix_max ? static_cast<uint8_t>(std::min(255, 64 + pix_max * 32)) : g;
      o[1] = pix_max ? 0 : g;
      o[2] = pix_max ? 0 : g;
      o[3] = 255;
    }
  }
  d.rmse = std::sqrt(sq / static_cast<double>(a.pixels.size()));
  return d;
}

GoldenResult check_golden(const std::string& name, const ImageRgba8& actual, const std::string& fingerprint,
                          int tolerance_other_driver, const std::string& why) {
  namespace fs = std::filesystem;
  const fs::path dir = VXR_GOLDEN_DIR;
  const fs::path png = dir / (name + ".png");
  const fs::path meta = dir / (name + ".json");
  GoldenResult r;

  const char* bless = std::getenv("VXR_BLESS");
  if (bless && bless[0] == '1') {
    Status s = write_png(png.string(), actual);
    nlohmann::json j = {{"fingerprint", fingerprint}, {"tolerance_other_driver", tolerance_other_driver}, {"why", why}};
    std::ofstream(meta) << j.dump(2) << "\n";
    r.passed = s.is_ok();
    r.message = "blessed " + png.string();
    return r;
  }

  auto expected = read_png(png.string());
  if (!expected) {
    r.message = "no golden image " + png.string() + " (run with VXR_BLESS=1 to create it)";
    return r;
  }
  std::ifstream mf(meta);
  nlohmann::json j = nlohmann::json::parse(mf, nullptr, false);
  const std::string golden_fp = j.is_object() ? j.value("fingerprint", "") : "";
  const int tol = j.is_object() ? j.value("tolerance_other_driver", tolerance_other_driver) : tolerance_other_driver;
  r.exact_required = golden_fp == fingerprint;

  ImageRgba8 diff;
  r.diff = diff_images(actual, *expected, &diff);
  r.passed = !r.diff.size_mismatch && (r.exact_required ? r.diff.max_abs == 0 : r.diff.max_abs <= tol);
  r.message = name + ": max_abs " + std::to_string(r.diff.max_abs) + ", rmse " + std::to_string(r.diff.rmse) +
              ", differing pixels " + std::to_string(r.diff.differing) +
              (r.exact_required ? " (same driver: exact match required)"
                                : " (other driver '" + fingerprint + "' vs '" + golden_fp +
                                      "': tolerance " + std::to_string(tol) + ")");
  if (!r.passed) {
    const fs::path out = VXR_TEST_OUT_DIR;
    fs::create_directories(out);
    (void)write_png((out / (name + ".actual.png")).string(), actual);
    if (!r.diff.size_mismatch) (void)write_png((out / (name + ".diff.png")).string(), diff);
    r.message += "; wrote " + (out / (name + ".actual.png")).string();
  }
  return r;
}

bool looks_non_blank(const ImageRgba8& image) {
  if (image.pixels.empty()) return false;
  bool differs = false, lit = false;
  for (size_t p = 0; p < image.pixels.size(); p += 4) {
    for (int c = 0; c < 3; ++c) {
      if (image.pixels[p + c] != image.pixels[c]) differs = true;
      if (image.pixels[p + c] > 16) lit = true;
    }
  }
  return differs && lit;
}

}  // namespace vxr::test
