// The .vxc container: round trips, pyramid, codecs, corruption detection,
// bounded resumable writing, and a volume of more than 2^32 voxels.
#include <doctest/doctest.h>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <random>

#include "volume/chunk_codec.h"
#include "volume/container_reader.h"
#include "volume/container_verify.h"
#include "volume/container_writer.h"
#include "volume/memory_slab_source.h"
#include "volume/pyramid_builder.h"

using namespace vxr;
namespace fs = std::filesystem;

namespace {

fs::path test_dir(const std::string& name) {
  fs::path d = fs::temp_directory_path() / ("vxr_container_test_" + name);
  fs::remove_all(d);
  fs::create_directories(d);
  return d;
}

template <typename T>
void put(std::vector<uint8_t>& buf, uint64_t i, T v) {
  std::memcpy(buf.data() + i * sizeof(T), &v, sizeof(T));
}

// A volume of `dtype` whose values depend on position, with some noise.
MemorySlabSource make_source(DType dtype, std::array<uint64_t, 3> dims, uint32_t channels = 1, uint32_t timepoints = 1,
                             std::array<double, 3> vs = {1, 1, 1}) {
  VolumeInfo info;
  info.dims = dims;
  info.dtype = dtype;
  info.channels = channels;
  info.timepoints = timepoints;
  info.voxel_size = vs;
  std::vector<std::vector<uint8_t>> vols;
  std::mt19937 rng(42);
  for (uint32_t v = 0; v < channels * timepoints; ++v) {
    std::vector<uint8_t> buf(info.voxels_per_volume() * dtype_bytes(dtype));
    for (uint64_t z = 0, i = 0; z < dims[2]; ++z)
      for (uint64_t y = 0; y < dims[1]; ++y)
        for (uint64_t x = 0; x < dims[0]; ++x, ++i) {
          const double base = double(x * 3 + y * 5 + z * 7 + v * 11) + double(rng() % 4);
          switch (dtype) {
            case DType::kU8: put<uint8_t>(buf, i, uint8_t(int(base) % 251)); break;
            case DType::kI8: put<int8_t>(buf, i, int8_t(int(base) % 251 - 125)); break;
            case DType::kU16: put<uint16_t>(buf, i, uint16_t(int(base * 13) % 65000)); break;
            case DType::kI16: put<int16_t>(buf, i, int16_t(int(base * 13) % 65000 - 32000)); break;
            case DType::kU32: put<uint32_t>(buf, i, uint32_t(base * 100000)); break;
            case DType::kI32: put<int32_t>(buf, i, int32_t(base * 100000) - 50000000); break;
            case DType::kF32: put<float>(buf, i, float(base * 0.37 - 20)); break;
          }
        }
    vols.push_back(std::move(buf));
  }
  return MemorySlabSource(info, std::move(vols));
}

std::vector<uint8_t> read_all(MemorySlabSource& src, uint32_t c = 0, uint32_t t = 0) {
  const auto& i = src.info();
  std::vector<uint8_t> out(i.voxels_per_volume() * dtype_bytes(i.dtype));
  Box3 box;
  box.size = i.dims;
  REQUIRE(src.read_region(c, t, box, out).is_ok());
  return out;
}

double voxel(const std::vector<uint8_t>& buf, DType t, uint64_t i) {
  DenseVolume v;
  v.dims = {uint32_t(buf.size() / dtype_bytes(t)), 1, 1};
  v.dtype = t;
  v.data = buf;
  return v.value_at(uint32_t(i), 0, 0);
}

void flip_byte(const std::string& path, uint64_t offset) {
  std::fstream f(path, std::ios::in | std::ios::out | std::ios::binary);
  f.seekg(static_cast<std::streamoff>(offset));
  char c;
  f.read(&c, 1);
  c = static_cast<char>(c ^ 0x5a);
  f.seekp(static_cast<std::streamoff>(offset));
  f.write(&c, 1);
}

}  // namespace

TEST_CASE("container: every dtype round-trips level 0 bit for bit, with metadata") {
  for (DType t : {DType::kU8, DType::kI8, DType::kU16, DType::kI16, DType::kU32, DType::kI32, DType::kF32}) {
    CAPTURE(dtype_name(t));
    const fs::path dir = test_dir(std::string("dtype_") + dtype_name(t));
    auto src = make_source(t, {37, 21, 19}, 2, 2, {0.5, 0.5, 1.0});
    ImportOptions opt;
    opt.chunk_size = 16;
    const std::string out = (dir / "v.vxc").string();
    auto sum = build_container(src, out, opt);
    REQUIRE_MESSAGE(sum.is_ok(), sum.status().to_string());
    CHECK_FALSE(fs::exists(out + ".partial"));
    auto r = ContainerReader::open(out);
    REQUIRE_MESSAGE(r.is_ok(), r.status().to_string());
    CHECK((*r)->info().dims == std::array<uint64_t, 3>{37, 21, 19});
    CHECK((*r)->info().dtype == t);
    CHECK((*r)->info().channels == 2);
    CHECK((*r)->info().timepoints == 2);
    CHECK((*r)->info().voxel_size[2] == 1.0);
    for (uint32_t tp = 0; tp < 2; ++tp)
      for (uint32_t c = 0; c < 2; ++c) {
        auto dense = read_level_dense(**r, 0, c, tp);
        REQUIRE(dense.is_ok());
        CHECK(dense->data == read_all(src, c, tp));
      }
    CHECK(verify_container(out).ok());
  }
}

TEST_CASE("container: chunk payloads carry a one-voxel apron from neighbours, edges repeated") {
  const fs::path dir = test_dir("apron");
  auto src = make_source(DType::kU16, {40, 30, 20});
  const auto all = read_all(src);
  ImportOptions opt;
  opt.chunk_size = 16;
  const std::string out = (dir / "a.vxc").string();
  REQUIRE(build_container(src, out, opt).is_ok());
  auto r = ContainerReader::open(out);
  REQUIRE(r.is_ok());
  const auto& L = (*r)->levels()[0];
  CHECK(L.chunk_counts == std::array<uint32_t, 3>{3, 2, 2});
  for (uint32_t cz = 0; cz < 2; ++cz)
    for (uint32_t cy = 0; cy < 2; ++cy)
      for (uint32_t cx = 0; cx < 3; ++cx) {
        auto chunk = (*r)->read({0, cx, cy, cz, 0, 0});
        REQUIRE(chunk.is_ok());
        const uint32_t E = (*chunk)->edge;
        REQUIRE(E == 18);
        double lo = 1e30, hi = -1e30;
        for (uint32_t k = 0; k < E; ++k)
          for (uint32_t j = 0; j < E; ++j)
            for (uint32_t i = 0; i < E; ++i) {
              const int64_t gx = std::clamp<int64_t>(int64_t(cx) * 16 - 1 + i, 0, 39);
              const int64_t gy = std::clamp<int64_t>(int64_t(cy) * 16 - 1 + j, 0, 29);
              const int64_t gz = std::clamp<int64_t>(int64_t(cz) * 16 - 1 + k, 0, 19);
              const double want = voxel(all, DType::kU16, uint64_t((gz * 30 + gy) * 40 + gx));
              const double got = voxel((*chunk)->data, DType::kU16, (uint64_t(k) * E + j) * E + i);
              if (want != got) FAIL("voxel ", i, ",", j, ",", k, " of chunk ", cx, ",", cy, ",", cz);
              lo = std::min(lo, got);
              hi = std::max(hi, got);
            }
        CHECK((*chunk)->stats.min == lo);
        CHECK((*chunk)->stats.max == hi);
        auto st = (*r)->stats({0, cx, cy, cz, 0, 0});
        REQUIRE(st.is_ok());
        CHECK(st->min == lo);
        CHECK(st->max == hi);
      }
  CHECK((*r)->read({0, 3, 0, 0, 0, 0}).status().code() == ErrorCode::kNotFound);
}

TEST_CASE("container: level 1 is the 2x2x2 mean (or max), edge voxels repeated for odd sizes") {
  for (auto mode : {vxc::Downsample::kMean, vxc::Downsample::kMax}) {
    const fs::path dir = test_dir("mean");
    auto src = make_source(DType::kU8, {35, 22, 17});
    const auto all = read_all(src);
    ImportOptions opt;
    opt.chunk_size = 8;
    opt.downsample = mode;
    const std::string out = (dir / "m.vxc").string();
    REQUIRE(build_container(src, out, opt).is_ok());
    auto r = ContainerReader::open(out);
    REQUIRE(r.is_ok());
    REQUIRE((*r)->levels().size() >= 3);
    CHECK((*r)->levels()[1].dims == std::array<uint64_t, 3>{18, 11, 9});
    CHECK((*r)->levels()[1].downsample == std::array<uint32_t, 3>{2, 2, 2});
    const auto& last = (*r)->levels().back();
    CHECK(last.chunk_counts == std::array<uint32_t, 3>{1, 1, 1});
    auto l1 = read_level_dense(**r, 1);
    REQUIRE(l1.is_ok());
    CHECK(l1->voxel_size[0] == 2.0);
    for (uint32_t z = 0; z < 9; ++z)
      for (uint32_t y = 0; y < 11; ++y)
        for (uint32_t x = 0; x < 18; ++x) {
          double sum = 0, mx = 0;
          for (int dz = 0; dz < 2; ++dz)
            for (int dy = 0; dy < 2; ++dy)
              for (int dx = 0; dx < 2; ++dx) {
                const uint64_t ix = std::min<uint64_t>(2 * x + dx, 34), iy = std::min<uint64_t>(2 * y + dy, 21),
                               iz = std::min<uint64_t>(2 * z + dz, 16);
                const double v = all[(iz * 22 + iy) * 35 + ix];
                sum += v;
                mx = std::max(mx, v);
              }
          const double want = mode == vxc::Downsample::kMax ? mx : std::floor(sum / 8 + 0.5);
          if (l1->value_at(x, y, z) != want) FAIL("level-1 voxel ", x, ",", y, ",", z);
        }
  }
}

TEST_CASE("container: anisotropic data is halved only along its fine axes until roughly isotropic") {
  auto levels = plan_pyramid({4096, 4096, 100}, {0.1, 0.1, 2.0}, 64);
  REQUIRE(levels.size() >= 6);
  CHECK(levels[1].downsample == std::array<uint32_t, 3>{2, 2, 1});
  CHECK(levels[4].downsample == std::array<uint32_t, 3>{16, 16, 1});  // 1.6 x 1.6 x 2: roughly isotropic now
  CHECK(levels[5].downsample == std::array<uint32_t, 3>{32, 32, 2});
  CHECK(levels.back().chunk_counts == std::array<uint32_t, 3>{1, 1, 1});
  auto iso = plan_pyramid({1000, 1000, 1000}, {1, 1, 1}, 64);
  CHECK(iso.size() == 5);  // 1000 -> 500 -> 250 -> 125 -> 63
  CHECK(iso[1].dims == std::array<uint64_t, 3>{500, 500, 500});
}

TEST_CASE("container: uniform chunks are stored without payload and read back as their value") {
  const fs::path dir = test_dir("uniform");
  VolumeInfo info;
  info.dims = {40, 40, 40};
  info.dtype = DType::kI16;
  std::vector<uint8_t> buf(info.voxels_per_volume() * 2);
  for (uint64_t i = 0; i < info.voxels_per_volume(); ++i) put<int16_t>(buf, i, -7);
  put<int16_t>(buf, 0, 1000);  // one non-uniform corner
  MemorySlabSource src(info, {buf});
  ImportOptions opt;
  opt.chunk_size = 16;
  const std::string out = (dir / "u.vxc").string();
  REQUIRE(build_container(src, out, opt).is_ok());
  auto r = ContainerReader::open(out);
  REQUIRE(r.is_ok());
  int uniform = 0;
  for (uint64_t i = 0; i < (*r)->chunk_count(); ++i)
    if (const vxc::IndexEntry e = (*r)->entry_at(i).value(); e.codec == uint8_t(vxc::Codec::kUniform)) {
      CHECK(e.stored_size == 0);
      CHECK(e.min == -7);
      ++uniform;
    }
  CHECK(uniform >= 20);
  auto far = (*r)->read({0, 2, 2, 2, 0, 0});
  REQUIRE(far.is_ok());
  CHECK((*far)->stats.uniform());
  CHECK(voxel((*far)->data, DType::kI16, 1234) == -7);
  auto corner = (*r)->read({0, 0, 0, 0, 0, 0});
  REQUIRE(corner.is_ok());
  CHECK((*corner)->stats.max == 1000);
  CHECK(voxel((*corner)->data, DType::kI16, (1 * 18 + 1) * 18 + 1) == 1000);  // interior (0,0,0)
  CHECK(voxel((*corner)->data, DType::kI16, 0) == 1000);                      // apron repeats the edge
}

TEST_CASE("codec: byte shuffle puts byte b of element i at b * n + i, for 2, 3 and 4 byte elements") {
  for (uint32_t e : {2u, 3u, 4u}) {
    CAPTURE(e);
    const size_t n = 1001;  // not a multiple of any vector width
    std::vector<uint8_t> src(n * e), shuf(n * e), back(n * e);
    for (size_t i = 0; i < src.size(); ++i) src[i] = uint8_t((i * 2654435761u) >> 11);
    byte_shuffle(src.data(), shuf.data(), n, e);
    bool layout = true;
    for (size_t i = 0; i < n; ++i)
      for (uint32_t b = 0; b < e; ++b) layout = layout && shuf[b * n + i] == src[i * e + b];
    CHECK(layout);
    byte_unshuffle(shuf.data(), back.data(), n, e);
    CHECK(back == src);
  }
}

TEST_CASE("codec: byte shuffle round-trips and LZ4 payloads decode exactly") {
  std::vector<uint8_t> v(18 * 18 * 18 * 2);
  std::mt19937 rng(1);
  for (size_t i = 0; i < v.size() / 2; ++i) put<uint16_t>(v, i, uint16_t(1000 + rng() % 64));
  for (auto c : {vxc::Codec::kLz4, vxc::Codec::kShuffleLz4, vxc::Codec::kRaw}) {
    auto enc = encode_chunk({}, DType::kU16, v, c);
    CHECK(enc.codec == c);
    std::vector<uint8_t> back(v.size());
    REQUIRE(decode_payload(enc.codec, DType::kU16, enc.stats, enc.stored, back).is_ok());
    CHECK(back == v);
    if (c != vxc::Codec::kRaw) {
      std::vector<uint8_t> bad = enc.stored;
      bad.resize(bad.size() / 2);
      CHECK(decode_payload(enc.codec, DType::kU16, enc.stats, bad, back).code() == ErrorCode::kCorrupt);
    }
  }
  auto plain = encode_chunk({}, DType::kU16, v, vxc::Codec::kLz4);
  auto shuf = encode_chunk({}, DType::kU16, v, vxc::Codec::kShuffleLz4);
  CHECK(shuf.stored.size() < plain.stored.size());  // the high bytes are nearly constant
}

namespace {

// Builds a small container and returns its path; records a payload offset etc.
std::string build_for_corruption(const fs::path& dir) {
  auto src = make_source(DType::kU16, {40, 36, 20});
  ImportOptions opt;
  opt.chunk_size = 16;
  const std::string out = (dir / "c.vxc").string();
  REQUIRE(build_container(src, out, opt).is_ok());
  return out;
}

bool any_problem_mentions(const VerifyReport& rep, const std::string& text) {
  for (const auto& p : rep.problems)
    if (p.find(text) != std::string::npos) return true;
  return false;
}

}  // namespace

TEST_CASE("corruption: a flipped byte in a chunk payload is found by verify and reading that chunk fails") {
  const std::string out = build_for_corruption(test_dir("corrupt_payload"));
  vxc::IndexEntry victim;
  {
    auto r = ContainerReader::open(out);
    REQUIRE(r.is_ok());
    victim = (*r)->entry_at(3).value();
    REQUIRE(victim.stored_size > 100);
  }
  flip_byte(out, victim.offset + sizeof(vxc::RecordHeader) + victim.stored_size / 2);
  const VerifyReport rep = verify_container(out);
  CHECK_FALSE(rep.ok());
  REQUIRE(rep.problems.size() == 1);
  CHECK(any_problem_mentions(rep, describe_key(key_of(victim))));
  auto r = ContainerReader::open(out);
  REQUIRE(r.is_ok());
  auto c = (*r)->read(key_of(victim));
  CHECK(c.status().code() == ErrorCode::kCorrupt);
  CHECK((*r)->read(key_of((*r)->entry_at(4).value())).is_ok());  // the rest stays readable
}

TEST_CASE("corruption: a flipped byte in a chunk record header is found and reading that chunk fails") {
  const std::string out = build_for_corruption(test_dir("corrupt_header"));
  vxc::IndexEntry victim;
  {
    auto r = ContainerReader::open(out);
    REQUIRE(r.is_ok());
    victim = (*r)->entry_at(5).value();
  }
  flip_byte(out, victim.offset + 50);  // inside stored_size
  const VerifyReport rep = verify_container(out);
  CHECK_FALSE(rep.ok());
  CHECK(any_problem_mentions(rep, describe_key(key_of(victim))));
  auto r = ContainerReader::open(out);
  REQUIRE(r.is_ok());
  CHECK((*r)->read(key_of(victim)).status().code() == ErrorCode::kCorrupt);
}

TEST_CASE("corruption: a flipped byte in the index or the footer is found, the file will not open") {
  for (const char* where : {"index", "footer", "file header"}) {
    CAPTURE(where);
    const std::string out = build_for_corruption(test_dir(std::string("corrupt_") + where));
    const uint64_t size = fs::file_size(out);
    vxc::Footer f;
    {
      std::ifstream in(out, std::ios::binary);
      in.seekg(static_cast<std::streamoff>(size - sizeof f));
      in.read(reinterpret_cast<char*>(&f), sizeof f);
    }
    if (std::string(where) == "index") flip_byte(out, f.index_offset + sizeof(vxc::IndexHeader) + 7 * 80 + 33);
    else if (std::string(where) == "footer") flip_byte(out, size - sizeof f + 8);
    else flip_byte(out, 20);
    const VerifyReport rep = verify_container(out);
    CHECK_FALSE(rep.ok());
    CHECK(any_problem_mentions(rep, std::string(where) == "file header" ? "header" : where));
    auto r = ContainerReader::open(out);
    CHECK(r.status().code() == ErrorCode::kCorrupt);
  }
}

namespace {

// Rewrites index entry `i` of a finished file with `edit` applied, then fixes
// the index and footer checksums, so only the entry's own checks can catch it.
template <typename Edit>
void rewrite_index_entry(const std::string& path, uint64_t i, Edit edit, bool fix_checksums = true) {
  const uint64_t size = fs::file_size(path);
  std::fstream io(path, std::ios::in | std::ios::out | std::ios::binary);
  vxc::Footer f;
  io.seekg(static_cast<std::streamoff>(size - sizeof f));
  io.read(reinterpret_cast<char*>(&f), sizeof f);
  std::vector<char> index(f.index_bytes);
  io.seekg(static_cast<std::streamoff>(f.index_offset));
  io.read(index.data(), static_cast<std::streamsize>(index.size()));
  vxc::IndexEntry e;
  char* at = index.data() + sizeof(vxc::IndexHeader) + i * sizeof e;
  std::memcpy(&e, at, sizeof e);
  edit(e);
  std::memcpy(at, &e, sizeof e);
  io.seekp(static_cast<std::streamoff>(f.index_offset));
  io.write(index.data(), static_cast<std::streamsize>(index.size()));
  if (fix_checksums) {
    f.index_checksum = vxc::checksum(index.data(), index.size());
    f.footer_checksum = vxc::checksum(&f, 48);
    io.seekp(static_cast<std::streamoff>(size - sizeof f));
    io.write(reinterpret_cast<const char*>(&f), sizeof f);
  }
}

}  // namespace

TEST_CASE("index: a wrong entry with valid checksums is caught at open or when its chunk is read") {
  // Entry 7 names another chunk: open() checks every entry's key against its position.
  {
    const std::string out = build_for_corruption(test_dir("index_wrong_key"));
    rewrite_index_entry(out, 7, [](vxc::IndexEntry& e) { e.x ^= 1; });
    auto r = ContainerReader::open(out);
    CHECK(r.status().code() == ErrorCode::kCorrupt);
    CHECK(r.status().message().find("index entry 7 is invalid") != std::string::npos);
    const VerifyReport rep = verify_container(out);
    CHECK_FALSE(rep.ok());
    CHECK(any_problem_mentions(rep, "index: entry 7 names"));
  }
  // Entry 5 points at entry 6's (intact) record: the record names another chunk.
  {
    const std::string out = build_for_corruption(test_dir("index_wrong_offset"));
    vxc::IndexEntry e5, e6;
    {
      auto r = ContainerReader::open(out);
      REQUIRE(r.is_ok());
      e5 = (*r)->entry_at(5).value();
      e6 = (*r)->entry_at(6).value();
    }
    REQUIRE(e5.offset != e6.offset);
    rewrite_index_entry(out, 5, [&](vxc::IndexEntry& e) { e.offset = e6.offset; });
    auto r = ContainerReader::open(out);
    REQUIRE(r.is_ok());
    CHECK((*r)->read(key_of(e5)).status().code() == ErrorCode::kCorrupt);
    CHECK((*r)->read(key_of(e6)).is_ok());
    const VerifyReport rep = verify_container(out);
    CHECK_FALSE(rep.ok());
    CHECK(any_problem_mentions(rep, describe_key(key_of(e5))));
  }
  // The file changes under an open reader: the lookup itself checks the entry.
  {
    const std::string out = build_for_corruption(test_dir("index_changed_after_open"));
    const vxc::IndexEntry e9 = ContainerReader::open(out).value()->entry_at(9).value();
    auto r = ContainerReader::open(out);
    REQUIRE(r.is_ok());
    REQUIRE((*r)->resident_index_bytes() == 0);  // nothing cached yet
    rewrite_index_entry(out, 9, [](vxc::IndexEntry& e) { e.y ^= 1; }, false);
    CHECK((*r)->stats(key_of(e9)).status().code() == ErrorCode::kCorrupt);
    CHECK((*r)->read(key_of(e9)).status().code() == ErrorCode::kCorrupt);
  }
}

TEST_CASE("index: the reader holds a bounded index cache, not the index, whatever the chunk count") {
  // 256^3 u8 in 8^3 chunks: 37449 chunks, a 3 MB index; and a 24^3 one with 36 chunks.
  uint64_t resident_small = 0;
  for (const uint64_t n : {uint64_t(24), uint64_t(256)}) {
    CAPTURE(n);
    VolumeInfo info;
    info.dims = {n, n, n};
    std::vector<uint8_t> buf(n * n * n, 3);
    buf[((n - 1) * n + 5) * n + 2] = 200;  // one marked voxel: chunk (0, 5/8, (n-1)/8) of level 0
    MemorySlabSource src(info, {buf});
    ImportOptions opt;
    opt.chunk_size = 8;
    const std::string out = (test_dir("index_resident_" + std::to_string(n)) / "r.vxc").string();
    REQUIRE(build_container(src, out, opt).is_ok());
    auto r = ContainerReader::open(out);
    REQUIRE(r.is_ok());
    const ContainerReader& reader = **r;
    CHECK(reader.resident_index_bytes() == 0);  // open() streamed the index, kept none of it
    uint64_t marked = 0, lookups = 0;
    for (uint32_t l = 0; l < reader.levels().size(); ++l) {
      const auto& c = reader.levels()[l].chunk_counts;
      for (uint32_t z = 0; z < c[2]; ++z)
        for (uint32_t y = 0; y < c[1]; ++y)
          for (uint32_t x = 0; x < c[0]; ++x) {
            auto st = reader.stats({l, x, y, z, 0, 0});
            REQUIRE(st.is_ok());
            ++lookups;
            if (l == 0 && st->max == 200) ++marked;
            if (l == 0) CHECK(st->min == 3);
          }
    }
    CHECK(lookups == reader.chunk_count());
    CHECK(marked == 1);  // the marked voxel is interior: one level-0 chunk, not in anyone's apron
    CHECK(reader.stats({0, 2 / 8, 5 / 8, uint32_t((n - 1) / 8), 0, 0})->max == 200);
    CHECK(reader.resident_index_bytes() <= ContainerReader::kIndexCacheBytes);
    if (n == 24) {
      resident_small = reader.resident_index_bytes();
      CHECK(resident_small == reader.chunk_count() * sizeof(vxc::IndexEntry));  // a small index fits the cache
    } else {
      CHECK(reader.chunk_count() * sizeof(vxc::IndexEntry) > 4 * ContainerReader::kIndexCacheBytes);
      CHECK(reader.resident_index_bytes() < reader.chunk_count() * sizeof(vxc::IndexEntry) / 4);
    }
  }
}

TEST_CASE("writer: an unfinished file is never accepted and a leftover partial is not overwritten silently") {
  const fs::path dir = test_dir("partial");
  auto src = make_source(DType::kU8, {20, 20, 20});
  auto layout = import_layout(src.info(), ImportOptions{.chunk_size = 8});
  REQUIRE(layout.is_ok());
  const std::string out = (dir / "p.vxc").string();
  {
    auto w = ContainerWriter::create(out, *layout, false);
    REQUIRE(w.is_ok());
    // abandoned without finish()
  }
  CHECK_FALSE(fs::exists(out));
  CHECK(ContainerReader::open(out + ".partial").status().code() == ErrorCode::kCorrupt);
  CHECK(ContainerWriter::create(out, *layout, false).status().code() == ErrorCode::kInvalidArgument);
  ImportOptions opt;
  opt.chunk_size = 8;
  opt.resume = true;
  REQUIRE(build_container(src, out, opt).is_ok());
  CHECK(ContainerReader::open(out).is_ok());
  // A partial file from different settings is refused on resume.
  {
    auto w = ContainerWriter::create(out, *layout, false);
    REQUIRE(w.is_ok());
  }
  opt.chunk_size = 16;
  CHECK(build_container(src, out, opt).status().code() == ErrorCode::kInvalidArgument);
}

TEST_CASE("writer: an unwritable output path fails with an I/O error naming it and leaves no file") {
  auto src = make_source(DType::kU8, {10, 10, 10});
  const std::string out = "/proc/vxr_no_such_dir/x.vxc";
  auto s = build_container(src, out, {});
  CHECK(s.status().code() == ErrorCode::kIo);
  CHECK(s.status().message().find("/proc/vxr_no_such_dir/x.vxc.partial") != std::string::npos);
  CHECK_FALSE(fs::exists(out));
}

namespace {

// 4100 x 1030 x 1020 u8 (4.3e9 voxels > 2^32): zero everywhere except a few
// marked voxels at the far corners, generated on demand.
class HugeSparseSource final : public SlabSource {
 public:
  HugeSparseSource() {
    info_.dims = {4100, 1030, 1020};
    info_.dtype = DType::kU8;
  }
  const VolumeInfo& info() const override { return info_; }
  std::string format_name() const override { return "procedural"; }
  static uint8_t value(uint64_t x, uint64_t y, uint64_t z) {
    if (x == 4099 && y == 1029 && z == 1019) return 200;
    if (x == 4099 && y == 0 && z == 1019) return 150;
    if (x == 0 && y == 1029 && z == 0) return 100;
    if (x == 5 && y == 6 && z == 7) return 50;
    return 3;
  }
  Status read_region(uint32_t, uint32_t, const Box3& box, std::span<uint8_t> dst) override {
    if (dst.size() != box.voxels()) return invalid_argument("size");
    std::memset(dst.data(), 3, dst.size());
    const uint64_t marks[4][3] = {{4099, 1029, 1019}, {4099, 0, 1019}, {0, 1029, 0}, {5, 6, 7}};
    for (const auto& m : marks) {
      bool in = true;
      for (int a = 0; a < 3; ++a) in &= m[a] >= box.origin[a] && m[a] < box.origin[a] + box.size[a];
      if (in)
        dst[((m[2] - box.origin[2]) * box.size[1] + (m[1] - box.origin[1])) * box.size[0] + (m[0] - box.origin[0])] =
            value(m[0], m[1], m[2]);
    }
    return Status::ok();
  }

 private:
  VolumeInfo info_;
};

double chunk_voxel(const ContainerReader& r, uint32_t level, uint64_t x, uint64_t y, uint64_t z) {
  const uint32_t C = r.chunk_size(), A = r.apron();
  auto c = r.read({level, uint32_t(x / C), uint32_t(y / C), uint32_t(z / C), 0, 0});
  REQUIRE_MESSAGE(c.is_ok(), c.status().to_string());
  const uint64_t E = (*c)->edge;
  return (*c)->data[((z % C + A) * E + (y % C + A)) * E + (x % C + A)];
}

}  // namespace

TEST_CASE("container: a volume of more than 2^32 voxels converts and reads back its far corners") {
  const fs::path dir = test_dir("huge");
  HugeSparseSource src;
  REQUIRE(src.info().voxels_per_volume() > (uint64_t(1) << 32));
  ImportOptions opt;
  opt.chunk_size = 128;
  opt.memory_bytes = uint64_t(256) << 20;
  const std::string out = (dir / "huge.vxc").string();
  auto sum = build_container(src, out, opt);
  REQUIRE_MESSAGE(sum.is_ok(), sum.status().to_string());
  CHECK(fs::file_size(out) < (uint64_t(8) << 20));
  auto r = ContainerReader::open(out);
  REQUIRE(r.is_ok());
  CHECK((*r)->info().dims == std::array<uint64_t, 3>{4100, 1030, 1020});
  CHECK(chunk_voxel(**r, 0, 4099, 1029, 1019) == 200);
  CHECK(chunk_voxel(**r, 0, 4099, 0, 1019) == 150);
  CHECK(chunk_voxel(**r, 0, 0, 1029, 0) == 100);
  CHECK(chunk_voxel(**r, 0, 5, 6, 7) == 50);
  CHECK(chunk_voxel(**r, 0, 4098, 1029, 1019) == 3);
  CHECK(chunk_voxel(**r, 0, 2000, 500, 500) == 3);
  // Level 1 averages the far corner's 2x2x2 block (edge repeated: x=4099 is even-aligned, so 4098..4099).
  CHECK(chunk_voxel(**r, 1, 2049, 514, 509) == std::floor((200.0 + 7 * 3) / 8 + 0.5));
  CHECK(verify_container(out).ok());
}
