// Writes a multi-page TIFF that ImageJ/Fiji, tifffile and our own importer
// read back: one page per (c, z, t) plane in ImageJ hyperstack order (XYCZT,
// channel fastest), uncompressed, with ImageJ metadata (channels, slices,
// frames, unit, spacing) and XResolution = 1 / pixel size. Uncompressed
// unless asked (TiffCompression).
//
// The file appears atomically: pages go to "<path>.partial" and are renamed
// over `path` only by finish(); a writer destroyed unfinished removes its
// partial file, so a failed export never leaves a file that looks complete.
// BigTIFF is used when the data would not fit a classic TIFF (4 GB).
#pragma once

#include <array>
#include <cstdint>
#include <memory>
#include <string>
#include <vector>

#include "core/output_file.h"
#include "core/status.h"
#include "volume/volume_info.h"

typedef struct tiff TIFF;

namespace vxr {

// Strip compression. LZW and Deflate use the horizontal-differencing
// predictor for integer data (what Fiji and tifffile write for microscopy).
enum class TiffCompression { kNone, kLzw, kDeflate };

class TiffStackWriter {
 public:
  // info: dims of each page (x, y) and the z count, dtype, channels,
  // timepoints, voxel size and unit. force_bigtiff: for tests.
  static Result<std::unique_ptr<TiffStackWriter>> create(const std::string& path, const VolumeInfo& info,
                                                          bool force_bigtiff = false,
                                                          TiffCompression compression = TiffCompression::kNone);
  ~TiffStackWriter();
  TiffStackWriter(const TiffStackWriter&) = delete;
  TiffStackWriter& operator=(const TiffStackWriter&) = delete;

  // Appends the next page: dims.x * dims.y voxels, x fastest, native byte order.
  // Pages must come in XYCZT order (for t, for z, for c).
  Status write_page(const uint8_t* voxels);
  // Checks every page was written, closes, syncs and renames into place.
  Status finish();

  bool big_tiff() const { return big_; }
  uint64_t pages_written() const { return pages_; }

  struct Sink;

 private:
  TiffStackWriter() = default;
  std::string path_;
  TempFile partial_;  // the file being written; renamed over path_ by finish()
  VolumeInfo info_;
  TIFF* tif_ = nullptr;
  std::unique_ptr<Sink> sink_;
  bool big_ = false;
  TiffCompression compression_ = TiffCompression::kNone;
  std::vector<uint8_t> scratch_;
  bool finished_ = false;
  uint64_t pages_ = 0;
  std::string description_;
};

// True when `info`'s voxels need BigTIFF (more than a classic TIFF's 4 GB).
bool needs_big_tiff(const VolumeInfo& info);

}  // namespace vxr
