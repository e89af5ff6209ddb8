#include "volume/zarr/zarr_codecs.h"

#include <blosc.h>
#include <lz4.h>
#include <zlib.h>
#include <zstd.h>

#include <array>
#include <cstring>
#include <limits>
#include <nlohmann/json.hpp>

namespace vxr::zarr {
namespace {

using Bytes = std::vector<uint8_t>;

Status size_mismatch(const char* codec, size_t got, size_t expected) {
  return corrupt(std::string(codec) + ": decoded " + std::to_string(got) + " bytes, the chunk needs " +
                 std::to_string(expected));
}

Result<Bytes> inflate_any(std::span<const uint8_t> in, size_t expected, const char* name) {
  z_stream zs{};
  if (inflateInit2(&zs, 15 + 32) != Z_OK) return internal_error(std::string(name) + ": cannot start zlib");
  Bytes out(expected ? expected : std::max<size_t>(in.size() * 4, 4096));
  zs.next_in = const_cast<Bytes::value_type*>(in.data());
  zs.avail_in = static_cast<uInt>(in.size());
  int rc = Z_OK;
  while (true) {
    zs.next_out = out.data() + zs.total_out;
    zs.avail_out = static_cast<uInt>(out.size() - zs.total_out);
    rc = inflate(&zs, Z_NO_FLUSH);
    if (rc == Z_STREAM_END) break;
    if (rc != Z_OK && rc != Z_BUF_ERROR) break;
    if (zs.avail_out == 0) {
      if (expected) break;  // more output than the chunk holds
      out.resize(out.size() * 2);
      continue;
    }
    if (zs.avail_in == 0) break;  // input ended before the stream did
  }
  const size_t produced = zs.total_out;
  const std::string msg = zs.msg ? zs.msg : "";
  inflateEnd(&zs);
  if (rc != Z_STREAM_END)
    return corrupt(std::string(name) + ": data is corrupt or truncated" + (msg.empty() ? "" : " (" + msg + ")"));
  out.resize(produced);
  if (expected && produced != expected) return size_mismatch(name, produced, expected);
  return out;
}

Result<Bytes> deflate_with(std::span<const uint8_t> in, int level, bool gzip) {
  z_stream zs{};
  if (deflateInit2(&zs, level, Z_DEFLATED, gzip ? 15 + 16 : 15, 8, Z_DEFAULT_STRATEGY) != Z_OK)
    return invalid_argument("gzip/zlib: bad level " + std::to_string(level));
  Bytes out(deflateBound(&zs, static_cast<uLong>(in.size())) + 32);
  zs.next_in = const_cast<Bytes::value_type*>(in.data());
  zs.avail_in = static_cast<uInt>(in.size());
  zs.next_out = out.data();
  zs.avail_out = static_cast<uInt>(out.size());
  const int rc = deflate(&zs, Z_FINISH);
  out.resize(zs.total_out);
  deflateEnd(&zs);
  if (rc != Z_STREAM_END) return internal_error("gzip/zlib: compression failed");
  return out;
}

Result<Bytes> zstd_decode(std::span<const uint8_t> in, size_t expected) {
  ZSTD_DStream* ds = ZSTD_createDStream();
  if (!ds) return internal_error("zstd: cannot start a decoder");
  Bytes out(expected ? expected : std::max<size_t>(in.size() * 4, 4096));
  ZSTD_inBuffer ib{in.data(), in.size(), 0};
  ZSTD_outBuffer ob{out.data(), out.size(), 0};
  size_t rc = 1;
  std::string err;
  while (true) {
    rc = ZSTD_decompressStream(ds, &ob, &ib);
    if (ZSTD_isError(rc)) {
      err = ZSTD_getErrorName(rc);
      break;
    }
    if (rc == 0 && ib.pos == ib.size) break;  // frame(s) done, input used up
    if (ob.pos == ob.size) {
      if (expected) break;
      out.resize(out.size() * 2);
      ob.dst = out.data();
      ob.size = out.size();
      continue;
    }
    if (ib.pos == ib.size) break;  // input ended mid-frame
  }
  ZSTD_freeDStream(ds);
  if (!err.empty()) return corrupt("zstd: data is corrupt (" + err + ")");
  if (rc != 0 || ib.pos != ib.size) return corrupt("zstd: data is truncated or has trailing bytes");
  out.resize(ob.pos);
  if (expected && ob.pos != expected) return size_mismatch("zstd", ob.pos, expected);
  return out;
}

Result<Bytes> blosc_decode(std::span<const uint8_t> in, size_t expected) {
  size_t nbytes = 0;
  if (in.size() < BLOSC_MIN_HEADER_LENGTH || blosc_cbuffer_validate(in.data(), in.size(), &nbytes) != 0)
    return corrupt("blosc: not a valid blosc frame (bad header or size)");
  if (expected && nbytes != expected) return size_mismatch("blosc", nbytes, expected);
  Bytes out(nbytes);
  // The _ctx call keeps no global state, so several threads decode at once.
  const int n = blosc_decompress_ctx(in.data(), out.data(), out.size(), 1);
  if (n < 0 || static_cast<size_t>(n) != nbytes) return corrupt("blosc: data is corrupt");
  return out;
}

Result<Bytes> blosc_encode(const BytesCodec& c, std::span<const uint8_t> in) {
  Bytes out(in.size() + BLOSC_MAX_OVERHEAD);
  const int n = blosc_compress_ctx(c.level, c.blosc_shuffle, std::max<uint32_t>(1, c.blosc_typesize), in.size(),
                                   in.data(), out.data(), out.size(), c.blosc_cname.c_str(), 0, 1);
  if (n <= 0) return invalid_argument("blosc: cannot compress with '" + c.blosc_cname + "'");
  out.resize(static_cast<size_t>(n));
  return out;
}

Result<Bytes> lz4_decode(std::span<const uint8_t> in, size_t expected) {
  if (in.size() < 4) return corrupt("lz4: shorter than its 4-byte size header");
  const uint32_t n = uint32_t(in[0]) | uint32_t(in[1]) << 8 | uint32_t(in[2]) << 16 | uint32_t(in[3]) << 24;
  if (expected && n != expected) return size_mismatch("lz4", n, expected);
  if (n > uint32_t(std::numeric_limits<int>::max())) return corrupt("lz4: size header is implausible");
  Bytes out(n);
  const int got = LZ4_decompress_safe(reinterpret_cast<const char*>(in.data() + 4), reinterpret_cast<char*>(out.data()),
                                      static_cast<int>(in.size() - 4), static_cast<int>(n));
  if (got < 0 || static_cast<uint32_t>(got) != n) return corrupt("lz4: data is corrupt or truncated");
  return out;
}

Result<Bytes> lz4_encode(std::span<const uint8_t> in) {
  if (in.size() > size_t(LZ4_MAX_INPUT_SIZE)) return invalid_argument("lz4: chunk too large");
  const int n = static_cast<int>(in.size());
  Bytes out(4 + size_t(LZ4_compressBound(n)));
  for (int i = 0; i < 4; ++i) out[i] = static_cast<uint8_t>(uint32_t(n) >> (8 * i));
  const int got = LZ4_compress_default(reinterpret_cast<const char*>(in.data()),
                                       reinterpret_cast<char*>(out.data() + 4), n, static_cast<int>(out.size() - 4));
  if (got <= 0) return internal_error("lz4: compression failed");
  out.resize(4 + size_t(got));
  return out;
}

Result<Bytes> crc_decode(std::span<const uint8_t> in) {
  if (in.size() < 4) return corrupt("crc32c: shorter than its 4-byte checksum");
  const size_t n = in.size() - 4;
  const uint32_t stored =
      uint32_t(in[n]) | uint32_t(in[n + 1]) << 8 | uint32_t(in[n + 2]) << 16 | uint32_t(in[n + 3]) << 24;
  if (crc32c(in.first(n)) != stored) return corrupt("crc32c: checksum mismatch (the data is damaged)");
  return Bytes(in.begin(), in.begin() + static_cast<std::ptrdiff_t>(n));
}

// Integer member of a config object, `fallback` when absent.
Result<int> int_member(const nlohmann::json& j, const char* key, int fallback, const std::string& where) {
  if (!j.is_object() || !j.contains(key)) return fallback;
  const auto& v = j.at(key);
  if (!v.is_number_integer()) return invalid_argument(where + ": '" + key + "' must be an integer");
  return v.get<int>();
}

bool known_blosc_cname(const std::string& n) {
  return n == "lz4" || n == "lz4hc" || n == "zstd" || n == "zlib" || n == "blosclz" || n == "snappy";
}

}  // namespace

const char* codec_name(CodecId id) {
  switch (id) {
    case CodecId::kGzip:
      return "gzip";
    case CodecId::kZlib:
      return "zlib";
    case CodecId::kZstd:
      return "zstd";
    case CodecId::kBlosc:
      return "blosc";
    case CodecId::kLz4:
      return "lz4";
    case CodecId::kCrc32c:
      return "crc32c";
  }
  return "?";
}

uint32_t crc32c(std::span<const uint8_t> bytes) {
  static const std::array<uint32_t, 256> table = [] {
    std::array<uint32_t, 256> t{};
    for (uint32_t i = 0; i < 256; ++i) {
      uint32_t c = i;
      for (int k = 0; k < 8; ++k) c = (c & 1) ? (c >> 1) ^ 0x82F63B78u : c >> 1;
      t[i] = c;
    }
    return t;
  }();
  uint32_t crc = 0xFFFFFFFFu;
  for (uint8_t b : bytes) crc = table[(crc ^ b) & 0xFFu] ^ (crc >> 8);
  return crc ^ 0xFFFFFFFFu;
}

Result<BytesCodec> parse_v2_compressor(const nlohmann::json& j) {
  const std::string where = "'compressor'";
  if (!j.is_object() || !j.contains("id") || !j.at("id").is_string())
    return invalid_argument(where + " must be null or an object with a string 'id'");
  const std::string id = j.at("id").get<std::string>();
  BytesCodec c;
  if (id == "gzip" || id == "zlib") {
    c.id = id == "gzip" ? CodecId::kGzip : CodecId::kZlib;
    VXR_ASSIGN_OR_RETURN(c.level, int_member(j, "level", 5, where));
  } else if (id == "zstd") {
    c.id = CodecId::kZstd;
    VXR_ASSIGN_OR_RETURN(c.level, int_member(j, "level", 3, where));
  } else if (id == "blosc") {
    c.id = CodecId::kBlosc;
    VXR_ASSIGN_OR_RETURN(c.level, int_member(j, "clevel", 5, where));
    VXR_ASSIGN_OR_RETURN(c.blosc_shuffle, int_member(j, "shuffle", 1, where));
    if (j.contains("cname")) {
      if (!j.at("cname").is_string() || !known_blosc_cname(j.at("cname").get<std::string>()))
        return invalid_argument(where + ": 'cname' must be one of lz4, lz4hc, zstd, zlib, blosclz, snappy");
      c.blosc_cname = j.at("cname").get<std::string>();
    }
  } else if (id == "lz4") {
    c.id = CodecId::kLz4;
  } else {
    return unsupported(where + ": unknown id '" + id + "' (vxr reads gzip, zlib, zstd, blosc and lz4)");
  }
  return c;
}

bool is_v3_bytes_codec(const std::string& name) {
  for (const char* n : {"gzip", "zstd", "blosc", "crc32c", "numcodecs.gzip", "numcodecs.zlib", "numcodecs.zstd",
                        "numcodecs.blosc", "numcodecs.lz4"})
    if (name == n) return true;
  return false;
}

Result<BytesCodec> parse_v3_bytes_codec(const nlohmann::json& j, const std::string& where) {
  const std::string name = j.at("name").get<std::string>();
  static const nlohmann::json kEmpty = nlohmann::json::object();
  const nlohmann::json& cfg = j.contains("configuration") ? j.at("configuration") : kEmpty;
  if (!cfg.is_object()) return invalid_argument(where + ": 'configuration' must be an object");
  // numcodecs.* codecs (zarr-python 3) keep the v2 configuration keys.
  if (name.rfind("numcodecs.", 0) == 0) {
    nlohmann::json v2 = cfg;
    v2["id"] = name.substr(10);
    auto c = parse_v2_compressor(v2);
    if (!c) return invalid_argument(where + ": " + c.status().message());
    return c;
  }
  BytesCodec c;
  if (name == "gzip") {
    c.id = CodecId::kGzip;
    VXR_ASSIGN_OR_RETURN(c.level, int_member(cfg, "level", 5, where));
  } else if (name == "zstd") {
    c.id = CodecId::kZstd;
    VXR_ASSIGN_OR_RETURN(c.level, int_member(cfg, "level", 3, where));
  } else if (name == "blosc") {
    c.id = CodecId::kBlosc;
    VXR_ASSIGN_OR_RETURN(c.level, int_member(cfg, "clevel", 5, where));
    if (cfg.contains("cname")) {
      if (!cfg.at("cname").is_string() || !known_blosc_cname(cfg.at("cname").get<std::string>()))
        return invalid_argument(where + ": 'cname' must be one of lz4, lz4hc, zstd, zlib, blosclz, snappy");
      c.blosc_cname = cfg.at("cname").get<std::string>();
    }
    if (cfg.contains("shuffle")) {
      const auto& s = cfg.at("shuffle");
      if (s == "noshuffle")
        c.blosc_shuffle = 0;
      else if (s == "shuffle")
        c.blosc_shuffle = 1;
      else if (s == "bitshuffle")
        c.blosc_shuffle = 2;
      else
        return invalid_argument(where + ": 'shuffle' must be noshuffle, shuffle or bitshuffle");
    }
    VXR_ASSIGN_OR_RETURN(int ts, int_member(cfg, "typesize", 1, where));
    c.blosc_typesize = static_cast<uint32_t>(std::max(1, ts));
  } else if (name == "crc32c") {
    c.id = CodecId::kCrc32c;
  } else {
    return unsupported(where + ": unknown codec '" + name + "'");
  }
  return c;
}

Result<std::vector<uint8_t>> decode(const BytesCodec& c, std::span<const uint8_t> in, size_t expected) {
  switch (c.id) {
    case CodecId::kGzip:
    case CodecId::kZlib:
      return inflate_any(in, expected, codec_name(c.id));
    case CodecId::kZstd:
      return zstd_decode(in, expected);
    case CodecId::kBlosc:
      return blosc_decode(in, expected);
    case CodecId::kLz4:
      return lz4_decode(in, expected);
    case CodecId::kCrc32c:
      return crc_decode(in);
  }
  return internal_error("unknown codec");
}

Result<std::vector<uint8_t>> encode(const BytesCodec& c, std::span<const uint8_t> in) {
  switch (c.id) {
    case CodecId::kGzip:
      return deflate_with(in, c.level, true);
    case CodecId::kZlib:
      return deflate_with(in, c.level, false);
    case CodecId::kZstd: {
      Bytes out(ZSTD_compressBound(in.size()));
      const size_t n = ZSTD_compress(out.data(), out.size(), in.data(), in.size(), c.level);
      if (ZSTD_isError(n)) return internal_error(std::string("zstd: ") + ZSTD_getErrorName(n));
      out.resize(n);
      return out;
    }
    case CodecId::kBlosc:
      return blosc_encode(c, in);
    case CodecId::kLz4:
      return lz4_encode(in);
    case CodecId::kCrc32c: {
      Bytes out(in.begin(), in.end());
      const uint32_t crc = crc32c(in);
      for (int i = 0; i < 4; ++i) out.push_back(static_cast<uint8_t>(crc >> (8 * i)));
      return out;
    }
  }
  return internal_error("unknown codec");
}

Result<std::vector<uint8_t>> decode_chain(const std::vector<BytesCodec>& codecs, std::vector<uint8_t> in,
                                          size_t expected) {
  for (size_t i = codecs.size(); i-- > 0;) {
    // Only the innermost (first-applied) codec's output is the chunk itself.
    VXR_ASSIGN_OR_RETURN(in, decode(codecs[i], in, i == 0 ? expected : 0));
  }
  if (expected && in.size() != expected) return size_mismatch("chunk", in.size(), expected);
  return in;
}

Result<std::vector<uint8_t>> encode_chain(const std::vector<BytesCodec>& codecs, std::vector<uint8_t> in) {
  for (const BytesCodec& c : codecs) {
    VXR_ASSIGN_OR_RETURN(in, encode(c, in));
  }
  return in;
}

}  // namespace vxr::zarr
