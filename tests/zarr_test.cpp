// OME-Zarr read in place (ZarrChunkSource) and imported (open_import_source):
// fixtures are written here by a small Zarr writer (v2 and v3, every codec,
// odd and oversized chunks, both separators, sharding, big-endian, F order,
// multiscales) and read back voxel for voxel; the real Neuroglancer files in
// ../shared/testdata/zarr are checked against the values SOURCES.md and their
// metadata give; malformed metadata and damaged chunks must give one-line
// errors naming the file and the key.
#include <doctest/doctest.h>

#include <algorithm>
#include <atomic>
#include <cmath>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <functional>
#include <nlohmann/json.hpp>
#include <string>
#include <thread>
#include <vector>

#include "cli_runner.h"
#include "volume/container_reader.h"
#include "volume/importers/import_source.h"
#include "volume/load_dense.h"
#include "volume/open_chunk_source.h"
#include "volume/zarr/ome_zarr.h"
#include "volume/zarr/zarr_array.h"
#include "volume/zarr/zarr_chunk_source.h"
#include "volume/zarr/zarr_codecs.h"

using namespace vxr;
namespace fs = std::filesystem;
using json = nlohmann::json;

namespace {

const std::string kData = VXR_TESTDATA_DIR;

fs::path scratch(const std::string& name) {
  const fs::path p = fs::path(VXR_TEST_OUT_DIR) / "zarr" / name;
  fs::remove_all(p);
  fs::create_directories(p);
  return p;
}

void write_file(const fs::path& p, const std::vector<uint8_t>& bytes) {
  fs::create_directories(p.parent_path());
  std::ofstream f(p, std::ios::binary);
  f.write(reinterpret_cast<const char*>(bytes.data()), static_cast<std::streamsize>(bytes.size()));
}
void write_text(const fs::path& p, const std::string& text) {
  write_file(p, std::vector<uint8_t>(text.begin(), text.end()));
}
std::string read_text(const fs::path& p) {
  std::ifstream f(p, std::ios::binary);
  return std::string(std::istreambuf_iterator<char>(f), {});
}

// ---- a small Zarr writer (test-only) -------------------------------------

// A typed N-d array in C order, values held as double (exact for every dtype used).
struct Volume {
  std::vector<uint64_t> shape;  // slowest first
  DType dtype = DType::kU16;
  std::vector<double> values;
  uint64_t count() const {
    uint64_t n = 1;
    for (uint64_t s : shape) n *= s;
    return n;
  }
  double at(const std::vector<uint64_t>& idx) const {
    uint64_t o = 0;
    for (size_t i = 0; i < shape.size(); ++i) o = o * shape[i] + idx[i];
    return values[o];
  }
};

// Deterministic, position-dependent values in the dtype's range (no two
// neighbours equal, so a one-voxel shift shows).
Volume make_volume(std::vector<uint64_t> shape, DType t, uint64_t seed = 1) {
  Volume v{std::move(shape), t, {}};
  v.values.resize(v.count());
  for (uint64_t i = 0; i < v.values.size(); ++i) {
    const uint64_t h = (i * 2654435761ull + seed * 97) % 1000003;
    switch (t) {
      case DType::kU8:
        v.values[i] = double(h % 251);
        break;
      case DType::kI8:
        v.values[i] = double(int(h % 251) - 125);
        break;
      case DType::kU16:
        v.values[i] = double(h % 65521);
        break;
      case DType::kI16:
        v.values[i] = double(int(h % 65521) - 32760);
        break;
      case DType::kU32:
        v.values[i] = double(h * 4099);
        break;
      case DType::kI32:
        v.values[i] = double(int64_t(h) * 2047 - 1000000000);
        break;
      case DType::kF32:
        v.values[i] = double(float(h) * 0.25f - 1000.0f);
        break;
    }
  }
  return v;
}

void put_value(DType t, double v, uint8_t* out) {
  switch (t) {
    case DType::kU8: {
      uint8_t x = uint8_t(v);
      std::memcpy(out, &x, 1);
      break;
    }
    case DType::kI8: {
      int8_t x = int8_t(v);
      std::memcpy(out, &x, 1);
      break;
    }
    case DType::kU16: {
      uint16_t x = uint16_t(v);
      std::memcpy(out, &x, 2);
      break;
    }
    case DType::kI16: {
      int16_t x = int16_t(v);
      std::memcpy(out, &x, 2);
      break;
    }
    case DType::kU32: {
      uint32_t x = uint32_t(v);
      std::memcpy(out, &x, 4);
      break;
    }
    case DType::kI32: {
      int32_t x = int32_t(v);
      std::memcpy(out, &x, 4);
      break;
    }
    case DType::kF32: {
      float x = float(v);
      std::memcpy(out, &x, 4);
      break;
    }
  }
}
double get_value(DType t, const uint8_t* p) {
  switch (t) {
    case DType::kU8:
      return *p;
    case DType::kI8:
      return int8_t(*p);
    case DType::kU16: {
      uint16_t x;
      std::memcpy(&x, p, 2);
      return x;
    }
    case DType::kI16: {
      int16_t x;
      std::memcpy(&x, p, 2);
      return x;
    }
    case DType::kU32: {
      uint32_t x;
      std::memcpy(&x, p, 4);
      return x;
    }
    case DType::kI32: {
      int32_t x;
      std::memcpy(&x, p, 4);
      return x;
    }
    case DType::kF32: {
      float x;
      std::memcpy(&x, p, 4);
      return x;
    }
  }
  return 0;
}

struct ArraySpec {
  int zarr_format = 2;
  std::vector<uint64_t> chunks;
  bool big_endian = false;
  bool fortran = false;  // v2 order "F"
  std::vector<zarr::BytesCodec> codecs;
  char separator = '.';         // v2 dimension_separator; v3 chunk key separator
  bool v3_v2_keys = false;      // v3 chunk_key_encoding "v2"
  std::vector<uint64_t> shard;  // v3 sharding: shard shape (chunks = inner shape)
  bool index_at_start = false;
  double fill = 0;
  bool omit_fill_chunks = false;  // chunks (inner chunks, shards) of only fill are not written
  std::vector<std::string> dimension_names;
};

std::string v2_dtype(DType t, bool big) {
  const char* body[] = {"u1", "i1", "u2", "i2", "u4", "i4", "f4"};
  return std::string(dtype_bytes(t) == 1 ? "|" : big ? ">" : "<") + body[int(t)];
}
std::string v3_dtype(DType t) {
  const char* n[] = {"uint8", "int8", "uint16", "int16", "uint32", "int32", "float32"};
  return n[int(t)];
}
json v2_compressor(const zarr::BytesCodec& c) {
  switch (c.id) {
    case zarr::CodecId::kGzip:
      return {{"id", "gzip"}, {"level", c.level}};
    case zarr::CodecId::kZlib:
      return {{"id", "zlib"}, {"level", c.level}};
    case zarr::CodecId::kZstd:
      return {{"id", "zstd"}, {"level", c.level}};
    case zarr::CodecId::kBlosc:
      return {{"id", "blosc"},
              {"cname", c.blosc_cname},
              {"clevel", c.level},
              {"shuffle", c.blosc_shuffle},
              {"blocksize", 0}};
    case zarr::CodecId::kLz4:
      return {{"id", "lz4"}, {"acceleration", 1}};
    default:
      return nullptr;
  }
}
json v3_codec(const zarr::BytesCodec& c) {
  const char* shuffles[] = {"noshuffle", "shuffle", "bitshuffle"};
  switch (c.id) {
    case zarr::CodecId::kGzip:
      return {{"name", "gzip"}, {"configuration", {{"level", c.level}}}};
    case zarr::CodecId::kZlib:
      return {{"name", "numcodecs.zlib"}, {"configuration", {{"level", c.level}}}};
    case zarr::CodecId::kZstd:
      return {{"name", "zstd"}, {"configuration", {{"level", c.level}, {"checksum", false}}}};
    case zarr::CodecId::kBlosc:
      return {{"name", "blosc"},
              {"configuration",
               {{"cname", c.blosc_cname},
                {"clevel", c.level},
                {"shuffle", shuffles[c.blosc_shuffle]},
                {"typesize", c.blosc_typesize},
                {"blocksize", 0}}}};
    case zarr::CodecId::kLz4:
      return {{"name", "numcodecs.lz4"}, {"configuration", {{"acceleration", 1}}}};
    case zarr::CodecId::kCrc32c:
      return {{"name", "crc32c"}};
  }
  return nullptr;
}

std::string key_of(const ArraySpec& s, const std::vector<uint64_t>& idx) {
  std::string k;
  if (s.zarr_format == 3 && !s.v3_v2_keys) k = std::string("c") + s.separator;
  for (size_t i = 0; i < idx.size(); ++i) {
    if (i) k.push_back(s.separator);
    k += std::to_string(idx[i]);
  }
  return k;
}

// Odometer over [0, extent) in C order.
bool next_index(std::vector<uint64_t>& idx, const std::vector<uint64_t>& extent) {
  for (size_t a = idx.size(); a-- > 0;) {
    if (++idx[a] < extent[a]) return true;
    idx[a] = 0;
  }
  return false;
}

// One chunk of `shape` at `origin` (elements past the array hold fill), in
// the stored byte order and memory order, encoded. Empty when it is all fill
// and the spec omits such chunks.
std::vector<uint8_t> encode_chunk(const Volume& v, const ArraySpec& s, const std::vector<uint64_t>& origin,
                                  bool& all_fill) {
  const size_t n = v.shape.size();
  const uint32_t item = dtype_bytes(v.dtype);
  uint64_t elems = 1;
  for (uint64_t c : s.chunks) elems *= c;
  std::vector<uint8_t> raw(elems * item);
  std::vector<uint64_t> i(n, 0);
  all_fill = true;
  do {
    std::vector<uint64_t> g(n);
    bool inside = true;
    for (size_t a = 0; a < n; ++a) g[a] = origin[a] + i[a], inside = inside && g[a] < v.shape[a];
    const double val = inside ? v.at(g) : s.fill;
    all_fill = all_fill && val == s.fill;
    // Memory order: C, or F (first index fastest) when asked.
    uint64_t off = 0;
    if (s.fortran) {
      for (size_t a = n; a-- > 0;) off = off * s.chunks[a] + i[a];
    } else {
      for (size_t a = 0; a < n; ++a) off = off * s.chunks[a] + i[a];
    }
    put_value(v.dtype, val, raw.data() + off * item);
  } while (next_index(i, s.chunks));
  if (s.big_endian)
    for (size_t k = 0; k < raw.size(); k += item) std::reverse(raw.begin() + k, raw.begin() + k + item);
  auto enc = zarr::encode_chain(s.codecs, raw);
  REQUIRE_MESSAGE(enc.is_ok(), enc.status().message());
  return *enc;
}

// Writes `v` as a Zarr array in `dir` (metadata and chunks).
void write_array(const fs::path& dir, const Volume& v, const ArraySpec& s) {
  const size_t n = v.shape.size();
  fs::create_directories(dir);
  if (s.zarr_format == 2) {
    json m = {{"zarr_format", 2},
              {"shape", v.shape},
              {"chunks", s.chunks},
              {"dtype", v2_dtype(v.dtype, s.big_endian)},
              {"fill_value", s.fill},
              {"order", s.fortran ? "F" : "C"},
              {"filters", nullptr},
              {"dimension_separator", std::string(1, s.separator)},
              {"compressor", s.codecs.empty() ? json(nullptr) : v2_compressor(s.codecs[0])}};
    write_text(dir / ".zarray", m.dump());
  } else {
    json inner = json::array();
    if (s.fortran) {
      std::vector<uint32_t> order(n);
      for (size_t a = 0; a < n; ++a) order[a] = uint32_t(n - 1 - a);
      inner.push_back({{"name", "transpose"}, {"configuration", {{"order", order}}}});
    }
    inner.push_back({{"name", "bytes"}, {"configuration", {{"endian", s.big_endian ? "big" : "little"}}}});
    for (const auto& c : s.codecs) inner.push_back(v3_codec(c));
    json codecs = inner;
    std::vector<uint64_t> grid = s.chunks;
    if (!s.shard.empty()) {
      grid = s.shard;
      codecs = json::array(
          {{{"name", "sharding_indexed"},
            {"configuration",
             {{"chunk_shape", s.chunks},
              {"codecs", inner},
              {"index_codecs",
               json::array({{{"name", "bytes"}, {"configuration", {{"endian", "little"}}}}, {{"name", "crc32c"}}})},
              {"index_location", s.index_at_start ? "start" : "end"}}}}});
    }
    json m = {
        {"zarr_format", 3},
        {"node_type", "array"},
        {"shape", v.shape},
        {"data_type", v3_dtype(v.dtype)},
        {"chunk_grid", {{"name", "regular"}, {"configuration", {{"chunk_shape", grid}}}}},
        {"chunk_key_encoding",
         {{"name", s.v3_v2_keys ? "v2" : "default"}, {"configuration", {{"separator", std::string(1, s.separator)}}}}},
        {"fill_value", s.fill},
        {"codecs", codecs},
        {"attributes", json::object()}};
    if (!s.dimension_names.empty()) m["dimension_names"] = s.dimension_names;
    write_text(dir / "zarr.json", m.dump());
  }
  const std::vector<uint64_t>& unit = s.shard.empty() ? s.chunks : s.shard;
  std::vector<uint64_t> count(n);
  for (size_t a = 0; a < n; ++a) count[a] = (v.shape[a] + unit[a] - 1) / unit[a];
  std::vector<uint64_t> ci(n, 0);
  do {
    std::vector<uint64_t> origin(n);
    for (size_t a = 0; a < n; ++a) origin[a] = ci[a] * unit[a];
    std::vector<uint8_t> bytes;
    bool all_fill = true;
    if (s.shard.empty()) {
      bytes = encode_chunk(v, s, origin, all_fill);
    } else {
      // A shard: inner chunks back to back, then (or first) the index and its crc32c.
      std::vector<uint64_t> per(n);
      for (size_t a = 0; a < n; ++a) per[a] = s.shard[a] / s.chunks[a];
      uint64_t inner_count = 1;
      for (uint64_t p : per) inner_count *= p;
      const uint64_t index_bytes = inner_count * 16 + 4;
      std::vector<uint8_t> index(inner_count * 16, 0xFF), body;
      std::vector<uint64_t> ii(n, 0);
      uint64_t linear = 0;
      do {
        std::vector<uint64_t> o(n);
        for (size_t a = 0; a < n; ++a) o[a] = origin[a] + ii[a] * s.chunks[a];
        bool inner_fill = true;
        bool outside = false;
        for (size_t a = 0; a < n; ++a) outside = outside || o[a] >= v.shape[a];
        std::vector<uint8_t> enc;
        if (!outside) enc = encode_chunk(v, s, o, inner_fill);
        all_fill = all_fill && (outside || inner_fill);
        if (!outside && !(inner_fill && s.omit_fill_chunks)) {
          const uint64_t off = (s.index_at_start ? index_bytes : 0) + body.size();
          for (int b = 0; b < 8; ++b) index[linear * 16 + b] = uint8_t(off >> (8 * b));
          for (int b = 0; b < 8; ++b) index[linear * 16 + 8 + b] = uint8_t(uint64_t(enc.size()) >> (8 * b));
          body.insert(body.end(), enc.begin(), enc.end());
        }
        ++linear;
      } while (next_index(ii, per));
      auto idx = zarr::encode({zarr::CodecId::kCrc32c}, index);
      REQUIRE(idx.is_ok());
      if (s.index_at_start) {
        bytes = *idx;
        bytes.insert(bytes.end(), body.begin(), body.end());
      } else {
        bytes = body;
        bytes.insert(bytes.end(), idx->begin(), idx->end());
      }
    }
    if (!(all_fill && s.omit_fill_chunks)) write_file(dir / key_of(s, ci), bytes);
  } while (next_index(ci, count));
}

struct LevelSpec {
  std::string path;
  std::vector<double> scale;
  std::vector<double> translation;
};

// The OME metadata of an image group: axes by name ("t","c","z","y","x"), unit for space axes.
void write_ome(const fs::path& dir, int zarr_format, const std::vector<std::string>& axes, const std::string& unit,
               const std::vector<LevelSpec>& levels) {
  json ax = json::array();
  for (const auto& a : axes) {
    json j = {{"name", a}, {"type", a == "t" ? "time" : a == "c" ? "channel" : "space"}};
    if (j["type"] == "space" && !unit.empty()) j["unit"] = unit;
    ax.push_back(j);
  }
  json ds = json::array();
  for (const auto& l : levels) {
    json t = json::array({{{"type", "scale"}, {"scale", l.scale}}});
    if (!l.translation.empty()) t.push_back({{"type", "translation"}, {"translation", l.translation}});
    ds.push_back({{"path", l.path}, {"coordinateTransformations", t}});
  }
  json ms = {{"axes", ax}, {"datasets", ds}, {"name", "test"}};
  if (zarr_format == 2) {
    ms["version"] = "0.4";
    write_text(dir / ".zgroup", R"({"zarr_format": 2})");
    write_text(dir / ".zattrs", json{{"multiscales", json::array({ms})}}.dump(1));
  } else {
    json g = {{"zarr_format", 3},
              {"node_type", "group"},
              {"attributes", {{"ome", {{"version", "0.5"}, {"multiscales", json::array({ms})}}}}}};
    write_text(dir / "zarr.json", g.dump(1));
  }
}

// A one-level z,y,x image of `v` with `spec`.
fs::path write_image(const std::string& name, const Volume& v, const ArraySpec& spec,
                     const std::string& unit = "micrometer", std::vector<double> scale = {}) {
  const fs::path dir = scratch(name);
  if (scale.empty()) scale.assign(v.shape.size(), 1.0);
  std::vector<std::string> axes;
  const char* names[] = {"t", "c", "z", "y", "x"};
  for (size_t i = 5 - v.shape.size(); i < 5; ++i) axes.push_back(names[i]);
  write_ome(dir, spec.zarr_format, axes, unit, {{"0", scale, {}}});
  write_array(dir / "0", v, spec);
  return dir;
}

// ---- checks ---------------------------------------------------------------

// Level-0 (x,y,z) value of a z,y,x or c,z,y,x volume (last three axes are space).
double voxel(const Volume& v, uint64_t x, uint64_t y, uint64_t z, uint64_t c = 0) {
  std::vector<uint64_t> idx;
  if (v.shape.size() == 4) idx.push_back(c);
  idx.insert(idx.end(), {z, y, x});
  if (v.shape.size() == 2) idx = {y, x};
  return v.at(idx);
}
std::array<uint64_t, 3> dims_xyz(const Volume& v) {
  const size_t n = v.shape.size();
  return {v.shape[n - 1], v.shape[n - 2], n >= 3 ? v.shape[n - 3] : 1};
}

// Whole-volume read through the import path equals the source.
void check_slab(const fs::path& dir, const Volume& v, uint32_t channel = 0) {
  auto src = open_import_source({dir.string()});
  REQUIRE_MESSAGE(src.is_ok(), src.status().message());
  const VolumeInfo& info = (*src)->info();
  REQUIRE(info.dims == dims_xyz(v));
  REQUIRE(info.dtype == v.dtype);
  Box3 box{{0, 0, 0}, info.dims};
  std::vector<uint8_t> buf(box.voxels() * dtype_bytes(v.dtype));
  const Status st = (*src)->read_region(channel, 0, box, buf);
  REQUIRE_MESSAGE(st.is_ok(), st.message());
  uint64_t i = 0, bad = 0;
  for (uint64_t z = 0; z < info.dims[2]; ++z)
    for (uint64_t y = 0; y < info.dims[1]; ++y)
      for (uint64_t x = 0; x < info.dims[0]; ++x, ++i)
        bad += get_value(v.dtype, buf.data() + i * dtype_bytes(v.dtype)) != voxel(v, x, y, z, channel);
  CHECK(bad == 0);
  // A sub-box that starts and ends inside chunks.
  Box3 sub{{1, 1, 0}, {info.dims[0] - 2, info.dims[1] - 1, info.dims[2]}};
  std::vector<uint8_t> part(sub.voxels() * dtype_bytes(v.dtype));
  REQUIRE((*src)->read_region(channel, 0, sub, part).is_ok());
  i = 0, bad = 0;
  for (uint64_t z = 0; z < sub.size[2]; ++z)
    for (uint64_t y = 0; y < sub.size[1]; ++y)
      for (uint64_t x = 0; x < sub.size[0]; ++x, ++i)
        bad += get_value(v.dtype, part.data() + i * dtype_bytes(v.dtype)) != voxel(v, x + 1, y + 1, z, channel);
  CHECK(bad == 0);
}

// Every chunk of level `level` of the chunk source: interior and apron equal
// the source volume at the clamped position (edge voxels repeat at borders).
void check_chunks(const ChunkSource& cs, uint32_t level, const Volume& lv, uint32_t channel = 0) {
  const LevelInfo& li = cs.levels()[level];
  REQUIRE(li.dims == dims_xyz(lv));
  const int64_t e = cs.chunk_size() + 2 * cs.apron();
  uint64_t bad = 0, checked = 0;
  for (uint32_t cz = 0; cz < li.chunk_counts[2]; ++cz)
    for (uint32_t cy = 0; cy < li.chunk_counts[1]; ++cy)
      for (uint32_t cx = 0; cx < li.chunk_counts[0]; ++cx) {
        auto ch = cs.read({level, cx, cy, cz, channel, 0});
        REQUIRE_MESSAGE(ch.is_ok(), ch.status().message());
        REQUIRE((*ch)->edge == e);
        REQUIRE((*ch)->data.size() == uint64_t(e * e * e) * dtype_bytes(lv.dtype));
        const std::array<uint32_t, 3> c{cx, cy, cz};
        double lo = INFINITY, hi = -INFINITY;
        for (int64_t z = 0; z < e; ++z)
          for (int64_t y = 0; y < e; ++y)
            for (int64_t x = 0; x < e; ++x) {
              std::array<int64_t, 3> p{x, y, z}, g;
              for (int a = 0; a < 3; ++a)
                g[a] = std::clamp<int64_t>(int64_t(c[a]) * cs.chunk_size() - cs.apron() + p[a], 0,
                                           int64_t(li.dims[a]) - 1);
              const double got =
                  get_value(lv.dtype, (*ch)->data.data() + ((z * e + y) * e + x) * dtype_bytes(lv.dtype));
              bad += got != voxel(lv, g[0], g[1], g[2], channel);
              lo = std::min(lo, got), hi = std::max(hi, got);
              ++checked;
            }
        CHECK((*ch)->stats.min == lo);
        CHECK((*ch)->stats.max == hi);
      }
  CHECK(checked > 0);
  CHECK(bad == 0);
}

std::unique_ptr<ZarrChunkSource> open_cs(const fs::path& dir, uint32_t chunk_size = 8) {
  auto cs = ZarrChunkSource::open(dir.string(), chunk_size, 1);
  REQUIRE_MESSAGE(cs.is_ok(), cs.status().message());
  return std::move(cs).value();
}

zarr::BytesCodec codec(zarr::CodecId id) {
  return zarr::BytesCodec{id};
}
zarr::BytesCodec blosc(const std::string& cname, int shuffle, uint32_t typesize) {
  zarr::BytesCodec c{zarr::CodecId::kBlosc};
  c.blosc_cname = cname;
  c.blosc_shuffle = shuffle;
  c.blosc_typesize = typesize;
  return c;
}

struct CodecCase {
  const char* name;
  std::vector<zarr::BytesCodec> codecs;
};
std::vector<CodecCase> codec_cases() {
  return {{"raw", {}},
          {"gzip", {codec(zarr::CodecId::kGzip)}},
          {"zlib", {codec(zarr::CodecId::kZlib)}},
          {"zstd", {codec(zarr::CodecId::kZstd)}},
          {"blosc-lz4-shuffle", {blosc("lz4", 1, 2)}},
          {"blosc-zstd-bitshuffle", {blosc("zstd", 2, 2)}},
          {"blosc-zlib-noshuffle", {blosc("zlib", 0, 2)}},
          {"lz4", {codec(zarr::CodecId::kLz4)}}};
}

// The first line of an error, and that it is the only one.
void check_one_line(const Status& st, const std::vector<std::string>& parts) {
  REQUIRE_FALSE(st.is_ok());
  INFO(st.message());
  CHECK(st.message().find('\n') == std::string::npos);
  for (const auto& p : parts) CHECK(st.message().find(p) != std::string::npos);
}

}  // namespace

TEST_CASE("zarr: every codec, v2 and v3, odd 7x5x3 chunks: import and chunk source read back the source voxels") {
  const Volume v = make_volume({13, 11, 17}, DType::kU16);
  for (int format : {2, 3})
    for (const CodecCase& cc : codec_cases()) {
      CAPTURE(format);
      CAPTURE(cc.name);
      ArraySpec s;
      s.zarr_format = format;
      s.chunks = {7, 5, 3};
      s.codecs = cc.codecs;
      s.separator = format == 2 ? '.' : '/';
      const fs::path dir = write_image(std::string("codec_v") + std::to_string(format) + "_" + cc.name, v, s);
      check_slab(dir, v);
      auto cs = open_cs(dir);
      REQUIRE(cs->levels().size() == 1);
      check_chunks(*cs, 0, v);
    }
}

TEST_CASE("zarr: v3 crc32c codec after gzip detects a flipped byte and names the chunk") {
  const Volume v = make_volume({4, 6, 8}, DType::kU8);
  ArraySpec s;
  s.zarr_format = 3;
  s.chunks = {4, 6, 8};
  s.separator = '/';
  s.codecs = {codec(zarr::CodecId::kGzip), codec(zarr::CodecId::kCrc32c)};
  const fs::path dir = write_image("crc32c", v, s);
  check_slab(dir, v);
  auto bytes = read_text(dir / "0/c/0/0/0");
  bytes[bytes.size() / 2] ^= 0x10;
  write_text(dir / "0/c/0/0/0", bytes);
  auto cs = open_cs(dir);
  auto r = cs->read({0, 0, 0, 0, 0, 0});
  check_one_line(r.status(), {"0/c/0/0/0", "crc32c"});
  CHECK(r.status().code() == ErrorCode::kCorrupt);
}

TEST_CASE("zarr: chunks larger than the array, and a 2-D y,x image, read as one z slice") {
  const Volume v = make_volume({5, 6, 7}, DType::kU8);
  for (int format : {2, 3}) {
    CAPTURE(format);
    ArraySpec s;
    s.zarr_format = format;
    s.chunks = {16, 16, 16};
    s.codecs = {codec(zarr::CodecId::kZstd)};
    const fs::path dir = write_image("oversized_v" + std::to_string(format), v, s);
    check_slab(dir, v);
    check_chunks(*open_cs(dir), 0, v);
  }
  const Volume flat = make_volume({9, 14}, DType::kU16);
  ArraySpec s;
  s.chunks = {4, 4};
  const fs::path dir = write_image("flat2d", flat, s, "nanometer", {3.0, 5.0});
  auto img = zarr::OmeZarrImage::open(dir.string());
  REQUIRE_MESSAGE(img.is_ok(), img.status().message());
  CHECK((*img)->info().dims == std::array<uint64_t, 3>{14, 9, 1});
  CHECK((*img)->info().unit == "nm");
  CHECK((*img)->info().voxel_size == std::array<double, 3>{5.0, 3.0, 5.0});  // z as thick as x is wide
  check_slab(dir, flat);
  check_chunks(*open_cs(dir), 0, flat);
}

TEST_CASE("zarr: chunk keys with '.' and '/' separators, v3 default and v2 encodings") {
  const Volume v = make_volume({6, 7, 9}, DType::kI16);
  struct Case {
    int format;
    char sep;
    bool v2_keys;
    const char* first_chunk;  // the key of chunk (0,0,0) on disk
  };
  for (const Case& c : {Case{2, '.', false, "0.0.0"}, Case{2, '/', false, "0/0/0"}, Case{3, '/', false, "c/0/0/0"},
                        Case{3, '.', false, "c.0.0.0"}, Case{3, '.', true, "0.0.0"}}) {
    CAPTURE(c.format);
    CAPTURE(c.sep);
    ArraySpec s;
    s.zarr_format = c.format;
    s.chunks = {4, 4, 4};
    s.separator = c.sep;
    s.v3_v2_keys = c.v2_keys;
    s.codecs = {codec(zarr::CodecId::kGzip)};
    const fs::path dir = write_image(std::string("sep_") + std::to_string(c.format) + (c.sep == '.' ? "dot" : "slash") +
                                         (c.v2_keys ? "_v2keys" : ""),
                                     v, s);
    REQUIRE(fs::is_regular_file(dir / "0" / c.first_chunk));
    check_slab(dir, v);
    check_chunks(*open_cs(dir), 0, v);
  }
}

TEST_CASE("zarr: v3 sharding (index at the end and at the start, missing inner chunks and shards) reads the source") {
  // Values zero in the last 6 z slices: whole shards and inner chunks of only fill are left out.
  Volume v = make_volume({16, 10, 13}, DType::kU16);
  for (uint64_t i = 10 * 10 * 13; i < v.values.size(); ++i) v.values[i] = 0;
  for (bool at_start : {false, true}) {
    CAPTURE(at_start);
    ArraySpec s;
    s.zarr_format = 3;
    s.chunks = {2, 5, 3};
    s.shard = {4, 10, 6};
    s.index_at_start = at_start;
    s.omit_fill_chunks = true;
    s.codecs = {blosc("lz4", 1, 2)};
    const fs::path dir = write_image(std::string("shard_") + (at_start ? "start" : "end"), v, s);
    CHECK_FALSE(fs::exists(dir / "0/c/3/0/0"));  // z 12..15: all fill, no shard
    check_slab(dir, v);
    check_chunks(*open_cs(dir), 0, v);
  }
}

TEST_CASE("zarr: big-endian u16 (v2 '>u2', v3 bytes endian big) and F order read as native C order") {
  const Volume v = make_volume({5, 9, 11}, DType::kU16);
  for (int format : {2, 3})
    for (bool fortran : {false, true}) {
      CAPTURE(format);
      CAPTURE(fortran);
      ArraySpec s;
      s.zarr_format = format;
      s.chunks = {3, 4, 5};
      s.big_endian = true;
      s.fortran = fortran;
      s.codecs = {codec(zarr::CodecId::kGzip)};
      const fs::path dir = write_image("bigendian_v" + std::to_string(format) + (fortran ? "_F" : "_C"), v, s);
      if (format == 2) CHECK(read_text(dir / "0/.zarray").find(">u2") != std::string::npos);
      check_slab(dir, v);
      check_chunks(*open_cs(dir), 0, v);
    }
}

TEST_CASE("zarr: dtypes u8 i8 i16 u32 i32 f32 read back exactly") {
  for (DType t : {DType::kU8, DType::kI8, DType::kI16, DType::kU32, DType::kI32, DType::kF32})
    for (int format : {2, 3}) {
      CAPTURE(dtype_name(t));
      CAPTURE(format);
      const Volume v = make_volume({4, 5, 6}, t, 3);
      ArraySpec s;
      s.zarr_format = format;
      s.chunks = {3, 3, 3};
      s.codecs = {blosc("lz4", 1, dtype_bytes(t))};
      const fs::path dir = write_image(std::string("dtype_") + dtype_name(t) + "_v" + std::to_string(format), v, s);
      check_slab(dir, v);
      check_chunks(*open_cs(dir), 0, v);
    }
}

TEST_CASE("zarr: a missing chunk reads as fill_value, a truncated chunk is an error naming its key") {
  const Volume v0 = make_volume({6, 6, 6}, DType::kU16);
  Volume v = v0;
  ArraySpec s;
  s.zarr_format = 2;
  s.chunks = {3, 3, 3};
  s.fill = 4242;
  s.codecs = {codec(zarr::CodecId::kZstd)};
  const fs::path dir = write_image("fill", v, s);
  fs::remove(dir / "0/1.0.1");  // chunk z 3..5, y 0..2, x 3..5
  for (uint64_t z = 3; z < 6; ++z)
    for (uint64_t y = 0; y < 3; ++y)
      for (uint64_t x = 3; x < 6; ++x) v.values[(z * 6 + y) * 6 + x] = 4242;
  check_slab(dir, v);
  check_chunks(*open_cs(dir, 8), 0, v);

  std::string bytes = read_text(dir / "0/0.0.0");
  write_text(dir / "0/0.0.0", bytes.substr(0, bytes.size() / 2));
  auto src = open_import_source({dir.string()});
  REQUIRE(src.is_ok());
  std::vector<uint8_t> buf(6 * 6 * 6 * 2);
  const Status st = (*src)->read_region(0, 0, Box3{{0, 0, 0}, {6, 6, 6}}, buf);
  check_one_line(st, {(dir / "0/0.0.0").string(), "zstd"});
  CHECK(st.code() == ErrorCode::kCorrupt);

  write_text(dir / "0/0.0.0", "this is not a zstd frame at all");
  auto cs = open_cs(dir);
  check_one_line(cs->read({0, 0, 0, 0, 0, 0}).status(), {"0/0.0.0", "does not decode"});
}

TEST_CASE("zarr: a 3-level multiscale (anisotropic first step) gives levels with the scale transforms' factors") {
  // Level 1 halves x and y only (z is already coarse), level 2 halves all three.
  const Volume l0 = make_volume({6, 20, 24}, DType::kU16, 1);
  const Volume l1 = make_volume({6, 10, 12}, DType::kU16, 2);
  const Volume l2 = make_volume({3, 5, 6}, DType::kU16, 3);
  for (int format : {2, 3}) {
    CAPTURE(format);
    const fs::path dir = scratch("multiscale_v" + std::to_string(format));
    write_ome(dir, format, {"z", "y", "x"}, "micrometer",
              {{"s0", {2.0, 0.5, 0.5}, {0, 0, 0}},
               {"s1", {2.0, 1.0, 1.0}, {0, 0.25, 0.25}},
               {"s2", {4.0, 2.0, 2.0}, {1, 0.75, 0.75}}});
    ArraySpec s;
    s.zarr_format = format;
    s.chunks = {4, 8, 8};
    s.codecs = {codec(zarr::CodecId::kGzip)};
    write_array(dir / "s0", l0, s);
    write_array(dir / "s1", l1, s);
    write_array(dir / "s2", l2, s);
    auto cs = open_cs(dir, 8);
    REQUIRE(cs->levels().size() == 3);
    CHECK(cs->levels()[0].downsample == std::array<uint32_t, 3>{1, 1, 1});
    CHECK(cs->levels()[1].downsample == std::array<uint32_t, 3>{2, 2, 1});
    CHECK(cs->levels()[2].downsample == std::array<uint32_t, 3>{4, 4, 2});
    CHECK(cs->info().voxel_size == std::array<double, 3>{0.5, 0.5, 2.0});
    CHECK(cs->info().unit == "um");
    check_chunks(*cs, 0, l0);
    check_chunks(*cs, 1, l1);
    check_chunks(*cs, 2, l2);
    check_slab(dir, l0);  // import reads level 0
  }
}

TEST_CASE("zarr: the translation is the volume's origin, read in place, imported into the .vxc and shown by info") {
  const Volume l0 = make_volume({4, 6, 8}, DType::kU8, 1);
  const fs::path dir = scratch("translation");
  // z y x order in the file; x y z in VolumeInfo. Millimetres: converted like the voxel size.
  write_ome(dir, 2, {"z", "y", "x"}, "millimeter", {{"0", {2.0, 0.5, 0.25}, {10.0, 20.5, -3.0}}});
  ArraySpec s;
  s.zarr_format = 2;
  s.chunks = {4, 6, 8};
  write_array(dir / "0", l0, s);
  auto cs = open_cs(dir, 8);
  CHECK(cs->info().unit == "mm");
  CHECK(cs->info().origin == std::array<double, 3>{-3.0, 20.5, 10.0});
  auto slab = open_import_source({dir.string()});
  REQUIRE(slab.is_ok());
  CHECK((*slab)->info().origin == std::array<double, 3>{-3.0, 20.5, 10.0});
  // Through `vxr import` into the container header, and back out of `vxr info`.
  const fs::path vxc = dir.parent_path() / "translation.vxc";
  const vxr::test::CliRun imp = vxr::test::run_vxr("import " + dir.string() + " -o " + vxc.string(), dir.parent_path());
  REQUIRE_MESSAGE(imp.rc == 0, imp.err);
  auto reader = ContainerReader::open(vxc.string());
  REQUIRE(reader.is_ok());
  CHECK((*reader)->info().origin == std::array<double, 3>{-3.0, 20.5, 10.0});
  const vxr::test::CliRun info = vxr::test::run_vxr("info " + vxc.string(), dir.parent_path());
  CHECK(info.out.find("origin:      -3, 20.5, 10 mm\n") != std::string::npos);
  const vxr::test::CliRun j = vxr::test::run_vxr("info --json " + vxc.string(), dir.parent_path());
  CHECK(json::parse(j.out).at("origin") == json::array({-3.0, 20.5, 10.0}));
}

TEST_CASE("zarr: a level that is not a 2x step ends the chunk source's pyramid, with a warning naming it") {
  const fs::path dir = scratch("multiscale_3x");
  const Volume l0 = make_volume({9, 9, 9}, DType::kU8), l1 = make_volume({3, 3, 3}, DType::kU8);
  write_ome(dir, 2, {"z", "y", "x"}, "", {{"a", {1, 1, 1}, {}}, {"b", {3, 3, 3}, {}}});
  ArraySpec s;
  s.chunks = {4, 4, 4};
  write_array(dir / "a", l0, s);
  write_array(dir / "b", l1, s);
  auto cs = open_cs(dir);
  CHECK(cs->levels().size() == 1);
  REQUIRE(cs->warnings().size() == 1);
  CHECK(cs->warnings()[0].find("'b'") != std::string::npos);
  CHECK(cs->info().unit == "px");
}

TEST_CASE("zarr: t and c axes select timepoints and channels") {
  const fs::path dir = scratch("tczyx");
  // 2 timepoints x 3 channels x 4 x 5 x 6; the writer's channel helper covers c,z,y,x, so index t by hand.
  Volume v = make_volume({2, 3, 4, 5, 6}, DType::kU16);
  write_ome(dir, 3, {"t", "c", "z", "y", "x"}, "micrometer", {{"0", {1, 1, 1, 1, 1}, {}}});
  ArraySpec s;
  s.zarr_format = 3;
  s.chunks = {1, 2, 3, 3, 3};
  s.codecs = {codec(zarr::CodecId::kZstd)};
  write_array(dir / "0", v, s);
  auto src = open_import_source({dir.string()});
  REQUIRE_MESSAGE(src.is_ok(), src.status().message());
  CHECK((*src)->info().channels == 3);
  CHECK((*src)->info().timepoints == 2);
  auto cs = open_cs(dir);
  for (uint32_t t = 0; t < 2; ++t)
    for (uint32_t c = 0; c < 3; ++c) {
      std::vector<uint8_t> buf(4 * 5 * 6 * 2);
      REQUIRE((*src)->read_region(c, t, Box3{{0, 0, 0}, {6, 5, 4}}, buf).is_ok());
      auto ch = cs->read({0, 0, 0, 0, c, t});
      REQUIRE(ch.is_ok());
      uint64_t bad = 0;
      for (uint64_t z = 0; z < 4; ++z)
        for (uint64_t y = 0; y < 5; ++y)
          for (uint64_t x = 0; x < 6; ++x) {
            const double want = v.at({t, c, z, y, x});
            bad += get_value(DType::kU16, buf.data() + ((z * 5 + y) * 6 + x) * 2) != want;
            bad += get_value(DType::kU16, (*ch)->data.data() + (((z + 1) * 10 + y + 1) * 10 + x + 1) * 2) != want;
          }
      CHECK(bad == 0);
    }
  CHECK(cs->read({0, 0, 0, 0, 3, 0}).status().code() == ErrorCode::kNotFound);
}

TEST_CASE("zarr: stats are the dtype's range until a chunk is read, then its exact payload range") {
  const Volume v = make_volume({4, 4, 4}, DType::kU8);
  ArraySpec s;
  s.chunks = {4, 4, 4};
  const fs::path dir = write_image("stats", v, s);
  auto cs = open_cs(dir);
  auto before = cs->stats({0, 0, 0, 0, 0, 0});
  REQUIRE(before.is_ok());
  CHECK(before->min == 0);
  CHECK(before->max == 255);
  auto ch = cs->read({0, 0, 0, 0, 0, 0});
  REQUIRE(ch.is_ok());
  auto after = cs->stats({0, 0, 0, 0, 0, 0});
  CHECK(after->min == *std::min_element(v.values.begin(), v.values.end()));
  CHECK(after->max == *std::max_element(v.values.begin(), v.values.end()));
  CHECK(cs->stats({0, 1, 0, 0, 0, 0}).status().code() == ErrorCode::kNotFound);
}

TEST_CASE("zarr: concurrent chunk reads agree, and the decoded-chunk cache stays within its budget") {
  const Volume v = make_volume({24, 24, 24}, DType::kU16);
  ArraySpec s;
  s.chunks = {6, 6, 6};  // 432 B a chunk decoded
  s.codecs = {codec(zarr::CodecId::kGzip)};
  const fs::path dir = write_image("threads", v, s);
  auto img = zarr::OmeZarrImage::open(dir.string(), 8 << 20);
  REQUIRE(img.is_ok());
  std::shared_ptr<const zarr::OmeZarrImage> shared = std::move(img).value();
  auto cs_r = ZarrChunkSource::create(shared, 8, 1);
  REQUIRE(cs_r.is_ok());
  const ChunkSource& cs = **cs_r;
  std::atomic<int> bad{0};
  std::vector<std::thread> threads;
  for (int t = 0; t < 4; ++t)
    threads.emplace_back([&, t] {
      for (int rep = 0; rep < 3; ++rep)
        for (uint32_t i = 0; i < 27; ++i) {
          const uint32_t k = (i + t * 7) % 27;
          auto ch = cs.read({0, k % 3, (k / 3) % 3, k / 9, 0, 0});
          if (!ch) {
            ++bad;
            continue;
          }
          // interior voxel (0,0,0) of the chunk
          const uint64_t x = (k % 3) * 8, y = ((k / 3) % 3) * 8, z = (k / 9) * 8;
          if (get_value(DType::kU16, (*ch)->data.data() + ((1 * 10 + 1) * 10 + 1) * 2) != voxel(v, x, y, z)) ++bad;
        }
    });
  for (auto& th : threads) th.join();
  CHECK(bad == 0);
  const zarr::ZarrArray& a = *shared->levels()[0].array;
  CHECK(a.cached_bytes() > 0);
  CHECK(a.cached_bytes() <= uint64_t(8) << 20);

  // A budget of a few chunks: reading everything decodes again instead of growing.
  auto store = std::make_shared<zarr::DirectoryStore>((dir / "0").string());
  auto small = zarr::ZarrArray::open(store, "", 2000);
  REQUIRE(small.is_ok());
  std::vector<uint8_t> all(24 * 24 * 24 * 2);
  const std::vector<uint64_t> start{0, 0, 0}, size{24, 24, 24};
  REQUIRE((*small)->read(start, size, all).is_ok());
  REQUIRE((*small)->read(start, size, all).is_ok());
  CHECK((*small)->cached_bytes() <= 2000);
  CHECK((*small)->decodes() == 2 * 64);
}

TEST_CASE("zarr: Neuroglancer simple_0.4 (v2, blosc-lz4) and simple_0.5 (v3, raw) read as SOURCES.md says") {
  // Level 0 is 10x10 u16 holding 10*y + x (the raw v3 chunk shows it); level 1
  // and 2 values as stored (5x5, 2x2). Scales [4,30] nm (y,x), 2x and 4x.
  const std::vector<double> level1 = {2,  3,  6,  7,  9,  20, 21, 23, 25, 26, 39, 41, 43,
                                      45, 47, 59, 61, 63, 65, 67, 79, 81, 82, 85, 86};
  const std::vector<double> level2 = {5, 8, 39, 42};
  for (const char* name : {"simple_0.4", "simple_0.5"}) {
    CAPTURE(name);
    const std::string dir = kData + "/zarr/" + name;
    Volume l0{{10, 10}, DType::kU16, {}};
    for (int i = 0; i < 100; ++i) l0.values.push_back(i);
    check_slab(dir, l0);
    auto src = open_import_source({dir});
    REQUIRE(src.is_ok());
    CHECK((*src)->info().unit == "nm");
    CHECK((*src)->info().voxel_size == std::array<double, 3>{30.0, 4.0, 30.0});
    CHECK((*src)->format_name() == std::string("OME-Zarr ") + (name[9] == '4' ? "0.4 (Zarr v2)" : "0.5 (Zarr v3)"));
    auto cs = open_cs(dir);
    REQUIRE(cs->levels().size() == 3);
    CHECK(cs->levels()[1].downsample == std::array<uint32_t, 3>{2, 2, 1});
    CHECK(cs->levels()[2].downsample == std::array<uint32_t, 3>{4, 4, 1});
    check_chunks(*cs, 0, l0);
    check_chunks(*cs, 1, Volume{{5, 5}, DType::kU16, level1});
    check_chunks(*cs, 2, Volume{{2, 2}, DType::kU16, level2});
    auto opened = open_chunk_source(dir);
    REQUIRE(opened.is_ok());
    CHECK(is_chunk_source_input(dir));
  }
}

TEST_CASE("zarr: load_for_render draws a chunk-source level of an OME-Zarr (what vxr view shows)") {
  auto loaded = load_for_render(kData + "/zarr/simple_0.5", 1024, uint64_t(1) << 30);
  REQUIRE_MESSAGE(loaded.is_ok(), loaded.status().message());
  REQUIRE(loaded->channels.size() == 1);
  CHECK(loaded->format == "OME-Zarr 0.5 (Zarr v3)");
  CHECK(loaded->channels[0].dims == std::array<uint32_t, 3>{10, 10, 1});
  CHECK(loaded->channels[0].value_at(7, 3, 0) == 37);
}

TEST_CASE("zarr: malformed metadata gives one line naming the file and the key") {
  const Volume v = make_volume({4, 4, 4}, DType::kU8);
  struct Case {
    int format;
    const char* file;  // relative to the image folder
    std::function<void(json&)> edit;
    const char* key;  // what the message must name
  };
  const std::vector<Case> cases = {
      {2, "0/.zarray",
       [](json& j) {
         j["chunks"] = {4, 0, 4};
       },
       "'chunks' must be a list of 3 positive integers"},
      {2, "0/.zarray", [](json& j) { j["chunks"] = "big"; }, "'chunks'"},
      {2, "0/.zarray", [](json& j) { j["shape"] = {4}; }, "'shape' must be a list of 2..5"},
      {2, "0/.zarray", [](json& j) { j["dtype"] = "<f8"; }, "'dtype' '<f8' is not read"},
      {2, "0/.zarray", [](json& j) { j["dtype"] = 7; }, "'dtype' must be"},
      {2, "0/.zarray",
       [](json& j) {
         j["compressor"] = {{"id", "lzma"}};
       },
       "'compressor': unknown id 'lzma'"},
      {2, "0/.zarray", [](json& j) { j["order"] = "K"; }, "'order'"},
      {2, "0/.zarray", [](json& j) { j["fill_value"] = 300; }, "'fill_value'"},
      {2, "0/.zarray",
       [](json& j) {
         j["filters"] = json::array({{{"id", "delta"}}});
       },
       "'filters'"},
      {2, "0/.zarray", [](json& j) { j["dimension_separator"] = "-"; }, "'dimension_separator'"},
      {2, ".zattrs", [](json& j) { j["multiscales"][0].erase("datasets"); }, "'datasets'"},
      {2, ".zattrs", [](json& j) { j["multiscales"][0]["axes"].erase(0); }, "'axes' must be a list of 3 axes"},
      {2, ".zattrs",
       [](json& j) {
         j["multiscales"][0]["datasets"][0]["coordinateTransformations"][0]["scale"] = {1, 1};
       },
       "'coordinateTransformations'[0]: 'scale' must be a list of 3 numbers"},
      {2, ".zattrs", [](json& j) { j["multiscales"][0]["datasets"][0]["path"] = 5; }, "'datasets'[0] must have"},
      {2, ".zattrs", [](json& j) { j.erase("multiscales"); }, "no 'multiscales'"},
      {2, ".zattrs",
       [](json& j) {
         j["multiscales"][0]["axes"][0]["type"] = "time";
         j["multiscales"][0]["axes"][1]["type"] = "time";
       },
       "more than one time axis"},
      {3, "0/zarr.json",
       [](json& j) {
         j["codecs"][1] = {{"name", "foo"}};
       },
       "'codecs'[1]: codec 'foo' is not read"},
      {3, "0/zarr.json", [](json& j) { j["data_type"] = "float64"; }, "'data_type' 'float64'"},
      {3, "0/zarr.json", [](json& j) { j["chunk_grid"]["name"] = "irregular"; }, "'chunk_grid'"},
      {3, "0/zarr.json",
       [](json& j) {
         j["chunk_grid"]["configuration"]["chunk_shape"] = {4, 4};
       },
       "'chunk_grid': 'chunk_shape'"},
      {3, "0/zarr.json", [](json& j) { j["chunk_key_encoding"]["name"] = "odd"; }, "'chunk_key_encoding'"},
      {3, "0/zarr.json", [](json& j) { j.erase("fill_value"); }, "'fill_value' is missing"},
      {3, "zarr.json", [](json& j) { j["attributes"]["ome"]["multiscales"] = json::object(); },
       "'multiscales' must be a non-empty list"},
      {3, "0/zarr.json",
       [](json& j) {
         j["shape"] = {4, 4, uint64_t(1) << 41};
       },
       "'shape' has a side over 2^40"},
      {2, "0/.zarray",
       [](json& j) {
         j["shape"] = {4, 4, -4};
       },
       "'shape' must be a list of 2..5 non-negative integers"},
  };
  int i = 0;
  for (const Case& c : cases) {
    CAPTURE(c.key);
    ArraySpec s;
    s.zarr_format = c.format;
    s.chunks = {4, 4, 4};
    s.codecs = {codec(zarr::CodecId::kGzip)};
    const fs::path dir = write_image("malformed_" + std::to_string(i++), v, s);
    json j = json::parse(read_text(dir / c.file));
    c.edit(j);
    write_text(dir / c.file, j.dump());
    auto src = open_import_source({dir.string()});
    check_one_line(src.status(), {(dir / c.file).string(), c.key});
    auto cs = ZarrChunkSource::open(dir.string());
    check_one_line(cs.status(), {(dir / c.file).string(), c.key});
  }
  // Not JSON at all.
  ArraySpec s;
  s.chunks = {4, 4, 4};
  const fs::path dir = write_image("malformed_text", v, s);
  write_text(dir / "0/.zarray", "{\"zarr_format\": 2, \"shape\": [4, 4");
  check_one_line(open_import_source({dir.string()}).status(), {(dir / "0/.zarray").string(), "not valid JSON"});
  // A .zarr folder with no metadata is not mistaken for a slice folder.
  const fs::path empty = scratch("nothing.zarr");
  check_one_line(open_import_source({empty.string()}).status(), {"nothing.zarr", "zarr.json"});
  check_one_line(open_import_source({empty.string() + "/"}).status(), {"nothing.zarr", "zarr.json"});
}

TEST_CASE("zarr: a bare Zarr array and a bioformats2raw folder open without OME multiscales at the top") {
  const Volume v = make_volume({5, 6, 7}, DType::kU16);
  ArraySpec s;
  s.chunks = {4, 4, 4};
  s.codecs = {codec(zarr::CodecId::kGzip)};
  const fs::path bare = scratch("bare_array");
  write_array(bare, v, s);  // .zarray at the top: axes by rank (z, y, x)
  check_slab(bare, v);
  check_chunks(*open_cs(bare), 0, v);

  auto bare_src = open_import_source({bare.string()});
  REQUIRE(bare_src.is_ok());
  CHECK((*bare_src)->files() == std::vector<std::string>{(bare / ".zarray").string()});

  const fs::path b2r = scratch("b2r.zarr");
  write_text(b2r / ".zgroup", R"({"zarr_format": 2})");
  write_text(b2r / ".zattrs", R"({"bioformats2raw.layout": 3})");
  write_ome(b2r / "0", 2, {"z", "y", "x"}, "micrometer", {{"0", {1, 1, 1}, {}}});
  write_array(b2r / "0" / "0", v, s);
  check_slab(b2r, v);
}

TEST_CASE("zarr: slice-shaped chunks (1 x 64 x 64) are decoded once each when the chunk source reads every chunk") {
  // bioformats2raw writes one z slice per chunk; a payload spans `edge` of
  // them. With a 1000-byte budget nothing would stay cached (every payload
  // decoding ~10 slices again); the chunk source raises it to two payloads' worth.
  const Volume v = make_volume({20, 64, 64}, DType::kU8);
  ArraySpec s;
  s.chunks = {1, 64, 64};
  const fs::path dir = write_image("slices", v, s);
  auto img = zarr::OmeZarrImage::open(dir.string(), 1000);
  REQUIRE(img.is_ok());
  std::shared_ptr<const zarr::OmeZarrImage> shared = std::move(img).value();
  auto cs = ZarrChunkSource::create(shared, 8, 1);
  REQUIRE(cs.is_ok());
  const zarr::ZarrArray& a = *shared->levels()[0].array;
  CHECK(a.cache_budget() == 2 * 10 * 64 * 64);  // 10 slices of 64 x 64 u8 per payload
  check_chunks(**cs, 0, v);
  CHECK(a.decodes() == 20);
}

TEST_CASE(
    "zarr: damaged copies (flipped bytes, truncation) of blosc, gzip and sharded fixtures fail cleanly, never crash") {
  // Each damaged copy either still reads (a flip the format cannot notice,
  // e.g. inside raw voxels) or fails with a one-line message; a crash fails
  // the whole test binary.
  const Volume v = make_volume({6, 10, 12}, DType::kU16);
  struct Fixture {
    const char* name;
    ArraySpec spec;
  };
  std::vector<Fixture> fixtures(3);
  fixtures[0].name = "fuzz_blosc";
  fixtures[0].spec.chunks = {3, 5, 6};
  fixtures[0].spec.codecs = {blosc("lz4", 1, 2)};
  fixtures[1].name = "fuzz_gzip_v3";
  fixtures[1].spec.zarr_format = 3;
  fixtures[1].spec.chunks = {3, 5, 6};
  fixtures[1].spec.codecs = {codec(zarr::CodecId::kGzip)};
  fixtures[2].name = "fuzz_shard";
  fixtures[2].spec.zarr_format = 3;
  fixtures[2].spec.chunks = {3, 5, 3};
  fixtures[2].spec.shard = {6, 10, 6};
  fixtures[2].spec.codecs = {blosc("zstd", 2, 2)};
  uint64_t rng = 12345;
  auto next = [&] { return rng = rng * 6364136223846793005ull + 1442695040888963407ull, rng >> 33; };
  int failures = 0, reads = 0;
  for (const Fixture& f : fixtures) {
    const fs::path clean = write_image(f.name, v, f.spec);
    std::vector<fs::path> files;
    for (const auto& e : fs::recursive_directory_iterator(clean))
      if (e.is_regular_file()) files.push_back(fs::relative(e.path(), clean));
    std::sort(files.begin(), files.end());
    for (int iter = 0; iter < 60; ++iter) {
      const fs::path dir = scratch(std::string(f.name) + "_damaged");
      fs::copy(clean, dir, fs::copy_options::recursive);
      const fs::path victim = dir / files[next() % files.size()];
      std::string bytes = read_text(victim);
      if (bytes.empty()) continue;
      if (iter % 3 == 0)
        bytes.resize(next() % bytes.size());
      else
        for (int k = 0; k < 1 + int(next() % 4); ++k) bytes[next() % bytes.size()] ^= char(1 + next() % 255);
      write_text(victim, bytes);
      CAPTURE(victim.string());
      auto cs = ZarrChunkSource::open(dir.string(), 8, 1);
      if (!cs) {
        ++failures;
        CHECK(cs.status().message().find('\n') == std::string::npos);
        continue;
      }
      for (const LevelInfo& li = (*cs)->levels()[0]; uint32_t i : {0u, 1u, 2u, 3u}) {
        auto ch = (*cs)->read({0, i % li.chunk_counts[0], (i / 2) % li.chunk_counts[1], 0, 0, 0});
        ++reads;
        if (!ch) {
          ++failures;
          CHECK(ch.status().message().find(dir.string()) != std::string::npos);
        }
      }
    }
  }
  CHECK(failures > 0);  // the damage was noticed somewhere
  CHECK(reads > 0);
}
