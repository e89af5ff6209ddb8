#include "core/image.h"

#include "core/output_file.h"

#include <png.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <memory>

namespace vxr {
namespace {

struct FileCloser {
  void operator()(FILE* f) const {
    if (f) std::fclose(f);
  }
};
using File = std::unique_ptr<FILE, FileCloser>;

}  // namespace

Status write_png(const std::string& path, const ImageRgba8& image) {
  if (image.width == 0 || image.height == 0) return invalid_argument(path + ": refusing to write an empty image");
  VXR_ASSIGN_OR_RETURN(TempFile tmp, TempFile::create_beside(path));
  volatile bool ok = false;  // volatile: survives png's longjmp
  {
    File f(::fdopen(tmp.release_fd(), "wb"));
    if (!f) return io_error(path + ": cannot open for writing");
    png_structp png = png_create_write_struct(PNG_LIBPNG_VER_STRING, nullptr, nullptr, nullptr);
    png_infop info = png ? png_create_info_struct(png) : nullptr;
    if (png && info && !setjmp(png_jmpbuf(png))) {
      png_init_io(png, f.get());
      png_set_IHDR(png, info, image.width, image.height, 8, PNG_COLOR_TYPE_RGBA, PNG_INTERLACE_NONE,
                   PNG_COMPRESSION_TYPE_DEFAULT, PNG_FILTER_TYPE_DEFAULT);
      png_write_info(png, info);
      for (uint32_t y = 0; y < image.height; ++y)
        png_write_row(png, const_cast<png_bytep>(image.at(0, y)));
      png_write_end(png, nullptr);
      ok = std::fflush(f.get()) == 0;
    }
    png_destroy_write_struct(&png, &info);
  }
  if (!ok) return io_error(path + ": PNG write failed (disk full?)");
  return tmp.commit();  // the temp file is removed if this fails
}

Result<ImageRgba8> read_png(const std::string& path) {
  VXR_RETURN_IF_ERROR(check_input(path));  // a FIFO would block fopen forever
  File f(std::fopen(path.c_str(), "rb"));
  if (!f) return not_found(path + ": cannot open");
  unsigned char sig[8];
  if (std::fread(sig, 1, 8, f.get()) != 8 || png_sig_cmp(sig, 0, 8)) return corrupt(path + ": not a PNG file");
  png_structp png = png_create_read_struct(PNG_LIBPNG_VER_STRING, nullptr, nullptr, nullptr);
  png_infop info = png ? png_create_info_struct(png) : nullptr;
  ImageRgba8 img;
  volatile bool ok = false;  // volatile: survives png's longjmp
  if (png && info && !setjmp(png_jmpbuf(png))) {
    png_init_io(png, f.get());
    png_set_sig_bytes(png, 8);
    png_read_info(png, info);
    png_set_expand(png);
    png_set_strip_16(png);
    png_set_gray_to_rgb(png);
    png_set_add_alpha(png, 0xff, PNG_FILLER_AFTER);
    png_read_update_info(png, info);
    const uint32_t w = png_get_image_width(png, info), h = png_get_image_height(png, info);
    if (w == 0 || h == 0 || uint64_t(w) * h > (uint64_t(1) << 28)) {
      png_destroy_read_struct(&png, &info, nullptr);
      return corrupt(path + ": unreasonable PNG size");
    }
    img = ImageRgba8(w, h);
    std::vector<png_bytep> rows(h);
    for (uint32_t y = 0; y < h; ++y) rows[y] = img.at(0, y);
    png_read_image(png, rows.data());
    ok = true;
  }
  png_destroy_read_struct(&png, &info, nullptr);
  if (!ok) return corrupt(path + ": PNG decode failed");
  return img;
}

ImageRgba8 to_rgba8(const ImageRgbaF& f) {
  ImageRgba8 img(f.width, f.height);
  for (size_t i = 0; i < f.rgba.size(); ++i) {
    const float v = f.rgba[i];
    const float c = v > 0.0f ? (v < 1.0f ? v : 1.0f) : 0.0f;  // NaN -> 0
    img.pixels[i] = static_cast<uint8_t>(c * 255.0f + 0.5f);
  }
  return img;
}

ImageRgba8 over_black(const ImageRgba8& premultiplied) {
  ImageRgba8 out = premultiplied;
  for (size_t i = 3; i < out.pixels.size(); i += 4) out.pixels[i] = 255;
  return out;
}

PixelDifference compare_pixels(const std::vector<uint8_t>& a, const std::vector<uint8_t>& b) {
  PixelDifference out;
  const size_t n = std::min(a.size(), b.size());
  if (n == 0) return out;
  double sq = 0.0;
  for (size_t i = 0; i < n; ++i) {
    const int d = std::abs(int(a[i]) - int(b[i]));
    out.max_abs = std::max(out.max_abs, d);
    sq += double(d) * d;
  }
  out.rmse = std::sqrt(sq / double(n));
  return out;
}

}  // namespace vxr
