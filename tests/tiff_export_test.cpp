// TIFF export: pages written by TiffStackWriter / export_tiff come back
// through our own importer bit for bit, with the same shape and calibration.
#include <doctest/doctest.h>

#include <algorithm>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <random>

#include "volume/chunk_source.h"
#include "volume/importers/import_source.h"
#include "volume/tiff_export.h"
#include "volume/tiff_writer.h"

using namespace vxr;
namespace fs = std::filesystem;

namespace {

const std::string kData = VXR_TESTDATA_DIR;

fs::path scratch(const std::string& name) {
  const fs::path p = fs::path(VXR_TEST_OUT_DIR) / "tiff_export" / name;
  fs::remove_all(p);
  fs::create_directories(p);
  return p;
}

// One-level ChunkSource over voxels in memory (per channel/timepoint), with
// an apron of edge-repeated voxels as the container has.
class MemoryChunks final : public ChunkSource {
 public:
  MemoryChunks(VolumeInfo info, std::vector<std::vector<uint8_t>> volumes, uint32_t cs, uint32_t apron)
      : info_(std::move(info)), vols_(std::move(volumes)), cs_(cs), apron_(apron) {
    LevelInfo l;
    l.dims = info_.dims;
    for (int a = 0; a < 3; ++a) l.chunk_counts[a] = uint32_t((info_.dims[a] + cs - 1) / cs);
    levels_ = {l};
  }
  const VolumeInfo& info() const override { return info_; }
  const std::vector<LevelInfo>& levels() const override { return levels_; }
  uint32_t chunk_size() const override { return cs_; }
  uint32_t apron() const override { return apron_; }
  Result<ChunkStats> stats(const ChunkKey&) const override { return ChunkStats{}; }
  Result<std::shared_ptr<const Chunk>> read(const ChunkKey& k) const override {
    ++reads;
    auto c = std::make_shared<Chunk>();
    c->key = k;
    c->edge = cs_ + 2 * apron_;
    c->dtype = info_.dtype;
    const uint32_t ob = dtype_bytes(info_.dtype), e = c->edge;
    c->data.resize(uint64_t(e) * e * e * ob);
    const auto& v = vols_[k.timepoint * info_.channels + k.channel];
    auto clampi = [](int64_t a, uint64_t n) { return uint64_t(std::clamp<int64_t>(a, 0, int64_t(n) - 1)); };
    for (uint32_t z = 0; z < e; ++z)
      for (uint32_t y = 0; y < e; ++y)
        for (uint32_t x = 0; x < e; ++x) {
          const uint64_t gx = clampi(int64_t(k.x) * cs_ + x - apron_, info_.dims[0]);
          const uint64_t gy = clampi(int64_t(k.y) * cs_ + y - apron_, info_.dims[1]);
          const uint64_t gz = clampi(int64_t(k.z) * cs_ + z - apron_, info_.dims[2]);
          std::memcpy(&c->data[((uint64_t(z) * e + y) * e + x) * ob],
                      &v[((gz * info_.dims[1] + gy) * info_.dims[0] + gx) * ob], ob);
        }
    return std::shared_ptr<const Chunk>(std::move(c));
  }
  mutable uint64_t reads = 0;

 private:
  VolumeInfo info_;
  std::vector<std::vector<uint8_t>> vols_;
  std::vector<LevelInfo> levels_;
  uint32_t cs_, apron_;
};

std::vector<uint8_t> read_all(SlabSource& s, uint32_t c, uint32_t t) {
  Box3 b;
  b.size = s.info().dims;
  std::vector<uint8_t> buf(b.voxels() * dtype_bytes(s.info().dtype));
  const Status st = s.read_region(c, t, b, buf);
  REQUIRE_MESSAGE(st.is_ok(), st.message());
  return buf;
}

std::unique_ptr<SlabSource> open_ok(const std::string& path) {
  auto r = open_import_source({path});
  REQUIRE_MESSAGE(r.is_ok(), r.status().message());
  return std::move(r).value();
}

}  // namespace

TEST_CASE("tiff export: every dtype, channels and timepoints round-trip bit for bit through the importer") {
  const fs::path dir = scratch("dtypes");
  std::mt19937 rng(7);
  for (DType t : {DType::kU8, DType::kI8, DType::kU16, DType::kI16, DType::kU32, DType::kI32, DType::kF32}) {
    CAPTURE(dtype_name(t));
    VolumeInfo info;
    info.dims = {37, 21, 11};  // not multiples of the chunk size
    info.dtype = t;
    info.channels = 2;
    info.timepoints = 3;
    info.voxel_size = {0.25, 0.25, 2.0};
    info.unit = "um";
    std::vector<std::vector<uint8_t>> vols(6);
    for (auto& v : vols) {
      v.resize(info.voxels_per_volume() * dtype_bytes(t));
      for (auto& b : v) b = uint8_t(rng());
      if (t == DType::kF32)  // keep floats finite (NaN payloads need not survive)
        for (size_t i = 3; i < v.size(); i += 4) v[i] &= 0x3f;
    }
    MemoryChunks src(info, vols, 8, 1);
    const std::string out = (dir / (std::string(dtype_name(t)) + ".tif")).string();
    REQUIRE(export_tiff(src, out).is_ok());
    CHECK_FALSE(fs::exists(out + ".partial"));
    auto back = open_ok(out);
    const VolumeInfo& b = back->info();
    CHECK(b.dims == info.dims);
    CHECK(b.dtype == t);
    CHECK(b.channels == 2);
    CHECK(b.timepoints == 3);
    CHECK(b.unit == "um");
    CHECK(b.voxel_size[0] == doctest::Approx(0.25));
    CHECK(b.voxel_size[2] == doctest::Approx(2.0));
    for (uint32_t tp = 0; tp < 3; ++tp)
      for (uint32_t c = 0; c < 2; ++c) CHECK(read_all(*back, c, tp) == vols[tp * 2 + c]);
    // One channel and one timepoint on their own.
    TiffExportOptions o;
    o.channel = 1;
    o.timepoint = 2;
    const std::string one = (dir / (std::string(dtype_name(t)) + "_c1t2.tif")).string();
    REQUIRE(export_tiff(src, one, o).is_ok());
    auto b1 = open_ok(one);
    CHECK(b1->info().channels == 1);
    CHECK(b1->info().timepoints == 1);
    CHECK(read_all(*b1, 0, 0) == vols[2 * 2 + 1]);
  }
}

TEST_CASE("tiff export: a real TIFF stack imported then exported gives the same pixels") {
  auto src = open_ok(kData + "/tiff/mri-stack-calibrated.tif");
  const VolumeInfo info = src->info();
  MemoryChunks chunks(info, {read_all(*src, 0, 0)}, 16, 1);
  const fs::path dir = scratch("real");
  const std::string out = (dir / "mri.tif").string();
  REQUIRE(export_tiff(chunks, out).is_ok());
  auto back = open_ok(out);
  CHECK(back->info().dims == info.dims);
  CHECK(back->info().voxel_size == info.voxel_size);  // (1, 1, 5) um
  CHECK(back->info().unit == "um");
  CHECK(read_all(*back, 0, 0) == read_all(*src, 0, 0));
  // Whole chunk layers fit the default budget: every chunk decodes exactly once.
  const auto& l = chunks.levels()[0];
  CHECK(chunks.reads == uint64_t(l.chunk_counts[0]) * l.chunk_counts[1] * l.chunk_counts[2]);
  // With a budget below one layer, it decodes per plane and still writes the same file.
  TiffExportOptions small;
  small.memory_budget = 1;
  const std::string out2 = (dir / "mri_small_budget.tif").string();
  REQUIRE(export_tiff(chunks, out2, small).is_ok());
  CHECK(read_all(*open_ok(out2), 0, 0) == read_all(*src, 0, 0));
}

TEST_CASE("tiff export: BigTIFF pages read back, and the switch happens past 4 GB") {
  VolumeInfo info;
  info.dims = {19, 7, 3};
  info.dtype = DType::kU16;
  const fs::path dir = scratch("bigtiff");
  const std::string out = (dir / "big.tif").string();
  auto w = TiffStackWriter::create(out, info, /*force_bigtiff=*/true);
  REQUIRE(w.is_ok());
  CHECK((*w)->big_tiff());
  std::vector<uint8_t> page(19 * 7 * 2);
  for (int z = 0; z < 3; ++z) {
    for (size_t i = 0; i < page.size(); ++i) page[i] = uint8_t(i * 3 + z);
    REQUIRE((*w)->write_page(page.data()).is_ok());
  }
  REQUIRE((*w)->finish().is_ok());
  std::ifstream f(out, std::ios::binary);
  char magic[4];
  f.read(magic, 4);
  CHECK(magic[2] == 43);  // 'II' 43: BigTIFF
  auto back = open_ok(out);
  CHECK(back->info().dims == info.dims);
  CHECK(read_all(*back, 0, 0).back() == page.back());
  VolumeInfo huge;
  huge.dims = {65536, 65536, 1};  // exactly 4 GiB of u8
  CHECK(needs_big_tiff(huge));
  huge.dims = {1024, 1024, 1000};  // 1 GB
  CHECK_FALSE(needs_big_tiff(huge));
  huge.dims = {1024, 1024, 2048};
  huge.dtype = DType::kU16;  // 4 GiB
  CHECK(needs_big_tiff(huge));
}

TEST_CASE("tiff writer: LZW and Deflate stacks (predictor 2) read back bit for bit, the caller's page untouched") {
  VolumeInfo info;
  info.dims = {61, 37, 4};
  info.dtype = DType::kU16;
  const fs::path dir = scratch("compressed");
  for (TiffCompression c : {TiffCompression::kLzw, TiffCompression::kDeflate}) {
    const std::string out = (dir / (c == TiffCompression::kLzw ? "lzw.tif" : "deflate.tif")).string();
    auto w = TiffStackWriter::create(out, info, false, c);
    REQUIRE(w.is_ok());
    std::vector<uint8_t> all;
    for (int z = 0; z < 4; ++z) {
      std::vector<uint16_t> page(61 * 37);
      for (size_t i = 0; i < page.size(); ++i) page[i] = uint16_t(1000 + (i % 61) * 7 + z * 300 + (i * 2654435761u >> 28));
      const std::vector<uint16_t> before = page;
      REQUIRE((*w)->write_page(reinterpret_cast<const uint8_t*>(page.data())).is_ok());
      CHECK(page == before);  // the predictor worked on a copy
      const auto* b = reinterpret_cast<const uint8_t*>(page.data());
      all.insert(all.end(), b, b + page.size() * 2);
    }
    REQUIRE((*w)->finish().is_ok());
    CHECK(fs::file_size(out) < all.size());  // really compressed
    auto back = open_ok(out);
    CHECK(back->info().dims == info.dims);
    CHECK(read_all(*back, 0, 0) == all);
  }
}

TEST_CASE("tiff export: failures leave no file behind") {
  const fs::path dir = scratch("failures");
  VolumeInfo info;
  info.dims = {4, 4, 2};
  // Unfinished writer: the partial file goes away, nothing appears at the path.
  {
    auto w = TiffStackWriter::create((dir / "unfinished.tif").string(), info);
    REQUIRE(w.is_ok());
    std::vector<uint8_t> page(16, 1);
    REQUIRE((*w)->write_page(page.data()).is_ok());
    CHECK((*w)->finish().code() == ErrorCode::kInternal);  // 1 of 2 pages
  }
  CHECK_FALSE(fs::exists(dir / "unfinished.tif"));
  CHECK_FALSE(fs::exists(dir / "unfinished.tif.partial"));
  // A folder that does not exist: one line naming the path.
  auto bad = TiffStackWriter::create((dir / "no/such/folder/x.tif").string(), info);
  REQUIRE_FALSE(bad.is_ok());
  CHECK(bad.status().message().find("x.tif: folder") != std::string::npos);
  // Bad level/channel: invalid argument naming the option.
  MemoryChunks src(info, {std::vector<uint8_t>(32, 0)}, 8, 1);
  TiffExportOptions o;
  o.channel = 3;
  const Status s = export_tiff(src, (dir / "c3.tif").string(), o);
  CHECK(s.code() == ErrorCode::kInvalidArgument);
  CHECK(s.message().find("--channel 3") == 0);
  CHECK_FALSE(fs::exists(dir / "c3.tif"));
}
