#include "volume/importers/picture_decoder.h"

#include <png.h>
#include <setjmp.h>

#include <cstdio>
#include <memory>
#include <cstring>
#include <filesystem>
// jpeglib.h needs size_t and FILE first.
#include <jpeglib.h>

#include "core/checked_math.h"
#include "volume/importers/import_limits.h"

namespace vxr {
namespace {

struct FileCloser {
  void operator()(FILE* f) const {
    if (f) std::fclose(f);
  }
};
using FilePtr = std::unique_ptr<FILE, FileCloser>;

struct JpegError {
  jpeg_error_mgr mgr;
  jmp_buf jump;
  char message[JMSG_LENGTH_MAX] = {0};
};

void jpeg_error_exit(j_common_ptr cinfo) {
  auto* err = reinterpret_cast<JpegError*>(cinfo->err);
  (*cinfo->err->format_message)(cinfo, err->message);
  longjmp(err->jump, 1);
}
void jpeg_silent(j_common_ptr, int) {}

struct PngState {
  char message[256] = {0};
};
void png_error_fn(png_structp png, png_const_charp msg) {
  auto* st = static_cast<PngState*>(png_get_error_ptr(png));
  std::snprintf(st->message, sizeof st->message, "%s", msg);
  png_longjmp(png, 1);
}
void png_warning_fn(png_structp, png_const_charp) {}

// A picture's decoded size comes from its header: believe it only as far as
// the file's bytes can expand (deflate ~1032x; JPEG generously 2^16x) and as
// far as the import budget goes (the slice cache holds a few pictures), so a
// 100-byte PNG claiming 10^9 x 10^9 pixels is an error, not a bad_alloc.
Status check_picture_size(const std::string& path, const PictureHeader& h, uint64_t max_expansion) {
  std::error_code ec;
  const uint64_t file_bytes = std::filesystem::file_size(path, ec);
  const auto bytes = checked_product({h.width, h.height, h.channels, dtype_bytes(h.dtype)});
  const auto affordable = checked_product({ec ? 0 : file_bytes, max_expansion});
  const std::string what = path + ": " + std::to_string(h.width) + " x " + std::to_string(h.height) + " pixels";
  if (!bytes || (affordable && *bytes > *affordable))
    return corrupt(what + " cannot come from a " + std::to_string(file_bytes) + "-byte file; the file is damaged");
  if (*bytes > import_memory_budget() / 2)
    return out_of_range(what + " need " + std::to_string(*bytes >> 20) + " MiB decoded, more than half the import "
                        "memory budget (" + std::to_string(import_memory_budget() >> 20) + " MiB); raise --memory");
  return Status::ok();
}

// One decoding pass for PNG; header_only stops after png_read_update_info.
Status run_png(const std::string& path, PictureHeader* header, std::vector<uint8_t>* out) {
  FilePtr f(std::fopen(path.c_str(), "rb"));
  if (!f) return not_found(path + ": cannot open");
  PngState st;
  png_structp png = png_create_read_struct(PNG_LIBPNG_VER_STRING, &st, png_error_fn, png_warning_fn);
  png_infop info = png ? png_create_info_struct(png) : nullptr;
  if (!png || !info) {
    png_destroy_read_struct(&png, &info, nullptr);
    return internal_error("libpng: out of memory");
  }
  std::vector<png_bytep> rows;
  if (setjmp(png_jmpbuf(png))) {
    png_destroy_read_struct(&png, &info, nullptr);
    return corrupt(path + ": cannot decode PNG (" + st.message + ")");
  }
  png_init_io(png, f.get());
  png_set_user_limits(png, 1u << 30, 1u << 30);
  png_read_info(png, info);
  const int color = png_get_color_type(png, info);
  const int depth = png_get_bit_depth(png, info);
  if (color == PNG_COLOR_TYPE_PALETTE) png_set_palette_to_rgb(png);
  if (color == PNG_COLOR_TYPE_GRAY && depth < 8) png_set_expand_gray_1_2_4_to_8(png);
  if (png_get_valid(png, info, PNG_INFO_tRNS)) png_set_tRNS_to_alpha(png);
  if (depth == 16) png_set_swap(png);  // PNG is big-endian; we want native (little)
  png_set_interlace_handling(png);
  png_read_update_info(png, info);
  PictureHeader h;
  h.format = PictureFormat::kPng;
  h.width = png_get_image_width(png, info);
  h.height = png_get_image_height(png, info);
  h.channels = png_get_channels(png, info);
  h.dtype = png_get_bit_depth(png, info) == 16 ? DType::kU16 : DType::kU8;
  if (Status s = check_picture_size(path, h, 1100); !s) {
    png_destroy_read_struct(&png, &info, nullptr);
    return s;
  }
  if (header) *header = h;
  if (out) {
    const size_t row_bytes = png_get_rowbytes(png, info);
    if (row_bytes != size_t(h.width) * h.channels * dtype_bytes(h.dtype)) {
      png_destroy_read_struct(&png, &info, nullptr);
      return internal_error(path + ": unexpected PNG row size");
    }
    out->resize(row_bytes * h.height);
    rows.resize(h.height);
    for (uint32_t y = 0; y < h.height; ++y) rows[y] = out->data() + row_bytes * y;
    png_read_image(png, rows.data());
    png_read_end(png, nullptr);
  }
  png_destroy_read_struct(&png, &info, nullptr);
  return Status::ok();
}

Status run_jpeg(const std::string& path, PictureHeader* header, std::vector<uint8_t>* out) {
  FilePtr f(std::fopen(path.c_str(), "rb"));
  if (!f) return not_found(path + ": cannot open");
  jpeg_decompress_struct cinfo;
  JpegError err;
  cinfo.err = jpeg_std_error(&err.mgr);
  err.mgr.error_exit = jpeg_error_exit;
  err.mgr.emit_message = jpeg_silent;
  if (setjmp(err.jump)) {
    jpeg_destroy_decompress(&cinfo);
    return corrupt(path + ": cannot decode JPEG (" + err.message + ")");
  }
  jpeg_create_decompress(&cinfo);
  jpeg_stdio_src(&cinfo, f.get());
  jpeg_read_header(&cinfo, TRUE);
  if (cinfo.jpeg_color_space == JCS_CMYK || cinfo.jpeg_color_space == JCS_YCCK) {
    jpeg_destroy_decompress(&cinfo);
    return unsupported(path + ": CMYK JPEG is not supported; save it as RGB or greyscale");
  }
  cinfo.out_color_space = cinfo.num_components == 1 ? JCS_GRAYSCALE : JCS_RGB;
  PictureHeader h;
  h.format = PictureFormat::kJpeg;
  h.width = cinfo.image_width;
  h.height = cinfo.image_height;
  h.channels = cinfo.num_components == 1 ? 1 : 3;
  h.dtype = DType::kU8;
  if (Status s = check_picture_size(path, h, uint64_t(1) << 16); !s) {
    jpeg_destroy_decompress(&cinfo);
    return s;
  }
  if (header) *header = h;
  if (out) {
    jpeg_start_decompress(&cinfo);
    const size_t row_bytes = size_t(h.width) * h.channels;
    out->resize(row_bytes * h.height);
    while (cinfo.output_scanline < cinfo.output_height) {
      JSAMPROW row = out->data() + row_bytes * cinfo.output_scanline;
      jpeg_read_scanlines(&cinfo, &row, 1);
    }
    jpeg_finish_decompress(&cinfo);
  }
  jpeg_destroy_decompress(&cinfo);
  return Status::ok();
}

}  // namespace

Result<PictureHeader> probe_picture(const std::string& path) {
  FilePtr f(std::fopen(path.c_str(), "rb"));
  if (!f) return not_found(path + ": cannot open");
  unsigned char m[8] = {0};
  const size_t n = std::fread(m, 1, 8, f.get());
  f.reset();
  PictureHeader h;
  if (n == 8 && std::memcmp(m, "\x89PNG\r\n\x1a\n", 8) == 0) {
    VXR_RETURN_IF_ERROR(run_png(path, &h, nullptr));
    return h;
  }
  if (n >= 3 && m[0] == 0xFF && m[1] == 0xD8 && m[2] == 0xFF) {
    VXR_RETURN_IF_ERROR(run_jpeg(path, &h, nullptr));
    return h;
  }
  return unsupported(path + ": not a PNG or JPEG file");
}

Status decode_picture(const std::string& path, const PictureHeader& header, std::vector<uint8_t>& out) {
  PictureHeader now;
  VXR_RETURN_IF_ERROR(header.format == PictureFormat::kPng ? run_png(path, &now, &out) : run_jpeg(path, &now, &out));
  if (now.width != header.width || now.height != header.height || now.channels != header.channels ||
      now.dtype != header.dtype)
    return corrupt(path + ": changed since the import started");
  return Status::ok();
}

}  // namespace vxr
