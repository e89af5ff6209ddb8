// Hostile files: each case reproduces one defect found by an adversarial run
// or by the fuzzers (tests/fuzz, docs/hardening.md) and failed before its fix.
// A hostile file must come back as one error line, never as a crash, a huge
// allocation or work out of proportion to its size.
#include <doctest/doctest.h>
#include <png.h>
#include <tiffio.h>
#include <zlib.h>

#include <chrono>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <limits>
#include <vector>

#include "core/checked_math.h"
#include "scene/render_settings.h"
#include "volume/chunk_codec.h"
#include "volume/container_layout.h"
#include "volume/container_reader.h"
#include "volume/container_verify.h"
#include "volume/container_writer.h"
#include "volume/importers/import_limits.h"
#include "volume/importers/import_source.h"
#include "volume/importers/slice_series_importer.h"

using namespace vxr;
namespace fs = std::filesystem;

namespace {

fs::path scratch(const std::string& name) {
  const fs::path d = fs::path(VXR_TEST_OUT_DIR) / "hardening" / name;
  fs::remove_all(d);
  fs::create_directories(d);
  return d;
}

void write_bytes(const fs::path& p, const std::string& bytes) {
  std::ofstream(p, std::ios::binary).write(bytes.data(), std::streamsize(bytes.size()));
}

// A one-strip 8-bit TIFF whose header claims `w` x `h` pixels in one strip of
// `compression`, while the file stores only `stored` bytes of it.
void write_tiff_claiming(const fs::path& p, uint32_t w, uint32_t h, uint16_t compression, size_t stored) {
  TIFF* t = TIFFOpen(p.c_str(), "w");
  REQUIRE(t);
  TIFFSetField(t, TIFFTAG_IMAGEWIDTH, w);
  TIFFSetField(t, TIFFTAG_IMAGELENGTH, h);
  TIFFSetField(t, TIFFTAG_SAMPLESPERPIXEL, 1);
  TIFFSetField(t, TIFFTAG_BITSPERSAMPLE, 8);
  TIFFSetField(t, TIFFTAG_COMPRESSION, compression);
  TIFFSetField(t, TIFFTAG_PHOTOMETRIC, PHOTOMETRIC_MINISBLACK);
  TIFFSetField(t, TIFFTAG_ROWSPERSTRIP, h);
  std::vector<uint8_t> junk(stored, 0x5a);
  REQUIRE(TIFFWriteRawStrip(t, 0, junk.data(), tmsize_t(junk.size())) == tmsize_t(stored));
  TIFFWriteDirectory(t);
  TIFFClose(t);
}

// The header bytes of a container layout with hand-made levels.
std::vector<uint8_t> header_with(ContainerLayout L) { return serialize_header(L); }

}  // namespace

TEST_CASE("hardening: checked_product and checked_sum refuse what wraps around") {
  CHECK(checked_product({uint64_t(1) << 32, uint64_t(1) << 31}) == uint64_t(1) << 63);
  CHECK_FALSE(checked_product({uint64_t(1) << 32, uint64_t(1) << 32}));
  CHECK_FALSE(checked_sum({std::numeric_limits<uint64_t>::max(), 1}));
  CHECK(range_inside(10, 5, 15));
  CHECK_FALSE(range_inside(~uint64_t(0) - 3, 8, 100));  // offset + length wraps to 4
}

TEST_CASE("hardening: a .vxc header whose chunk count overflows 64 bits is refused at open") {
  // One level of 2^34 voxels per axis at chunk 8: 2^31 chunks per axis, 2^93
  // chunks, which wrapped to 0 so an empty index "matched" and export then
  // looped over 2^93 chunks.
  ContainerLayout L;
  L.info.dims = {uint64_t(1) << 34, uint64_t(1) << 34, uint64_t(1) << 34};
  L.chunk_size = 8;
  LevelInfo li;
  li.dims = L.info.dims;
  li.chunk_counts = {1u << 31, 1u << 31, 1u << 31};
  L.levels = {li};
  CHECK(L.total_chunks() == std::numeric_limits<uint64_t>::max());  // saturates, never wraps
  const std::vector<uint8_t> h = header_with(L);
  uint64_t header_bytes = 0;
  const auto parsed = parse_header(h, "crafted.vxc", &header_bytes);
  REQUIRE_FALSE(parsed);
  CHECK(parsed.status().code() == ErrorCode::kCorrupt);
  CHECK(parsed.status().message().find("crafted.vxc: header claims absurd dimensions") == 0);
}

TEST_CASE("hardening: a .vxc header with dims past 2^40 or a non-finite voxel size is refused") {
  auto layout = make_layout(VolumeInfo{.dims = {64, 64, 64}}, 32, 1, vxc::Downsample::kMean, vxc::Codec::kLz4);
  REQUIRE(layout);
  uint64_t header_bytes = 0;
  {
    ContainerLayout L = *layout;
    L.info.dims[0] = L.levels[0].dims[0] = uint64_t(1) << 41;
    L.levels[0].chunk_counts[0] = uint32_t(((uint64_t(1) << 41) + 31) / 32);
    const auto parsed = parse_header(header_with(L), "wide.vxc", &header_bytes);
    REQUIRE_FALSE(parsed);
    CHECK(parsed.status().message().find("absurd dimensions") != std::string::npos);
  }
  {
    ContainerLayout L = *layout;
    L.info.voxel_size[1] = std::numeric_limits<double>::infinity();
    const auto parsed = parse_header(header_with(L), "inf.vxc", &header_bytes);
    REQUIRE_FALSE(parsed);
    CHECK(parsed.status().message().find("voxel size") != std::string::npos);
  }
  CHECK(parse_header(header_with(*layout), "fine.vxc", &header_bytes));
}

TEST_CASE("hardening: verify checks uniform chunks without filling them (work bounded by the file size)") {
  // 24 uniform 514^3 float chunks: a 10 KB file. Verify used to decode each
  // (544 MB memset + allocation apiece: tens of seconds, like the 103 KB file
  // that took 105 s); the file's bytes pay for checking the value only.
  const fs::path dir = scratch("verify_uniform");
  auto layout = make_layout(VolumeInfo{.dims = {512 * 16, 512, 1}, .dtype = DType::kF32}, 512, 1,
                            vxc::Downsample::kMean, vxc::Codec::kLz4);
  REQUIRE(layout);
  const fs::path path = dir / "uniform.vxc";
  {
    auto w = ContainerWriter::create(path.string(), *layout, false);
    REQUIRE(w);
    for (uint64_t i = 0; i < layout->total_chunks(); ++i) {
      EncodedChunk c;
      c.key = layout->key_at(i);
      c.codec = vxc::Codec::kUniform;
      c.raw_size = layout->payload_bytes();
      c.stats = {7.0, 7.0};
      REQUIRE((*w)->append(c));
    }
    REQUIRE((*w)->finish());
  }
  CHECK(fs::file_size(path) < 64 * 1024);
  const auto t0 = std::chrono::steady_clock::now();
  const VerifyReport rep = verify_container(path.string());
  const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  CHECK(rep.ok());
  CHECK(rep.chunks_checked == layout->total_chunks());
  CHECK(seconds < 1.0);  // was about 0.15 s per chunk
}

TEST_CASE("hardening: a uniform chunk whose value does not fit its dtype is corrupt, not converted") {
  std::vector<uint8_t> out(8);
  // 1e300 -> uint8 was an undefined float-to-int conversion (UBSan float-cast-overflow).
  CHECK(decode_payload(vxc::Codec::kUniform, DType::kU8, {1e300, 1e300}, {}, out).code() == ErrorCode::kCorrupt);
  CHECK(decode_payload(vxc::Codec::kUniform, DType::kI16, {2.5, 2.5}, {}, out).code() == ErrorCode::kCorrupt);
  CHECK(decode_payload(vxc::Codec::kUniform, DType::kF32, {1e300, 1e300}, {}, out).code() == ErrorCode::kCorrupt);
  CHECK(decode_payload(vxc::Codec::kUniform, DType::kU16, {65535, 65535}, {}, out));
  CHECK(out[0] == 0xff);
}

TEST_CASE("hardening: a TIFF strip claiming more decoded bytes than its stored bytes can hold is refused at open") {
  // 2000 x 2000 deflate strip (4 MB) from 100 stored bytes: deflate expands
  // at most ~1032x. The buffer was sized from the header, not the byte count.
  const fs::path dir = scratch("tiff_ratio");
  write_tiff_claiming(dir / "x.tif", 2000, 2000, COMPRESSION_ADOBE_DEFLATE, 100);
  auto s = open_import_source({(dir / "x.tif").string()});
  REQUIRE_FALSE(s);
  CHECK(s.status().code() == ErrorCode::kCorrupt);
  CHECK(s.status().message().find((dir / "x.tif").string() + ": page 0: strip 0 stores 100 bytes but claims 4000000") ==
        0);
}

TEST_CASE("hardening: a TIFF strip larger than the import memory budget is refused before it is decoded") {
  // 30000 x 30000 LZW in one strip: 900 MB for one decode buffer (the
  // fuzzers' tiny TIFFs aborted with bad_alloc or grew to 24 GB this way).
  const fs::path dir = scratch("tiff_budget");
  write_tiff_claiming(dir / "big.tif", 30000, 30000, COMPRESSION_LZW, 300000);
  auto s = open_import_source({(dir / "big.tif").string()}, ImportHints{.memory_bytes = uint64_t(256) << 20});
  REQUIRE_FALSE(s);
  CHECK(s.status().code() == ErrorCode::kOutOfRange);
  CHECK(s.status().message().find("strips of 900000000 bytes each exceed the 32768 KiB one decoded block may take "
                                   "(1/8 of the import memory budget, 256 MiB)") != std::string::npos);
  set_import_memory_budget(kDefaultImportMemoryBytes);
}

TEST_CASE("hardening: an 81-byte BigTIFF whose first IFD offset wraps around is one error, not an out-of-bounds read") {
  // libtiff refuses the directory; the fallback that reads the raw IFD for a
  // message added offset + length without an overflow check (ASan: read
  // before the buffer). Replayed under the asan preset and by fuzz_replay.tiff.
  const fs::path dir = scratch("bigtiff_wrap");
  std::string b = std::string("II\x2b\x00\x08\x00\x00\x00", 8) + std::string("\xfc\xff\xff\xff\xff\xff\xff\xff", 8);
  b.resize(81, '\0');
  write_bytes(dir / "wrap.tif", b);
  auto s = open_import_source({(dir / "wrap.tif").string()});
  REQUIRE_FALSE(s);
  CHECK(s.status().message().find((dir / "wrap.tif").string() + ": damaged TIFF directory") == 0);
}

TEST_CASE("hardening: raw sidecar dims whose byte count overflows 64 bits are refused") {
  // 2^32 x 2^32 x 1 bytes wrapped to 0 and "matched" an empty raw file.
  const fs::path dir = scratch("raw_overflow");
  write_bytes(dir / "vol.raw", "");
  write_bytes(dir / "vol.json", R"({"file": "vol.raw", "dims": [4294967296, 4294967296, 1], "dtype": "u8"})");
  auto s = open_import_source({(dir / "vol.json").string()});
  REQUIRE_FALSE(s);
  CHECK(s.status().code() == ErrorCode::kOutOfRange);
  CHECK(s.status().message().find((dir / "vol.json").string() + ": \"dims\" 4294967296 x 4294967296 x 1") == 0);
}

TEST_CASE("hardening: raw sidecar channels that no integer holds are an error, not a conversion") {
  const fs::path dir = scratch("raw_channels");
  write_bytes(dir / "vol.raw", std::string(8, '\0'));
  for (const char* channels : {"1e300", "-1", "2.5"}) {
    write_bytes(dir / "vol.json", std::string(R"({"file": "vol.raw", "dims": [2, 2, 2], "dtype": "u8", "channels": )") +
                                      channels + "}");
    auto s = open_import_source({(dir / "vol.json").string()});
    REQUIRE_FALSE(s);
    CHECK(s.status().message().find("\"channels\" and \"timepoints\" must be integers >= 1") != std::string::npos);
  }
}

TEST_CASE("hardening: settings JSON integers out of range name the key instead of wrapping") {
  // 1e300 -> uint32 was undefined (UBSan float-cast-overflow); -1 wrapped to 4294967295.
  for (const char* text : {R"({"max_steps": 1e300})", R"({"max_steps": -1})", R"({"iso_channel": 4294967296})"}) {
    auto s = render_settings_from_json(text);
    REQUIRE_FALSE(s);
    CHECK(s.status().message().find("is not a non-negative integer in range") != std::string::npos);
  }
  auto ok = render_settings_from_json(R"({"max_steps": 100.0, "iso_channel": 1})");
  REQUIRE(ok);
  CHECK(ok->max_steps == 100);
}

TEST_CASE("hardening: a tiny PNG slice claiming 100000 x 100000 pixels is refused before decoding") {
  // The decode buffer was sized from IHDR: 10 GB for a file of about 100 bytes.
  const fs::path dir = scratch("png_claim");
  const fs::path p = dir / "claim.png";
  png_image img;
  std::memset(&img, 0, sizeof img);
  img.version = PNG_IMAGE_VERSION;
  img.width = 4, img.height = 4, img.format = PNG_FORMAT_GRAY;
  const std::vector<uint8_t> px(16, 9);
  REQUIRE(png_image_write_to_file(&img, p.c_str(), 0, px.data(), 0, nullptr));
  std::string b;
  {
    std::ifstream in(p, std::ios::binary);
    b.assign(std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>());
  }
  REQUIRE(b.compare(12, 4, "IHDR") == 0);
  for (int k : {16, 20}) b.replace(size_t(k), 4, std::string("\x00\x01\x86\xa0", 4));  // 100000
  const uint32_t crc = uint32_t(crc32(0, reinterpret_cast<const Bytef*>(b.data() + 12), 17));
  for (int i = 0; i < 4; ++i) b[size_t(29 + i)] = char(crc >> (24 - 8 * i));
  write_bytes(p, b);
  auto s = open_slice_series_import({p.string()});
  REQUIRE_FALSE(s);
  CHECK(s.status().message().find(p.string() + ": 100000 x 100000 pixels cannot come from a") == 0);
}

TEST_CASE("hardening: an uncompressed TIFF claiming rows wider than the budget allows is refused at open") {
  // Found by fuzz_tiff (corpus/tiff/timeout_wide_raw_rows.tif): uncompressed
  // rows are read whole, and 2 rows of a 1.3 GB-wide page were one 2.7 GB
  // allocation for a 1.2 KB file (an OOM, then a timeout).
  const fs::path dir = scratch("tiff_wide_rows");
  write_tiff_claiming(dir / "wide.tif", uint32_t(1) << 28, 2, COMPRESSION_NONE, 16);
  auto s = open_import_source({(dir / "wide.tif").string()});
  REQUIRE_FALSE(s);
  CHECK(s.status().code() == ErrorCode::kOutOfRange);
  CHECK(s.status().message().find("rows of 268435456 bytes exceed") != std::string::npos);
}
