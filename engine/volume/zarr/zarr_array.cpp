#include "volume/zarr/zarr_array.h"

#include <algorithm>
#include <bit>
#include <cmath>
#include <cstring>
#include <limits>
#include <nlohmann/json.hpp>

namespace vxr::zarr {
namespace {

using json = nlohmann::json;

Status bad(const std::string& what, const std::string& why) {
  return invalid_argument(what + ": " + why);
}

Result<json> parse_json(const std::string& text, const std::string& what) {
  try {
    return json::parse(text);
  } catch (const json::parse_error& e) {
    return bad(what, "not valid JSON (syntax error at byte " + std::to_string(e.byte) + ")");
  }
}

// A list of `n` (0: any count in 2..5) integers, each >= min_value.
Result<std::vector<uint64_t>> int_list(const json& j, const char* key, size_t n, uint64_t min_value,
                                       const std::string& what) {
  const std::string count = n ? std::to_string(n) : "2..5";
  const std::string expect = std::string("'") + key + "' must be a list of " + count +
                             (min_value ? " positive" : " non-negative") + " integers" +
                             (n ? " (one per dimension of 'shape')" : "");
  if (!j.contains(key)) return bad(what, std::string("'") + key + "' is missing");
  const json& v = j.at(key);
  if (!v.is_array() || (n ? v.size() != n : v.size() < 2 || v.size() > 5)) return bad(what, expect);
  std::vector<uint64_t> out;
  for (const json& e : v) {
    if (!e.is_number_integer() || (e.is_number_integer() && e.get<int64_t>() < int64_t(min_value)))
      return bad(what, expect);
    out.push_back(e.get<uint64_t>());
  }
  return out;
}

// Element counts can overflow on hostile metadata; keep one chunk below 2 GiB decoded.
Status check_chunk_size(const std::vector<uint64_t>& chunks, DType dtype, const char* key, const std::string& what) {
  long double n = dtype_bytes(dtype);
  for (uint64_t c : chunks) n *= static_cast<long double>(c);
  if (n > static_cast<long double>(uint64_t(1) << 31))
    return unsupported(what + ": '" + key + "' makes chunks of more than 2 GiB decoded; vxr reads smaller chunks");
  return Status();
}

// Sides up to 2^40 voxels keep every offset and chunk count far from overflow.
Status check_shape(const std::vector<uint64_t>& shape, const std::string& what) {
  for (uint64_t v : shape)
    if (v > (uint64_t(1) << 40))
      return unsupported(what + ": 'shape' has a side over 2^40 voxels; vxr reads smaller arrays");
  return Status();
}

struct DtypeSpec {
  DType dtype;
  bool big_endian;
};

Result<DtypeSpec> parse_v2_dtype(const json& j, const std::string& what) {
  const std::string expect = "'dtype' must be one of |u1 |i1 <u2 <i2 <u4 <i4 <f4 (or '>' for big-endian)";
  if (!j.is_string()) return bad(what, expect + "; structured dtypes are not read");
  const std::string s = j.get<std::string>();
  if (s.size() != 3 || std::string("<>|=").find(s[0]) == std::string::npos) return bad(what, expect);
  const std::string body = s.substr(1);
  DType t;
  if (body == "u1")
    t = DType::kU8;
  else if (body == "i1")
    t = DType::kI8;
  else if (body == "u2")
    t = DType::kU16;
  else if (body == "i2")
    t = DType::kI16;
  else if (body == "u4")
    t = DType::kU32;
  else if (body == "i4")
    t = DType::kI32;
  else if (body == "f4")
    t = DType::kF32;
  else
    return unsupported(what + ": 'dtype' '" + s + "' is not read (vxr reads u1, i1, u2, i2, u4, i4, f4; convert " +
                       "64-bit data first)");
  return DtypeSpec{t, s[0] == '>'};
}

Result<DType> parse_v3_dtype(const json& j, const std::string& what) {
  if (!j.is_string()) return bad(what, "'data_type' must be a string such as \"uint16\"");
  const std::string s = j.get<std::string>();
  if (s == "uint8") return DType::kU8;
  if (s == "int8") return DType::kI8;
  if (s == "uint16") return DType::kU16;
  if (s == "int16") return DType::kI16;
  if (s == "uint32") return DType::kU32;
  if (s == "int32") return DType::kI32;
  if (s == "float32") return DType::kF32;
  return unsupported(what + ": 'data_type' '" + s +
                     "' is not read (vxr reads uint8, int8, uint16, int16, uint32, int32, float32)");
}

template <typename T>
std::vector<uint8_t> element_bytes(T v) {
  std::vector<uint8_t> out(sizeof(T));
  std::memcpy(out.data(), &v, sizeof(T));
  return out;
}

// fill_value as one native-order element. null (v2: "no fill value") reads as 0.
Result<std::vector<uint8_t>> parse_fill(const json& j, DType t, const std::string& what) {
  const std::string expect = "'fill_value' must be a number, null, \"NaN\", \"Infinity\" or \"-Infinity\"";
  if (j.is_null()) return std::vector<uint8_t>(dtype_bytes(t), 0);
  if (t == DType::kF32) {
    if (j.is_number()) return element_bytes(static_cast<float>(j.get<double>()));
    if (!j.is_string()) return bad(what, expect);
    const std::string s = j.get<std::string>();
    if (s == "NaN") return element_bytes(std::numeric_limits<float>::quiet_NaN());
    if (s == "Infinity") return element_bytes(std::numeric_limits<float>::infinity());
    if (s == "-Infinity") return element_bytes(-std::numeric_limits<float>::infinity());
    if (s.size() == 10 && s.rfind("0x", 0) == 0) {  // v3: the float's bits in hex
      char* end = nullptr;
      const unsigned long bits = std::strtoul(s.c_str() + 2, &end, 16);
      if (*end == '\0') return element_bytes(static_cast<uint32_t>(bits));
    }
    return bad(what, expect);
  }
  if (j.is_boolean()) return bad(what, expect);
  if (!j.is_number_integer()) {
    if (j.is_number_float() && std::floor(j.get<double>()) == j.get<double>()) {
      // 0.0 for an integer array: accepted, as zarr-python writes it.
    } else {
      return bad(what, "'fill_value' must be an integer for a " + std::string(dtype_name(t)) + " array");
    }
  }
  const double v = j.get<double>();
  auto in_range = [&](double lo, double hi) { return v >= lo && v <= hi; };
  switch (t) {
    case DType::kU8:
      if (in_range(0, 255)) return element_bytes(static_cast<uint8_t>(v));
      break;
    case DType::kI8:
      if (in_range(-128, 127)) return element_bytes(static_cast<int8_t>(v));
      break;
    case DType::kU16:
      if (in_range(0, 65535)) return element_bytes(static_cast<uint16_t>(v));
      break;
    case DType::kI16:
      if (in_range(-32768, 32767)) return element_bytes(static_cast<int16_t>(v));
      break;
    case DType::kU32:
      if (in_range(0, 4294967295.0)) return element_bytes(static_cast<uint32_t>(v));
      break;
    case DType::kI32:
      if (in_range(-2147483648.0, 2147483647.0)) return element_bytes(static_cast<int32_t>(v));
      break;
    default:
      break;
  }
  return bad(what, "'fill_value' is outside the range of " + std::string(dtype_name(t)));
}

Result<std::vector<uint32_t>> parse_permutation(const json& j, size_t n, const std::string& what,
                                                const std::string& where) {
  const std::string expect = where + ": 'order' must list each of 0.." + std::to_string(n - 1) + " once";
  if (j.is_string() && j == "C") return std::vector<uint32_t>{};
  if (!j.is_array() || j.size() != n) return bad(what, expect);
  std::vector<uint32_t> p;
  std::vector<bool> seen(n, false);
  for (const json& e : j) {
    if (!e.is_number_integer() || e.get<int64_t>() < 0 || e.get<uint64_t>() >= n || seen[e.get<size_t>()])
      return bad(what, expect);
    seen[e.get<size_t>()] = true;
    p.push_back(e.get<uint32_t>());
  }
  bool identity = true;
  for (size_t i = 0; i < n; ++i) identity = identity && p[i] == i;
  return identity ? std::vector<uint32_t>{} : p;
}

std::vector<uint32_t> reversed_order(size_t n) {
  std::vector<uint32_t> p(n);
  for (size_t i = 0; i < n; ++i) p[i] = static_cast<uint32_t>(n - 1 - i);
  return p;
}

// The codec list of a v3 array or shard: [array->array]* array->bytes [bytes->bytes]*.
struct CodecList {
  std::vector<uint32_t> transpose;
  bool big_endian = false;
  bool sharding = false;
  json sharding_config;
  std::vector<BytesCodec> bytes_codecs;
};

Result<CodecList> parse_v3_codecs(const json& list, size_t ndim, const std::string& what, const std::string& where) {
  if (!list.is_array() || list.empty()) return bad(what, where + " must be a non-empty list of codecs");
  CodecList out;
  bool have_array_to_bytes = false;
  for (size_t i = 0; i < list.size(); ++i) {
    const std::string at = where + "[" + std::to_string(i) + "]";
    const json& c = list[i];
    if (!c.is_object() || !c.contains("name") || !c.at("name").is_string())
      return bad(what, at + " must be an object with a string 'name'");
    const std::string name = c.at("name").get<std::string>();
    const json cfg = c.contains("configuration") ? c.at("configuration") : json::object();
    if (!cfg.is_object()) return bad(what, at + ": 'configuration' must be an object");
    if (name == "transpose") {
      if (have_array_to_bytes) return bad(what, at + ": 'transpose' must come before 'bytes'");
      if (!out.transpose.empty()) return unsupported(what + ": " + at + ": two transpose codecs are not read");
      if (!cfg.contains("order")) return bad(what, at + ": 'order' is missing");
      VXR_ASSIGN_OR_RETURN(out.transpose, parse_permutation(cfg.at("order"), ndim, what, at));
    } else if (name == "bytes" || name == "endian") {
      if (have_array_to_bytes) return bad(what, at + ": a second array-to-bytes codec");
      have_array_to_bytes = true;
      if (cfg.contains("endian")) {
        const json& e = cfg.at("endian");
        if (e != "little" && e != "big") return bad(what, at + ": 'endian' must be \"little\" or \"big\"");
        out.big_endian = e == "big";
      }
    } else if (name == "sharding_indexed") {
      if (have_array_to_bytes) return bad(what, at + ": a second array-to-bytes codec");
      have_array_to_bytes = true;
      out.sharding = true;
      out.sharding_config = cfg;
    } else if (is_v3_bytes_codec(name)) {
      if (!have_array_to_bytes) return bad(what, at + ": '" + name + "' must come after 'bytes'");
      auto bc = parse_v3_bytes_codec(c, at);
      if (!bc) return Status(bc.status().code(), what + ": " + bc.status().message());
      out.bytes_codecs.push_back(*bc);
    } else {
      return unsupported(what + ": " + at + ": codec '" + name +
                         "' is not read (vxr reads bytes, transpose, sharding_indexed, gzip, zstd, blosc, crc32c)");
    }
  }
  if (!have_array_to_bytes) return bad(what, where + " has no 'bytes' codec");
  return out;
}

}  // namespace

uint64_t ArrayMeta::chunk_elements() const {
  uint64_t n = 1;
  for (uint64_t c : chunks) n *= c;
  return n;
}

Result<ArrayMeta> parse_v2_array(const std::string& text, const std::string& what) {
  VXR_ASSIGN_OR_RETURN(json j, parse_json(text, what));
  try {
    if (!j.is_object()) return bad(what, "must hold a JSON object");
    if (!j.contains("zarr_format") || j.at("zarr_format") != 2) return bad(what, "'zarr_format' must be 2");
    ArrayMeta m;
    m.zarr_format = 2;
    VXR_ASSIGN_OR_RETURN(m.shape, int_list(j, "shape", 0, 0, what));
    VXR_RETURN_IF_ERROR(check_shape(m.shape, what));
    VXR_ASSIGN_OR_RETURN(m.chunks, int_list(j, "chunks", m.shape.size(), 1, what));
    if (!j.contains("dtype")) return bad(what, "'dtype' is missing");
    VXR_ASSIGN_OR_RETURN(DtypeSpec dt, parse_v2_dtype(j.at("dtype"), what));
    m.dtype = dt.dtype;
    m.big_endian = dt.big_endian && dtype_bytes(dt.dtype) > 1;
    VXR_RETURN_IF_ERROR(check_chunk_size(m.chunks, m.dtype, "chunks", what));
    VXR_ASSIGN_OR_RETURN(m.fill, parse_fill(j.contains("fill_value") ? j.at("fill_value") : json(), m.dtype, what));
    const json order = j.contains("order") ? j.at("order") : json("C");
    if (order == "F")
      m.transpose = reversed_order(m.shape.size());
    else if (order != "C")
      return bad(what, "'order' must be \"C\" or \"F\"");
    if (j.contains("compressor") && !j.at("compressor").is_null()) {
      auto c = parse_v2_compressor(j.at("compressor"));
      if (!c) return Status(c.status().code(), what + ": " + c.status().message());
      m.codecs.push_back(*c);
    }
    if (j.contains("filters") && !j.at("filters").is_null() && !(j.at("filters").is_array() && j.at("filters").empty()))
      return unsupported(what + ": 'filters' are not read (vxr reads arrays without numcodecs filters)");
    m.separator = '.';
    if (j.contains("dimension_separator")) {
      const json& s = j.at("dimension_separator");
      if (s == "/")
        m.separator = '/';
      else if (s != ".")
        return bad(what, "'dimension_separator' must be \".\" or \"/\"");
    }
    return m;
  } catch (const json::exception& e) {
    return bad(what, std::string("unexpected JSON value (") + e.what() + ")");
  }
}

Result<ArrayMeta> parse_v3_array(const std::string& text, const std::string& what) {
  VXR_ASSIGN_OR_RETURN(json j, parse_json(text, what));
  try {
    if (!j.is_object()) return bad(what, "must hold a JSON object");
    if (!j.contains("zarr_format") || j.at("zarr_format") != 3) return bad(what, "'zarr_format' must be 3");
    if (!j.contains("node_type") || j.at("node_type") != "array")
      return bad(what, "'node_type' must be \"array\" (this is a group, not an array)");
    ArrayMeta m;
    m.zarr_format = 3;
    VXR_ASSIGN_OR_RETURN(m.shape, int_list(j, "shape", 0, 0, what));
    VXR_RETURN_IF_ERROR(check_shape(m.shape, what));
    const size_t n = m.shape.size();
    if (!j.contains("data_type")) return bad(what, "'data_type' is missing");
    VXR_ASSIGN_OR_RETURN(m.dtype, parse_v3_dtype(j.at("data_type"), what));
    if (!j.contains("chunk_grid") || !j.at("chunk_grid").is_object() ||
        j.at("chunk_grid").value("name", "") != "regular" || !j.at("chunk_grid").contains("configuration"))
      return bad(what, "'chunk_grid' must be {\"name\": \"regular\", \"configuration\": {\"chunk_shape\": [...]}}");
    std::vector<uint64_t> outer;
    {
      auto cs = int_list(j.at("chunk_grid").at("configuration"), "chunk_shape", n, 1, what);
      if (!cs) return bad(what, "'chunk_grid': " + cs.status().message().substr(what.size() + 2));
      outer = *cs;
    }
    if (!j.contains("fill_value")) return bad(what, "'fill_value' is missing");
    VXR_ASSIGN_OR_RETURN(m.fill, parse_fill(j.at("fill_value"), m.dtype, what));
    m.key_prefix = "c";
    m.separator = '/';
    if (j.contains("chunk_key_encoding")) {
      const json& e = j.at("chunk_key_encoding");
      const std::string name = e.is_object() ? e.value("name", "") : "";
      if (name != "default" && name != "v2") return bad(what, "'chunk_key_encoding': 'name' must be default or v2");
      if (name == "v2") m.key_prefix.clear(), m.separator = '.';
      if (e.contains("configuration") && e.at("configuration").contains("separator")) {
        const json& s = e.at("configuration").at("separator");
        if (s != "/" && s != ".") return bad(what, "'chunk_key_encoding': 'separator' must be \".\" or \"/\"");
        m.separator = s.get<std::string>()[0];
      }
    }
    if (j.contains("storage_transformers") && !j.at("storage_transformers").empty())
      return unsupported(what + ": 'storage_transformers' are not read");
    if (j.contains("dimension_names") && j.at("dimension_names").is_array())
      for (const json& d : j.at("dimension_names"))
        m.dimension_names.push_back(d.is_string() ? d.get<std::string>() : "");
    if (!j.contains("codecs")) return bad(what, "'codecs' is missing");
    VXR_ASSIGN_OR_RETURN(CodecList cl, parse_v3_codecs(j.at("codecs"), n, what, "'codecs'"));
    if (!cl.sharding) {
      m.chunks = outer;
      m.transpose = cl.transpose;
      m.big_endian = cl.big_endian && dtype_bytes(m.dtype) > 1;
      m.codecs = cl.bytes_codecs;
    } else {
      if (!cl.transpose.empty() || !cl.bytes_codecs.empty())
        return unsupported(what + ": 'codecs': only 'sharding_indexed' alone is read around shards");
      const json& cfg = cl.sharding_config;
      const std::string where = "'codecs' sharding_indexed";
      auto inner = int_list(cfg, "chunk_shape", n, 1, what);
      if (!inner) return bad(what, where + ": " + inner.status().message().substr(what.size() + 2));
      for (size_t i = 0; i < n; ++i)
        if (outer[i] % (*inner)[i] != 0)
          return bad(what, where + ": 'chunk_shape' must divide the shard shape in 'chunk_grid'");
      m.sharded = true;
      m.shard_shape = outer;
      m.chunks = *inner;
      if (!cfg.contains("codecs")) return bad(what, where + ": 'codecs' is missing");
      VXR_ASSIGN_OR_RETURN(CodecList in, parse_v3_codecs(cfg.at("codecs"), n, what, where + " 'codecs'"));
      if (in.sharding) return unsupported(what + ": " + where + ": nested sharding is not read");
      m.transpose = in.transpose;
      m.big_endian = in.big_endian && dtype_bytes(m.dtype) > 1;
      m.codecs = in.bytes_codecs;
      if (cfg.contains("index_codecs")) {
        VXR_ASSIGN_OR_RETURN(CodecList ic, parse_v3_codecs(cfg.at("index_codecs"), 1, what, where + " 'index_codecs'"));
        if (ic.sharding || ic.big_endian || !ic.transpose.empty())
          return unsupported(what + ": " + where + ": 'index_codecs' must be little-endian bytes (+ crc32c)");
        for (const BytesCodec& b : ic.bytes_codecs)
          if (b.id != CodecId::kCrc32c)
            return unsupported(what + ": " + where + ": 'index_codecs' other than crc32c are not read");
        m.index_codecs = ic.bytes_codecs;
      }
      if (cfg.contains("index_location")) {
        const json& l = cfg.at("index_location");
        if (l != "start" && l != "end") return bad(what, where + ": 'index_location' must be \"start\" or \"end\"");
        m.index_at_end = l == "end";
      }
    }
    VXR_RETURN_IF_ERROR(check_chunk_size(m.chunks, m.dtype, "chunk_shape", what));
    return m;
  } catch (const json::exception& e) {
    return bad(what, std::string("unexpected JSON value (") + e.what() + ")");
  }
}

Result<std::unique_ptr<ZarrArray>> ZarrArray::open(std::shared_ptr<const ZarrStore> store, const std::string& path,
                                                   uint64_t cache_bytes) {
  const std::string prefix = path.empty() ? "" : path + "/";
  auto v3 = store->get(prefix + "zarr.json");
  if (!v3) return v3.status();
  Result<ArrayMeta> meta = not_found("");
  if (const auto& text = *v3; text.has_value()) {
    meta = parse_v3_array(std::string(text->begin(), text->end()), store->describe(prefix + "zarr.json"));
  } else {
    auto v2 = store->get(prefix + ".zarray");
    if (!v2) return v2.status();
    const auto& text2 = *v2;
    if (!text2.has_value())
      return not_found(store->describe(path) + ": no Zarr array here (neither .zarray nor zarr.json)");
    meta = parse_v2_array(std::string(text2->begin(), text2->end()), store->describe(prefix + ".zarray"));
  }
  if (!meta) return meta.status();
  return std::unique_ptr<ZarrArray>(new ZarrArray(std::move(store), path, std::move(meta).value(), cache_bytes));
}

std::string ZarrArray::chunk_key(std::span<const uint64_t> index) const {
  std::string key = path_.empty() ? "" : path_ + "/";
  if (!meta_.key_prefix.empty()) key += meta_.key_prefix + meta_.separator;
  if (index.empty()) return key + "0";
  for (size_t i = 0; i < index.size(); ++i) {
    if (i) key += meta_.separator;
    key += std::to_string(index[i]);
  }
  return key;
}

uint64_t ZarrArray::cached_bytes() const {
  std::lock_guard lock(mutex_);
  return held_;
}

void ZarrArray::raise_cache_bytes(uint64_t bytes) {
  std::lock_guard lock(mutex_);
  cache_bytes_ = std::max(cache_bytes_, bytes);
}

uint64_t ZarrArray::cache_budget() const {
  std::lock_guard lock(mutex_);
  return cache_bytes_;
}

uint64_t ZarrArray::decodes() const {
  std::lock_guard lock(mutex_);
  return decodes_;
}

namespace {

void byteswap_all(std::vector<uint8_t>& b, uint32_t size) {
  if (size == 2)
    for (size_t i = 0; i + 1 < b.size(); i += 2) std::swap(b[i], b[i + 1]);
  else if (size == 4)
    for (size_t i = 0; i + 3 < b.size(); i += 4) std::swap(b[i], b[i + 3]), std::swap(b[i + 1], b[i + 2]);
}

// Undoes a transpose: `stored` holds the chunk transposed by `order` (stored
// axis k is chunk axis order[k]), C order; returns the chunk in C order.
std::vector<uint8_t> untranspose(const std::vector<uint8_t>& stored, const std::vector<uint64_t>& shape,
                                 const std::vector<uint32_t>& order, uint32_t item) {
  const size_t n = shape.size();
  std::vector<uint64_t> stored_stride(n);  // in elements, per stored axis
  uint64_t s = 1;
  for (size_t k = n; k-- > 0;) stored_stride[k] = s, s *= shape[order[k]];
  std::vector<uint64_t> step(n);  // stored offset per unit of chunk axis a
  for (size_t k = 0; k < n; ++k) step[order[k]] = stored_stride[k];
  std::vector<uint8_t> out(stored.size());
  std::vector<uint64_t> idx(n, 0);
  uint64_t src = 0;
  const uint64_t count = stored.size() / item;
  for (uint64_t e = 0; e < count; ++e) {
    std::memcpy(out.data() + e * item, stored.data() + src * item, item);
    for (size_t a = n; a-- > 0;) {  // odometer over the chunk's C order
      if (++idx[a] < shape[a]) {
        src += step[a];
        break;
      }
      src -= step[a] * (shape[a] - 1);
      idx[a] = 0;
    }
  }
  return out;
}

}  // namespace

Result<ZarrArray::Bytes> ZarrArray::decode_unit(Bytes stored, const std::string& key) const {
  const uint32_t item = dtype_bytes(meta_.dtype);
  const size_t expected = static_cast<size_t>(meta_.chunk_elements() * item);
  auto raw = decode_chain(meta_.codecs, std::move(stored), expected);
  if (!raw) return corrupt(store_->describe(key) + ": chunk does not decode (" + raw.status().message() + ")");
  Bytes out = std::move(raw).value();
  if (!meta_.transpose.empty()) out = untranspose(out, meta_.chunks, meta_.transpose, item);
  if (meta_.big_endian != (std::endian::native == std::endian::big)) byteswap_all(out, item);
  return out;
}

Result<std::shared_ptr<const std::vector<ZarrArray::ShardEntry>>> ZarrArray::shard_index(const std::string& key) const {
  {
    std::lock_guard lock(mutex_);
    for (auto it = shard_indexes_.begin(); it != shard_indexes_.end(); ++it)
      if (it->first == key) {
        shard_indexes_.splice(shard_indexes_.begin(), shard_indexes_, it);
        return it->second;
      }
  }
  uint64_t inner = 1;
  for (size_t i = 0; i < ndim(); ++i) inner *= meta_.shard_shape[i] / meta_.chunks[i];
  uint64_t index_bytes = inner * 16;
  for (const BytesCodec& c : meta_.index_codecs) index_bytes += c.id == CodecId::kCrc32c ? 4 : 0;
  const ByteRange range = meta_.index_at_end ? ByteRange::suffix(index_bytes) : ByteRange::range(0, index_bytes);
  auto got = store_->get(key, range);
  if (!got) return corrupt(store_->describe(key) + ": shard index unreadable (" + got.status().message() + ")");
  std::shared_ptr<std::vector<ShardEntry>> entries;
  if (*got) {
    auto table = decode_chain(meta_.index_codecs, std::move(**got), inner * 16);
    if (!table) return corrupt(store_->describe(key) + ": shard index is damaged (" + table.status().message() + ")");
    entries = std::make_shared<std::vector<ShardEntry>>(inner);
    auto u64 = [&](size_t at) {
      uint64_t v = 0;
      for (int b = 7; b >= 0; --b) v = (v << 8) | (*table)[at + b];
      return v;
    };
    for (uint64_t i = 0; i < inner; ++i) (*entries)[i] = {u64(i * 16), u64(i * 16 + 8)};
  }
  std::lock_guard lock(mutex_);
  shard_indexes_.emplace_front(key, entries);
  if (shard_indexes_.size() > 8) shard_indexes_.pop_back();
  return std::shared_ptr<const std::vector<ShardEntry>>(entries);
}

Result<std::shared_ptr<const ZarrArray::Bytes>> ZarrArray::load_chunk(const std::vector<uint64_t>& index) const {
  if (!meta_.sharded) {
    const std::string key = chunk_key(index);
    auto got = store_->get(key);
    if (!got) return got.status();
    if (!*got) return std::shared_ptr<const Bytes>();
    VXR_ASSIGN_OR_RETURN(Bytes decoded, decode_unit(std::move(**got), key));
    return std::shared_ptr<const Bytes>(std::make_shared<Bytes>(std::move(decoded)));
  }
  const size_t n = ndim();
  std::vector<uint64_t> shard(n);
  uint64_t linear = 0;
  for (size_t i = 0; i < n; ++i) {
    const uint64_t per = meta_.shard_shape[i] / meta_.chunks[i];
    shard[i] = index[i] / per;
    linear = linear * per + index[i] % per;
  }
  const std::string key = chunk_key(shard);
  VXR_ASSIGN_OR_RETURN(auto entries, shard_index(key));
  if (!entries) return std::shared_ptr<const Bytes>();  // no shard: all fill
  const ShardEntry e = (*entries)[linear];
  if (e.offset == ~uint64_t(0) && e.nbytes == ~uint64_t(0)) return std::shared_ptr<const Bytes>();
  auto got = store_->get(key, ByteRange::range(e.offset, e.nbytes));
  if (!got)
    return corrupt(store_->describe(key) + ": inner chunk " + std::to_string(linear) + " points outside the shard (" +
                   got.status().message() + ")");
  if (!*got) return std::shared_ptr<const Bytes>();
  auto decoded = decode_unit(std::move(**got), key);
  if (!decoded) return corrupt(decoded.status().message() + " (inner chunk " + std::to_string(linear) + ")");
  return std::shared_ptr<const Bytes>(std::make_shared<Bytes>(std::move(decoded).value()));
}

Result<std::shared_ptr<const ZarrArray::Bytes>> ZarrArray::chunk(const std::vector<uint64_t>& index) const {
  std::string id;
  for (uint64_t v : index) id += std::to_string(v) + ",";
  {
    std::lock_guard lock(mutex_);
    if (auto it = cache_.find(id); it != cache_.end()) {
      lru_.splice(lru_.begin(), lru_, it->second.lru);
      return it->second.bytes;
    }
  }
  VXR_ASSIGN_OR_RETURN(std::shared_ptr<const Bytes> bytes, load_chunk(index));
  std::lock_guard lock(mutex_);
  ++decodes_;
  if (cache_.count(id)) return bytes;  // another thread got there first
  const uint64_t size = (bytes ? bytes->size() : 0) + 64;
  if (size > cache_bytes_) return bytes;
  lru_.push_front(id);
  cache_[id] = {bytes, lru_.begin()};
  held_ += size;
  while (held_ > cache_bytes_ && !lru_.empty()) {
    auto it = cache_.find(lru_.back());
    held_ -= (it->second.bytes ? it->second.bytes->size() : 0) + 64;
    cache_.erase(it);
    lru_.pop_back();
  }
  return bytes;
}

Status ZarrArray::read(std::span<const uint64_t> start, std::span<const uint64_t> size, std::span<uint8_t> dst) const {
  const size_t n = ndim();
  const uint32_t item = dtype_bytes(meta_.dtype);
  if (start.size() != n || size.size() != n) return invalid_argument(describe() + ": read with the wrong rank");
  uint64_t total = item;
  for (size_t i = 0; i < n; ++i) {
    if (start[i] > meta_.shape[i] || size[i] > meta_.shape[i] - start[i])
      return out_of_range(describe() + ": read outside the array");
    total *= size[i];
  }
  if (dst.size() != total) return invalid_argument(describe() + ": read buffer has the wrong size");
  if (total == 0) return Status();
  // Strides (elements) of the destination and of one chunk.
  std::vector<uint64_t> dst_stride(n), chunk_stride(n);
  for (size_t i = n, d = 1, c = 1; i-- > 0;) {
    dst_stride[i] = d, d *= size[i];
    chunk_stride[i] = c, c *= meta_.chunks[i];
  }
  std::vector<uint64_t> first(n), last(n), ci(n);
  for (size_t i = 0; i < n; ++i) {
    first[i] = start[i] / meta_.chunks[i];
    last[i] = (start[i] + size[i] - 1) / meta_.chunks[i];
  }
  ci = first;
  while (true) {
    VXR_ASSIGN_OR_RETURN(std::shared_ptr<const Bytes> chunk_bytes, chunk(ci));
    // The part of the box inside this chunk: [lo, hi) in array coordinates.
    std::vector<uint64_t> lo(n), hi(n);
    for (size_t i = 0; i < n; ++i) {
      lo[i] = std::max(start[i], ci[i] * meta_.chunks[i]);
      hi[i] = std::min(start[i] + size[i], (ci[i] + 1) * meta_.chunks[i]);
    }
    const uint64_t run = hi[n - 1] - lo[n - 1];
    std::vector<uint64_t> p = lo;  // odometer over all axes but the last
    while (true) {
      uint64_t d = 0, c = 0;
      for (size_t i = 0; i < n; ++i) {
        d += (p[i] - start[i]) * dst_stride[i];
        c += (p[i] - ci[i] * meta_.chunks[i]) * chunk_stride[i];
      }
      uint8_t* out = dst.data() + d * item;
      if (chunk_bytes) {
        std::memcpy(out, chunk_bytes->data() + c * item, run * item);
      } else {
        for (uint64_t k = 0; k < run; ++k) std::memcpy(out + k * item, meta_.fill.data(), item);
      }
      size_t a = n - 1;
      while (a-- > 0) {
        if (++p[a] < hi[a]) break;
        p[a] = lo[a];
      }
      if (a == size_t(-1)) break;
    }
    size_t a = n;
    while (a-- > 0) {
      if (++ci[a] <= last[a]) break;
      ci[a] = first[a];
    }
    if (a == size_t(-1)) break;
  }
  return Status();
}

}  // namespace vxr::zarr
