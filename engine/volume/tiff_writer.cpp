#include "volume/tiff_writer.h"

#include <fcntl.h>
#include <tiffio.h>
#include <unistd.h>

#include <algorithm>
#include <cstdarg>
#include <cstdio>
#include <filesystem>
#include <sstream>

namespace vxr {

struct TiffStackWriter::Sink {
  std::string first_error;
};

namespace {

int on_error(TIFF*, void* user, const char*, const char* fmt, va_list ap) {
  auto* sink = static_cast<TiffStackWriter::Sink*>(user);
  if (sink && sink->first_error.empty()) {
    char buf[512];
    std::vsnprintf(buf, sizeof buf, fmt, ap);
    sink->first_error = buf;
  }
  return 1;
}
int on_warning(TIFF*, void*, const char*, const char*, va_list) { return 1; }

std::string number(double v) {
  std::ostringstream s;
  s.precision(17);
  s << v;
  return s.str();
}

}  // namespace

bool needs_big_tiff(const VolumeInfo& info) {
  const uint64_t bytes = info.voxels_per_volume() * dtype_bytes(info.dtype) * info.channels * info.timepoints;
  const uint64_t pages = info.dims[2] * info.channels * info.timepoints;
  // Headroom for the directories (about 200 bytes a page) and the description.
  return bytes + pages * 512 + (1u << 20) > (uint64_t(1) << 32) - 1;
}

Result<std::unique_ptr<TiffStackWriter>> TiffStackWriter::create(const std::string& path, const VolumeInfo& info,
                                                                 bool force_bigtiff, TiffCompression compression) {
  if (!info.dims[0] || !info.dims[1] || !info.dims[2] || info.dims[0] > 0xffffffffu || info.dims[1] > 0xffffffffu)
    return invalid_argument(path + ": cannot write a TIFF page of " + std::to_string(info.dims[0]) + " x " +
                            std::to_string(info.dims[1]) + " voxels");
  std::unique_ptr<TiffStackWriter> w(new TiffStackWriter());
  w->path_ = path;
  w->info_ = info;
  w->big_ = force_bigtiff || needs_big_tiff(info);  // compressed data is never larger than this assumes
  w->compression_ = compression;
  w->sink_ = std::make_unique<Sink>();
  std::error_code ec;
  const std::filesystem::path parent = std::filesystem::absolute(path, ec).parent_path();
  if (!std::filesystem::is_directory(parent, ec))
    return not_found(path + ": folder " + parent.string() + " does not exist");
  VXR_ASSIGN_OR_RETURN(w->partial_, TempFile::create_beside(path));
  TIFFOpenOptions* opts = TIFFOpenOptionsAlloc();
  TIFFOpenOptionsSetErrorHandlerExtR(opts, on_error, w->sink_.get());
  TIFFOpenOptionsSetWarningHandlerExtR(opts, on_warning, w->sink_.get());
  // libtiff owns (and closes) the descriptor from here on.
  w->tif_ = TIFFFdOpenExt(w->partial_.release_fd(), w->partial_.path().c_str(), w->big_ ? "w8" : "w", opts);
  TIFFOpenOptionsFree(opts);
  if (!w->tif_) return io_error(path + ": cannot create " + w->partial_.path() + " (" + w->sink_->first_error + ")");

  // ImageJ hyperstack description (ij/io/FileSaver.getDescriptionString).
  const uint64_t images = info.dims[2] * info.channels * info.timepoints;
  std::string d = "ImageJ=1.54f\nimages=" + std::to_string(images) + "\n";
  if (info.channels > 1) d += "channels=" + std::to_string(info.channels) + "\n";
  if (info.dims[2] > 1) d += "slices=" + std::to_string(info.dims[2]) + "\n";
  if (info.timepoints > 1) d += "frames=" + std::to_string(info.timepoints) + "\n";
  if (info.channels > 1 || info.timepoints > 1) d += "hyperstack=true\n";
  if (info.unit != "px" && !info.unit.empty()) {
    d += "unit=" + (info.unit == "um" ? std::string("micron") : info.unit) + "\n";
    if (info.voxel_size[2] != 1.0) d += "spacing=" + number(info.voxel_size[2]) + "\n";
  }
  d += "loop=false\n";
  w->description_ = d;
  return w;
}

// partial_ (a TempFile) removes the unfinished file after libtiff closed it.
TiffStackWriter::~TiffStackWriter() {
  if (tif_) TIFFClose(tif_);
}

Status TiffStackWriter::write_page(const uint8_t* voxels) {
  const uint64_t total = info_.dims[2] * info_.channels * info_.timepoints;
  if (!tif_ || pages_ >= total) return internal_error(path_ + ": more pages written than the stack holds");
  const uint32_t w = uint32_t(info_.dims[0]), h = uint32_t(info_.dims[1]);
  const uint32_t bpv = dtype_bytes(info_.dtype);
  const uint16_t format = info_.dtype == DType::kF32                                  ? SAMPLEFORMAT_IEEEFP
                          : (info_.dtype == DType::kI8 || info_.dtype == DType::kI16 ||
                             info_.dtype == DType::kI32)                                ? SAMPLEFORMAT_INT
                                                                                        : SAMPLEFORMAT_UINT;
  TIFFSetField(tif_, TIFFTAG_IMAGEWIDTH, w);
  TIFFSetField(tif_, TIFFTAG_IMAGELENGTH, h);
  TIFFSetField(tif_, TIFFTAG_BITSPERSAMPLE, uint16_t(bpv * 8));
  TIFFSetField(tif_, TIFFTAG_SAMPLESPERPIXEL, uint16_t(1));
  TIFFSetField(tif_, TIFFTAG_SAMPLEFORMAT, format);
  TIFFSetField(tif_, TIFFTAG_PHOTOMETRIC, PHOTOMETRIC_MINISBLACK);
  TIFFSetField(tif_, TIFFTAG_PLANARCONFIG, PLANARCONFIG_CONTIG);
  switch (compression_) {
    case TiffCompression::kNone: TIFFSetField(tif_, TIFFTAG_COMPRESSION, COMPRESSION_NONE); break;
    case TiffCompression::kLzw: TIFFSetField(tif_, TIFFTAG_COMPRESSION, COMPRESSION_LZW); break;
    case TiffCompression::kDeflate: TIFFSetField(tif_, TIFFTAG_COMPRESSION, COMPRESSION_ADOBE_DEFLATE); break;
  }
  if (compression_ != TiffCompression::kNone && format != SAMPLEFORMAT_IEEEFP)
    TIFFSetField(tif_, TIFFTAG_PREDICTOR, PREDICTOR_HORIZONTAL);
  if (pages_ == 0) TIFFSetField(tif_, TIFFTAG_IMAGEDESCRIPTION, description_.c_str());
  if (info_.unit != "px" && info_.voxel_size[0] > 0 && info_.voxel_size[1] > 0) {
    TIFFSetField(tif_, TIFFTAG_XRESOLUTION, float(1.0 / info_.voxel_size[0]));
    TIFFSetField(tif_, TIFFTAG_YRESOLUTION, float(1.0 / info_.voxel_size[1]));
    TIFFSetField(tif_, TIFFTAG_RESOLUTIONUNIT, RESUNIT_NONE);
  }
  // Strips of about 256 KB: small enough for partial reads, few enough for a small index.
  const uint64_t row = uint64_t(w) * bpv;
  const uint32_t rows_per_strip = uint32_t(std::clamp<uint64_t>((256u << 10) / std::max<uint64_t>(row, 1), 1, h));
  TIFFSetField(tif_, TIFFTAG_ROWSPERSTRIP, rows_per_strip);
  for (uint32_t y = 0, s = 0; y < h; y += rows_per_strip, ++s) {
    const uint32_t n = std::min(rows_per_strip, h - y);
    uint8_t* strip = const_cast<uint8_t*>(voxels + row * y);
    if (compression_ != TiffCompression::kNone) {  // the predictor differences the buffer in place: use a copy
      scratch_.assign(strip, strip + row * n);
      strip = scratch_.data();
    }
    if (TIFFWriteEncodedStrip(tif_, s, strip, tmsize_t(row * n)) < 0)
      return io_error(path_ + ": cannot write page " + std::to_string(pages_) + " (" + sink_->first_error + ")");
  }
  if (!TIFFWriteDirectory(tif_))
    return io_error(path_ + ": cannot write page " + std::to_string(pages_) + " (" + sink_->first_error + ")");
  ++pages_;
  return Status::ok();
}

Status TiffStackWriter::finish() {
  const uint64_t total = info_.dims[2] * info_.channels * info_.timepoints;
  if (pages_ != total)
    return internal_error(path_ + ": " + std::to_string(pages_) + " of " + std::to_string(total) + " pages written");
  TIFFClose(tif_);
  tif_ = nullptr;
  if (!sink_->first_error.empty()) return io_error(path_ + ": " + sink_->first_error);
  VXR_RETURN_IF_ERROR(partial_.commit());
  finished_ = true;
  return Status::ok();
}

}  // namespace vxr
