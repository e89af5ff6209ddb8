// Low-level TIFF access shared by the TIFF, ImageJ, OME-TIFF and slice-series
// importers: one libtiff handle with captured errors, a description of every
// page (IFD), and region reads that decode only the strips/tiles a box touches.
//
// libtiff handles are not thread-safe; TiffPlanes (tiff_planes.h) keeps a pool
// of them so several threads can read one dataset at once.
#pragma once

#include <array>
#include <atomic>
#include <cstdint>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "core/status.h"
#include "volume/dtype.h"

typedef struct tiff TIFF;

namespace vxr::tiff {

// Process-wide counters, so tests and benchmarks can see how much a read touched.
struct ReadCounters {
  std::atomic<uint64_t> blocks_decoded{0};  // compressed strips/tiles decoded
  std::atomic<uint64_t> raw_bytes{0};       // uncompressed bytes read straight from files
};
ReadCounters& read_counters();

// True when the first bytes of `path` are a TIFF or BigTIFF header.
bool has_tiff_magic(const std::string& path);

// What one IFD holds, as far as the importers care.
struct PageInfo {
  uint64_t ifd_offset = 0;
  uint32_t width = 0, height = 0;
  uint16_t spp = 1;            // samples per pixel
  uint16_t bps = 8;            // bits per sample
  uint16_t sample_format = 1;  // SAMPLEFORMAT_UINT/INT/IEEEFP
  uint16_t planar = 1;         // PLANARCONFIG_CONTIG (1) or SEPARATE (2)
  uint16_t photometric = 1;
  uint16_t compression = 1;
  uint16_t fill_order = 1;
  bool tiled = false;
  bool reduced = false;                 // NewSubfileType says thumbnail / reduced resolution
  uint32_t block_w = 0, block_h = 0;    // tile size, or (width, rows per strip)
  std::shared_ptr<const std::array<std::vector<uint16_t>, 3>> colormap;  // palette pages only
  bool palette_is_u8 = true;            // indices of <= 8 bits: colormap already scaled to 0..255
  std::string description;              // ImageDescription (empty when absent)
  double x_resolution = 0, y_resolution = 0;
  uint16_t resolution_unit = 2;         // RESUNIT_INCH by default, as TIFF says
  DType dtype = DType::kU8;             // what a voxel of this page becomes
  // Nonzero: a plane with no IFD of its own, stored uncompressed and chunky at
  // this file offset with page 0's layout (ImageJ files over 4 GB hold one
  // IFD; the other planes follow the first contiguously).
  uint64_t raw_offset = 0;

  // Channels this page contributes: its samples, or 3 for a colour palette.
  uint32_t channels() const { return colormap ? 3u : spp; }
  // "128x72, 3 x 8-bit" for messages.
  std::string shape_string() const;
};

// One open libtiff handle. Errors and warnings that libtiff reports on it are
// captured (never printed) so they can go into a one-line Status.
class TiffFile {
 public:
  static Result<std::unique_ptr<TiffFile>> open(const std::string& path);
  ~TiffFile();
  TiffFile(const TiffFile&) = delete;
  TiffFile& operator=(const TiffFile&) = delete;

  const std::string& path() const { return path_; }
  uint64_t file_size() const { return file_size_; }

  // Describes every page in the IFD chain, checking sizes for overflow and
  // that every strip/tile lies inside the file. Leaves the handle on page 0.
  Result<std::vector<PageInfo>> scan_pages();
  // Describes the current page.
  Result<PageInfo> describe_current(uint32_t page_index);

  // Reads [x0, x0+w) x [y0, y0+h) of `channel` of `page` into dst as
  // page.dtype, rows of w voxels packed. Only the strips/tiles that overlap
  // the rectangle are read.
  Status read_region(const PageInfo& page, uint32_t channel, uint32_t x0, uint32_t y0, uint32_t w, uint32_t h,
                     uint8_t* dst);

  // Where an uncompressed, chunky, strip-organised page's pixels start, when
  // its strips lie back to back in the file (nullopt otherwise).
  std::optional<uint64_t> contiguous_data_offset(const PageInfo& page);

  // The first error libtiff reported since the last call (and clears it).
  std::string take_error();

  struct Sink;  // error capture, shared with the libtiff callback

 private:
  TiffFile() = default;
  Status go_to(const PageInfo& page);
  Status decode_block(const PageInfo& page, uint32_t block, std::vector<uint8_t>& out);
  Status read_rows_raw(const PageInfo& page, uint64_t off, uint64_t len, uint32_t row0, uint32_t rows,
                       uint64_t row_bytes, std::vector<uint8_t>& out);

  std::string path_;
  uint64_t file_size_ = 0;
  TIFF* tif_ = nullptr;
  std::unique_ptr<Sink> sink_;
  uint64_t current_ifd_ = ~0ull;
  std::vector<uint8_t> scratch_;
  std::vector<uint8_t> scratch2_;  // the last decoded block, kept for the next read of the same block
  uint32_t cached_block_ = ~0u;
  uint64_t cached_ifd_ = ~0ull;
};

}  // namespace vxr::tiff
