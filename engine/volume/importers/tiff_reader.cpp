#include "volume/importers/tiff_reader.h"

#include <tiffio.h>
#include <unistd.h>

#include <algorithm>
#include <cstdarg>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <optional>

#include "core/checked_math.h"
#include "volume/importers/import_limits.h"

namespace vxr::tiff {

struct TiffFile::Sink {
  std::string first_error;
};

namespace {

// libtiff reports through callbacks; keep the first error of each call.
int on_error(TIFF*, void* user, const char* module, const char* fmt, va_list ap) {
  auto* sink = static_cast<TiffFile::Sink*>(user);
  if (sink && sink->first_error.empty()) {
    char buf[512];
    std::vsnprintf(buf, sizeof buf, fmt, ap);
    sink->first_error = buf;
    (void)module;
  }
  return 1;  // handled: do not print
}

int on_warning(TIFF*, void*, const char*, const char*, va_list) { return 1; }

float half_to_float(uint16_t h) {
  const uint32_t sign = uint32_t(h & 0x8000u) << 16;
  uint32_t exp = (h >> 10) & 0x1f;
  uint32_t mant = h & 0x3ffu;
  uint32_t bits;
  if (exp == 0) {
    if (mant == 0) {
      bits = sign;
    } else {  // subnormal: normalise
      exp = 127 - 15 + 1;
      while (!(mant & 0x400u)) {
        mant <<= 1;
        --exp;
      }
      mant &= 0x3ffu;
      bits = sign | (exp << 23) | (mant << 13);
    }
  } else if (exp == 31) {
    bits = sign | 0x7f800000u | (mant << 13);
  } else {
    bits = sign | ((exp + 127 - 15) << 23) | (mant << 13);
  }
  float f;
  std::memcpy(&f, &bits, 4);
  return f;
}

// The most a block of one stored byte can decode to with compression `c`: a
// header's strip size is believed only as far as its stored bytes can pay
// for it (a 158-byte file claiming 2 GB strips grew to 24 GB).
// Most bytes of uncompressed rows read_region holds at once.
constexpr uint64_t kRawScratchBytes = uint64_t(16) << 20;

uint64_t max_expansion(uint16_t c) {
  switch (c) {
    case COMPRESSION_NONE: return 1;
    case COMPRESSION_PACKBITS: return 64;         // 2 bytes -> 128 repeats
    case COMPRESSION_DEFLATE:
    case COMPRESSION_ADOBE_DEFLATE: return 1100;  // deflate's limit is 1032:1
    case COMPRESSION_LZW: return 4096;            // one 9..12-bit code -> at most 4094 bytes
    default: return uint64_t(1) << 16;           // JPEG, ZSTD, LZMA, fax...: generous
  }
}

const char* compression_name(uint16_t c) {
  const TIFFCodec* codec = TIFFFindCODEC(c);
  return codec ? codec->name : "unknown";
}

// Reads `count` samples starting at sample index `first`, `stride` samples
// apart, from a row of packed samples; writes them as `out_type`.
void extract_samples(const uint8_t* row, uint64_t first, uint32_t stride, uint32_t count, const PageInfo& p,
                     uint8_t* out) {
  const uint32_t ob = dtype_bytes(p.dtype);
  const bool is_float = p.sample_format == SAMPLEFORMAT_IEEEFP;
  const bool is_signed = p.sample_format == SAMPLEFORMAT_INT;
  if (p.bps == 8) {
    for (uint32_t i = 0; i < count; ++i) out[i] = row[first + uint64_t(i) * stride];
  } else if (p.bps == 16 && !is_float) {
    for (uint32_t i = 0; i < count; ++i) std::memcpy(out + 2 * i, row + 2 * (first + uint64_t(i) * stride), 2);
  } else if (p.bps == 16) {
    for (uint32_t i = 0; i < count; ++i) {
      uint16_t h;
      std::memcpy(&h, row + 2 * (first + uint64_t(i) * stride), 2);
      const float f = half_to_float(h);
      std::memcpy(out + 4 * i, &f, 4);
    }
  } else if (p.bps == 32) {
    for (uint32_t i = 0; i < count; ++i) std::memcpy(out + 4 * i, row + 4 * (first + uint64_t(i) * stride), 4);
  } else if (p.bps == 64) {
    for (uint32_t i = 0; i < count; ++i) {
      double d;
      std::memcpy(&d, row + 8 * (first + uint64_t(i) * stride), 8);
      const float f = static_cast<float>(d);
      std::memcpy(out + 4 * i, &f, 4);
    }
  } else {
    // Packed samples (1..31 bits), most significant bit first, as TIFF stores them.
    for (uint32_t i = 0; i < count; ++i) {
      uint64_t bit = (first + uint64_t(i) * stride) * p.bps;
      uint32_t v = 0;
      for (uint32_t b = 0; b < p.bps; ++b, ++bit) v = (v << 1) | ((row[bit >> 3] >> (7 - (bit & 7))) & 1u);
      if (is_signed && (v >> (p.bps - 1)) & 1u) v |= ~0u << p.bps;  // sign-extend
      std::memcpy(out + ob * i, &v, ob);                            // little-endian host: low bytes first
    }
  }
}

// Width and height straight from the first IFD's bytes, for a message when
// libtiff refuses the directory (it does so for sizes that overflow).
std::optional<std::pair<uint64_t, uint64_t>> raw_first_page_size(const std::string& path) {
  std::ifstream f(path, std::ios::binary);
  std::vector<uint8_t> b(1 << 16);
  f.read(reinterpret_cast<char*>(b.data()), std::streamsize(b.size()));
  b.resize(size_t(f.gcount()));
  if (b.size() < 16) return std::nullopt;
  const bool be = b[0] == 'M', big = (be ? b[3] : b[2]) == 43;
  auto rd = [&](uint64_t o, int n) -> std::optional<uint64_t> {
    if (!range_inside(o, uint64_t(n), b.size())) return std::nullopt;  // o comes from the file: no o + n overflow
    uint64_t v = 0;
    for (int i = 0; i < n; ++i) v |= uint64_t(b[o + i]) << (8 * (be ? n - 1 - i : i));
    return v;
  };
  const auto ifd = big ? rd(8, 8) : rd(4, 4);
  if (!ifd) return std::nullopt;
  const auto count = big ? rd(*ifd, 8) : rd(*ifd, 2);
  if (!count) return std::nullopt;
  uint64_t w = 0, h = 0;
  const uint64_t entry = big ? 20 : 12;
  if (*ifd > b.size()) return std::nullopt;
  const uint64_t first = *ifd + (big ? 8 : 2);
  for (uint64_t i = 0; i < *count && i < 4096; ++i) {
    const auto tag = rd(first + i * entry, 2), type = rd(first + i * entry + 2, 2);
    if (!tag || !type) break;
    const int n = *type == 3 ? 2 : *type == 4 ? 4 : *type == 16 ? 8 : 0;
    if (n == 0) continue;
    const auto v = rd(first + i * entry + (big ? 12 : 8), n);
    if (v && *tag == 256) w = *v;
    if (v && *tag == 257) h = *v;
  }
  if (!w || !h) return std::nullopt;
  return std::pair{w, h};
}

}  // namespace

ReadCounters& read_counters() {
  static ReadCounters c;
  return c;
}

bool has_tiff_magic(const std::string& path) {
  std::ifstream f(path, std::ios::binary);
  unsigned char h[4] = {0, 0, 0, 0};
  if (!f.read(reinterpret_cast<char*>(h), 4)) return false;
  const bool ii = h[0] == 'I' && h[1] == 'I' && (h[2] == 42 || h[2] == 43) && h[3] == 0;
  const bool mm = h[0] == 'M' && h[1] == 'M' && h[2] == 0 && (h[3] == 42 || h[3] == 43);
  return ii || mm;
}

std::string PageInfo::shape_string() const {
  std::string s = std::to_string(width) + "x" + std::to_string(height) + ", " + std::to_string(channels()) + " x " +
                  dtype_name(dtype);
  return s;
}

Result<std::unique_ptr<TiffFile>> TiffFile::open(const std::string& path) {
  std::error_code ec;
  if (!std::filesystem::is_regular_file(path, ec)) return not_found(path + ": no such file");
  if (!has_tiff_magic(path))
    return invalid_argument(path + ": not a TIFF file (it does not start with a TIFF header II*/MM*)");
  std::unique_ptr<TiffFile> f(new TiffFile());
  f->path_ = path;
  f->file_size_ = std::filesystem::file_size(path, ec);
  f->sink_ = std::make_unique<Sink>();
  TIFFOpenOptions* opts = TIFFOpenOptionsAlloc();
  TIFFOpenOptionsSetErrorHandlerExtR(opts, on_error, f->sink_.get());
  TIFFOpenOptionsSetWarningHandlerExtR(opts, on_warning, f->sink_.get());
  // libtiff sizes some buffers from the header; keep each within the import budget.
  TIFFOpenOptionsSetMaxSingleMemAlloc(opts, tmsize_t(std::min<uint64_t>(uint64_t(1) << 31, import_memory_budget())));
  // "m": no memory mapping. libtiff maps read-only files by default, and every
  // compressed strip it decodes from the map stays resident (file-backed RSS):
  // a 1.4 GB LZW stack imported with --memory 256M peaked at 1.7 GB RSS,
  // 1.38 GB of it the mapped file. read() into libtiff's own strip buffer keeps
  // memory within the import budget.
  f->tif_ = TIFFOpenExt(path.c_str(), "rm", opts);
  TIFFOpenOptionsFree(opts);
  if (!f->tif_) {
    const std::string why = f->take_error();
    if (const auto wh = raw_first_page_size(path); wh && wh->first * wh->second > (uint64_t(1) << 40))
      return out_of_range(path + ": claims absurd dimensions (" + std::to_string(wh->first) + " x " +
                          std::to_string(wh->second) + " pixels); the file is damaged");
    return corrupt(path + ": damaged TIFF directory; cannot read the first page" +
                   (why.empty() ? std::string() : " (libtiff: " + why + ")"));
  }
  f->current_ifd_ = TIFFCurrentDirOffset(f->tif_);
  return f;
}

TiffFile::~TiffFile() {
  if (tif_) TIFFClose(tif_);
}

std::string TiffFile::take_error() {
  std::string e = std::move(sink_->first_error);
  sink_->first_error.clear();
  return e;
}

Result<PageInfo> TiffFile::describe_current(uint32_t index) {
  const std::string where = path_ + ": page " + std::to_string(index);
  PageInfo p;
  p.ifd_offset = TIFFCurrentDirOffset(tif_);
  uint32_t w = 0, h = 0;
  if (!TIFFGetField(tif_, TIFFTAG_IMAGEWIDTH, &w) || !TIFFGetField(tif_, TIFFTAG_IMAGELENGTH, &h) || !w || !h)
    return corrupt(where + ": no image width/height; the file is damaged");
  p.width = w;
  p.height = h;
  TIFFGetFieldDefaulted(tif_, TIFFTAG_SAMPLESPERPIXEL, &p.spp);
  TIFFGetFieldDefaulted(tif_, TIFFTAG_BITSPERSAMPLE, &p.bps);
  TIFFGetFieldDefaulted(tif_, TIFFTAG_SAMPLEFORMAT, &p.sample_format);
  TIFFGetFieldDefaulted(tif_, TIFFTAG_PLANARCONFIG, &p.planar);
  TIFFGetFieldDefaulted(tif_, TIFFTAG_COMPRESSION, &p.compression);
  TIFFGetFieldDefaulted(tif_, TIFFTAG_FILLORDER, &p.fill_order);
  if (!TIFFGetField(tif_, TIFFTAG_PHOTOMETRIC, &p.photometric))
    p.photometric = p.spp >= 3 ? PHOTOMETRIC_RGB : PHOTOMETRIC_MINISBLACK;
  uint32_t subfile = 0;
  if (TIFFGetField(tif_, TIFFTAG_SUBFILETYPE, &subfile)) p.reduced = (subfile & FILETYPE_REDUCEDIMAGE) != 0;
  char* desc = nullptr;
  if (TIFFGetField(tif_, TIFFTAG_IMAGEDESCRIPTION, &desc) && desc) p.description = desc;
  float xr = 0, yr = 0;
  if (TIFFGetField(tif_, TIFFTAG_XRESOLUTION, &xr)) p.x_resolution = xr;
  if (TIFFGetField(tif_, TIFFTAG_YRESOLUTION, &yr)) p.y_resolution = yr;
  TIFFGetFieldDefaulted(tif_, TIFFTAG_RESOLUTIONUNIT, &p.resolution_unit);

  if (p.spp == 0 || p.bps == 0 || p.bps > 64)
    return corrupt(where + ": invalid samples per pixel (" + std::to_string(p.spp) + ") or bits per sample (" +
                   std::to_string(p.bps) + ")");
  // Overflow check before anything is sized from these numbers.
  unsigned __int128 bits = (unsigned __int128)w * h * p.spp * p.bps;
  if (bits > ((unsigned __int128)1 << 47) * 8)
    return out_of_range(where + ": claims absurd dimensions (" + std::to_string(w) + " x " + std::to_string(h) + " x " +
                        std::to_string(p.spp) + " samples x " + std::to_string(p.bps) +
                        " bits, over 128 TiB per page); the file is damaged");
  if (!TIFFIsCODECConfigured(p.compression))
    return unsupported(where + ": compression " + std::to_string(p.compression) + " (" +
                       compression_name(p.compression) + ") is not supported by this libtiff build");
  if (p.compression == COMPRESSION_OJPEG)
    return unsupported(where + ": old-style JPEG compression (6) is not supported; re-save the file");

  // Sample type -> voxel type.
  const uint16_t sf = p.sample_format;
  if (p.photometric == PHOTOMETRIC_PALETTE) {
    if (p.spp != 1 || p.bps > 16) return unsupported(where + ": palette image with " + std::to_string(p.spp) +
                                                     " samples of " + std::to_string(p.bps) + " bits");
    uint16_t *r = nullptr, *g = nullptr, *b = nullptr;
    if (!TIFFGetField(tif_, TIFFTAG_COLORMAP, &r, &g, &b) || !r || !g || !b)
      return corrupt(where + ": palette image without a colour map");
    auto cmap = std::make_shared<std::array<std::vector<uint16_t>, 3>>();
    const size_t n = size_t(1) << p.bps;
    (*cmap)[0].assign(r, r + n);
    (*cmap)[1].assign(g, g + n);
    (*cmap)[2].assign(b, b + n);
    // Colour maps are 16-bit; 8-bit pictures store x*257 (or x<<8): bring them back to 8 bits.
    bool low_zero = true;
    for (size_t i = 0; i < n; ++i)
      for (int c = 0; c < 3; ++c) low_zero = low_zero && ((*cmap)[c][i] & 0xff) == 0;
    p.palette_is_u8 = p.bps <= 8;
    if (p.palette_is_u8)
      for (auto& comp : *cmap)
        for (uint16_t& v : comp) v = low_zero ? uint16_t(v >> 8) : uint16_t((uint32_t(v) * 255 + 32767) / 65535);
    p.colormap = std::move(cmap);
    p.dtype = p.palette_is_u8 ? DType::kU8 : DType::kU16;
  } else if (sf == SAMPLEFORMAT_IEEEFP) {
    if (p.bps != 16 && p.bps != 32 && p.bps != 64)
      return unsupported(where + ": " + std::to_string(p.bps) + "-bit floating point samples are not supported");
    p.dtype = DType::kF32;
  } else if (sf == SAMPLEFORMAT_UINT || sf == SAMPLEFORMAT_VOID || sf == SAMPLEFORMAT_INT) {
    const bool s = sf == SAMPLEFORMAT_INT;
    if (p.bps == 24 || p.bps > 32)
      return unsupported(where + ": " + std::to_string(p.bps) + "-bit integer samples are not supported");
    p.dtype = p.bps <= 8 ? (s ? DType::kI8 : DType::kU8) : p.bps <= 16 ? (s ? DType::kI16 : DType::kU16)
                                                                     : (s ? DType::kI32 : DType::kU32);
  } else {
    return unsupported(where + ": sample format " + std::to_string(sf) + " (complex numbers) is not supported");
  }
  if (p.photometric == PHOTOMETRIC_YCBCR) {
    if (p.compression == COMPRESSION_JPEG) {
      TIFFSetField(tif_, TIFFTAG_JPEGCOLORMODE, JPEGCOLORMODE_RGB);
      p.photometric = PHOTOMETRIC_RGB;  // libtiff upsamples and converts for us
    } else {
      uint16_t sh = 1, sv = 1;
      TIFFGetFieldDefaulted(tif_, TIFFTAG_YCBCRSUBSAMPLING, &sh, &sv);
      if (sh != 1 || sv != 1)
        return unsupported(where + ": subsampled YCbCr without JPEG compression is not supported; re-save as RGB");
    }
  }

  // Block geometry and sizes, straight from libtiff.
  p.tiled = TIFFIsTiled(tif_);
  uint64_t block_bytes = 0;
  uint32_t expected_blocks = 0;
  if (p.tiled) {
    uint32_t tw = 0, th = 0;
    TIFFGetField(tif_, TIFFTAG_TILEWIDTH, &tw);
    TIFFGetField(tif_, TIFFTAG_TILELENGTH, &th);
    if (!tw || !th) return corrupt(where + ": tiled page without a tile size");
    p.block_w = tw;
    p.block_h = th;
    block_bytes = TIFFTileSize64(tif_);
    expected_blocks = TIFFNumberOfTiles(tif_);
  } else {
    uint32_t rps = h;
    TIFFGetFieldDefaulted(tif_, TIFFTAG_ROWSPERSTRIP, &rps);
    p.block_w = w;
    p.block_h = std::clamp<uint32_t>(rps, 1, h);
    block_bytes = TIFFStripSize64(tif_);
    expected_blocks = TIFFNumberOfStrips(tif_);
  }
  if (block_bytes == 0) {
    const std::string why = take_error();
    return corrupt(where + ": cannot size its " + (p.tiled ? "tiles" : "strips") + (why.empty() ? "" : " (" + why + ")"));
  }
  if (p.compression != COMPRESSION_NONE && block_bytes > (uint64_t(1) << 31))
    return unsupported(where + ": compressed " + (p.tiled ? "tiles" : "strips") + " of " + std::to_string(block_bytes) +
                       " bytes are too large to decode; re-save with smaller strips");
  const uint64_t per_plane = uint64_t((w + p.block_w - 1) / p.block_w) * ((h + p.block_h - 1) / p.block_h);
  const uint64_t need = per_plane * (p.planar == PLANARCONFIG_SEPARATE ? p.spp : 1);
  if (expected_blocks < need)
    return corrupt(where + ": has " + std::to_string(expected_blocks) + " strips/tiles but needs " +
                   std::to_string(need) + "; the file is damaged");
  // Blocks that are decoded whole (compressed, or bit-reversed) get a buffer
  // of block_bytes: it must fit the import budget before anything is read.
  const bool decoded = p.compression != COMPRESSION_NONE || p.fill_order != FILLORDER_MSB2LSB;
  if (decoded && block_bytes > max_decoded_block_bytes())
    return out_of_range(where + ": " + (p.tiled ? "tiles" : "strips") + " of " + std::to_string(block_bytes) +
                        " bytes each exceed the " + std::to_string(max_decoded_block_bytes() >> 10) +
                        " KiB one decoded block may take (1/8 of the import memory budget, " +
                        std::to_string(import_memory_budget() >> 20) +
                        " MiB); re-save with smaller strips or tiles, or raise --memory");
  // Uncompressed rows are read whole (read_region): one must fit the per-block share of the budget.
  const uint64_t row_bytes = p.tiled ? TIFFTileRowSize64(tif_) : TIFFScanlineSize64(tif_);
  if (!decoded && row_bytes > max_decoded_block_bytes())
    return out_of_range(where + ": rows of " + std::to_string(row_bytes) + " bytes exceed the " +
                        std::to_string(max_decoded_block_bytes() >> 10) +
                        " KiB one read may take (1/8 of the import memory budget); the file is damaged or too wide");
  const uint32_t rows_per_block = p.block_h;
  for (uint32_t i = 0; i < need; ++i) {
    int err = 0;
    const uint64_t off = TIFFGetStrileOffsetWithErr(tif_, i, &err);
    const uint64_t len = err ? 0 : TIFFGetStrileByteCountWithErr(tif_, i, &err);
    if (err) return corrupt(where + ": cannot read strip/tile offsets; the file is damaged");
    if (!range_inside(off, len, file_size_))
      return corrupt(where + ": image data runs past the end of the file (" + (p.tiled ? "tile " : "strip ") +
                     std::to_string(i) + " ends at byte " + std::to_string(off + len) + ", the file has " +
                     std::to_string(file_size_) + " bytes); the file is truncated");
    if (decoded) {
      // A strip's rows: the last strip of a plane may be shorter than the rest.
      uint64_t bytes = block_bytes;
      if (!p.tiled) {
        const uint32_t row0 = (i % uint32_t(per_plane)) * rows_per_block;
        const uint32_t rows = std::min<uint32_t>(rows_per_block, h - std::min(h, row0));
        bytes = TIFFVStripSize64(tif_, rows);
      }
      const auto affordable = checked_product({len, max_expansion(p.compression)});
      if (affordable && bytes > *affordable)
        return corrupt(where + ": " + (p.tiled ? "tile " : "strip ") + std::to_string(i) + " stores " +
                       std::to_string(len) + " bytes but claims " + std::to_string(bytes) +
                       " decoded, more than " + compression_name(p.compression) + " can expand to; the file is damaged");
    }
  }
  take_error();
  return p;
}

Result<std::vector<PageInfo>> TiffFile::scan_pages() {
  std::vector<PageInfo> pages;
  if (!TIFFSetDirectory(tif_, 0)) return corrupt(path_ + ": cannot read the first TIFF directory");
  current_ifd_ = TIFFCurrentDirOffset(tif_);
  take_error();
  for (uint32_t i = 0;; ++i) {
    VXR_ASSIGN_OR_RETURN(PageInfo p, describe_current(i));
    pages.push_back(std::move(p));
    if (TIFFLastDirectory(tif_)) break;
    if (!TIFFReadDirectory(tif_)) {
      const std::string why = take_error();
      return corrupt(path_ + ": page " + std::to_string(i + 1) + ": cannot read the TIFF directory (" +
                     (why.empty() ? "damaged file" : why) + "); the file is truncated or damaged");
    }
    current_ifd_ = TIFFCurrentDirOffset(tif_);
    if (i > (1u << 24)) return corrupt(path_ + ": more than 16 million pages; the directory chain is damaged");
  }
  current_ifd_ = ~0ull;
  return pages;
}

Status TiffFile::go_to(const PageInfo& page) {
  if (current_ifd_ == page.ifd_offset) return Status::ok();
  take_error();
  if (!TIFFSetSubDirectory(tif_, page.ifd_offset)) {
    current_ifd_ = ~0ull;
    return corrupt(path_ + ": cannot read the TIFF directory at byte " + std::to_string(page.ifd_offset) + " (" +
                   take_error() + ")");
  }
  uint16_t photometric = 0, compression = 0;
  TIFFGetFieldDefaulted(tif_, TIFFTAG_COMPRESSION, &compression);
  if (TIFFGetField(tif_, TIFFTAG_PHOTOMETRIC, &photometric) && photometric == PHOTOMETRIC_YCBCR &&
      compression == COMPRESSION_JPEG)
    TIFFSetField(tif_, TIFFTAG_JPEGCOLORMODE, JPEGCOLORMODE_RGB);
  current_ifd_ = page.ifd_offset;
  return Status::ok();
}

Status TiffFile::decode_block(const PageInfo& page, uint32_t block, std::vector<uint8_t>& out) {
  const uint64_t size = page.tiled ? TIFFTileSize64(tif_) : TIFFStripSize64(tif_);
  out.resize(size);
  const tmsize_t got = page.tiled ? TIFFReadEncodedTile(tif_, block, out.data(), tmsize_t(size))
                                  : TIFFReadEncodedStrip(tif_, block, out.data(), tmsize_t(size));
  if (got < 0) {
    const std::string why = take_error();
    return corrupt(path_ + ": cannot decode " + (page.tiled ? "tile " : "strip ") + std::to_string(block) + " (" +
                   (why.empty() ? "damaged data" : why) + ")");
  }
  read_counters().blocks_decoded.fetch_add(1, std::memory_order_relaxed);
  // A short last strip or a damaged block: zero what was not decoded.
  if (uint64_t(got) < size) std::fill(out.begin() + got, out.end(), 0);
  return Status::ok();
}

std::optional<uint64_t> TiffFile::contiguous_data_offset(const PageInfo& page) {
  if (page.compression != COMPRESSION_NONE || page.tiled || page.fill_order != FILLORDER_MSB2LSB ||
      (page.planar == PLANARCONFIG_SEPARATE && page.spp > 1) || !go_to(page).is_ok())
    return std::nullopt;
  const uint32_t n = TIFFNumberOfStrips(tif_);
  int err = 0;
  const uint64_t first = TIFFGetStrileOffsetWithErr(tif_, 0, &err);
  uint64_t end = first;
  for (uint32_t i = 0; i < n && !err; ++i) {
    if (TIFFGetStrileOffsetWithErr(tif_, i, &err) != end) return std::nullopt;
    end += TIFFGetStrileByteCountWithErr(tif_, i, &err);
  }
  if (err) return std::nullopt;
  return first;
}

// Uncompressed data: read only the rows needed, straight from the file.
// [off, off + len) is the block (strip, tile or contiguous plane) in the file.
Status TiffFile::read_rows_raw(const PageInfo& page, uint64_t off, uint64_t len, uint32_t row0, uint32_t rows,
                               uint64_t row_bytes, std::vector<uint8_t>& out) {
  const uint64_t start = uint64_t(row0) * row_bytes, n = uint64_t(rows) * row_bytes;
  out.assign(n, 0);
  // Bytes beyond the stored byte count are treated as missing (zero), as libtiff does.
  const uint64_t avail = start < len ? std::min<uint64_t>(n, len - start) : 0;
  uint64_t done = 0;
  const int fd = TIFFFileno(tif_);
  while (done < avail) {
    const ssize_t r = ::pread(fd, out.data() + done, avail - done, off_t(off + start + done));
    if (r <= 0) return corrupt(path_ + ": image data runs past the end of the file; the file is truncated");
    done += uint64_t(r);
  }
  read_counters().raw_bytes.fetch_add(avail, std::memory_order_relaxed);
  if (TIFFIsByteSwapped(tif_)) {
    if (page.bps == 16) TIFFSwabArrayOfShort(reinterpret_cast<uint16_t*>(out.data()), tmsize_t(n / 2));
    if (page.bps == 32) TIFFSwabArrayOfLong(reinterpret_cast<uint32_t*>(out.data()), tmsize_t(n / 4));
    if (page.bps == 64) TIFFSwabArrayOfDouble(reinterpret_cast<double*>(out.data()), tmsize_t(n / 8));
  }
  return Status::ok();
}

Status TiffFile::read_region(const PageInfo& page, uint32_t channel, uint32_t x0, uint32_t y0, uint32_t w,
                             uint32_t h, uint8_t* dst) {
  if (uint64_t(x0) + w > page.width || uint64_t(y0) + h > page.height || channel >= page.channels())
    return internal_error(path_ + ": region outside the page");
  // A plane without an IFD (ImageJ > 4 GB): one block, the whole plane, at raw_offset.
  const bool virtual_page = page.raw_offset != 0;
  if (!virtual_page) VXR_RETURN_IF_ERROR(go_to(page));
  const bool palette = page.colormap != nullptr;
  const uint32_t sample = palette ? 0 : channel;
  const bool separate = page.planar == PLANARCONFIG_SEPARATE && page.spp > 1;
  const uint32_t spb = separate ? 1 : page.spp;  // samples per pixel inside a block
  const uint32_t soff = separate ? 0 : sample;
  const uint32_t across = (page.width + page.block_w - 1) / page.block_w;
  const uint32_t down = (page.height + page.block_h - 1) / page.block_h;
  const uint32_t plane_base = separate ? sample * across * down : 0;
  const uint64_t row_bytes = virtual_page ? (uint64_t(page.width) * page.spp * page.bps + 7) / 8
                             : page.tiled ? TIFFTileRowSize64(tif_)
                                          : TIFFScanlineSize64(tif_);
  if (row_bytes == 0) return corrupt(path_ + ": cannot size a row (" + take_error() + ")");
  const bool raw = virtual_page || (page.compression == COMPRESSION_NONE && page.fill_order == FILLORDER_MSB2LSB);
  const uint32_t ob = dtype_bytes(page.dtype);
  // Palette pages: decode indices (u16) then map through the colour map.
  PageInfo index_page = page;
  if (palette) index_page.dtype = page.bps <= 8 ? DType::kU8 : DType::kU16, index_page.sample_format = SAMPLEFORMAT_UINT;
  std::vector<uint8_t> idx(palette ? size_t(w) * 2 : 0);

  for (uint32_t by = y0 / page.block_h; by <= (y0 + h - 1) / page.block_h; ++by) {
    for (uint32_t bx = x0 / page.block_w; bx <= (x0 + w - 1) / page.block_w; ++bx) {
      const uint32_t block = plane_base + (page.tiled ? by * across + bx : by);
      const uint32_t bx0 = bx * page.block_w, by0 = by * page.block_h;
      const uint32_t rx0 = std::max(x0, bx0), rx1 = std::min(x0 + w, std::min(bx0 + page.block_w, page.width));
      const uint32_t ry0 = std::max(y0, by0), ry1 = std::min(y0 + h, std::min(by0 + page.block_h, page.height));
      // Uncompressed rows are read whole (every column), so a page that claims
      // very wide rows is read a few rows at a time: the scratch buffer stays
      // near kRawScratchBytes whatever width the header claims.
      const uint32_t batch =
          raw ? uint32_t(std::clamp<uint64_t>(kRawScratchBytes / row_bytes, 1, ry1 - ry0)) : ry1 - ry0;
      for (uint32_t ys = ry0; ys < ry1; ys += batch) {
        const uint32_t ye = std::min(ry1, ys + batch);
        const uint8_t* base = nullptr;
        uint32_t first_row = 0;  // block row that `base` starts at
        if (raw) {
          uint64_t off = page.raw_offset, len = row_bytes * page.height;
          if (!virtual_page) {
            int err = 0;
            off = TIFFGetStrileOffsetWithErr(tif_, block, &err);
            len = err ? 0 : TIFFGetStrileByteCountWithErr(tif_, block, &err);
            if (err) return corrupt(path_ + ": cannot read strip/tile offsets");
          }
          VXR_RETURN_IF_ERROR(read_rows_raw(page, off, len, ys - by0, ye - ys, row_bytes, scratch_));
          base = scratch_.data();
          first_row = ys - by0;
        } else {
          if (cached_block_ != block || cached_ifd_ != page.ifd_offset) {
            cached_block_ = ~0u;
            VXR_RETURN_IF_ERROR(decode_block(page, block, scratch2_));
            cached_block_ = block;
            cached_ifd_ = page.ifd_offset;
          }
          base = scratch2_.data();
        }
        for (uint32_t y = ys; y < ye; ++y) {
          const uint8_t* row = base + uint64_t(y - by0 - first_row) * row_bytes;
          uint8_t* out = dst + (uint64_t(y - y0) * w + (rx0 - x0)) * ob;
          const uint64_t first = uint64_t(rx0 - bx0) * spb + soff;
          if (!palette) {
            extract_samples(row, first, spb, rx1 - rx0, page, out);
          } else {
            extract_samples(row, first, spb, rx1 - rx0, index_page, idx.data());
            const std::vector<uint16_t>& map = (*page.colormap)[channel];
            for (uint32_t i = 0; i < rx1 - rx0; ++i) {
              uint16_t k = idx[i];
              if (index_page.dtype == DType::kU16) std::memcpy(&k, idx.data() + 2 * i, 2);
              const uint16_t v = map[std::min<size_t>(k, map.size() - 1)];
              if (ob == 1) out[i] = uint8_t(v);
              else std::memcpy(out + 2 * i, &v, 2);
            }
          }
        }
      }
    }
  }
  return Status::ok();
}

}  // namespace vxr::tiff
