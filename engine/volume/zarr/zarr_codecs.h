// The bytes-to-bytes codecs of Zarr: what turns a stored chunk into raw voxel
// bytes and back. Zarr v2 names one "compressor" (numcodecs ids), Zarr v3 a
// list of codecs; both map onto BytesCodec.
//
//   gzip, zlib  deflate (zlib1g); decode accepts either wrapper
//   zstd        Zstandard frames (libzstd), streamed so a frame without a
//               content size decodes too
//   blosc       Blosc 1 frames (libblosc: lz4, lz4hc, zstd, zlib, blosclz;
//               byte/bit shuffle are recorded in the frame header)
//   lz4         numcodecs' LZ4: a 4-byte little-endian size, then one LZ4 block
//   crc32c      v3 checksum: the payload followed by its CRC-32C, little-endian
//
// Encoding exists for the tests' fixtures and for a later zarr writer.
#pragma once

#include <cstdint>
#include <nlohmann/json_fwd.hpp>
#include <span>
#include <string>
#include <vector>

#include "core/status.h"

namespace vxr::zarr {

enum class CodecId : uint8_t { kGzip, kZlib, kZstd, kBlosc, kLz4, kCrc32c };

struct BytesCodec {
  CodecId id = CodecId::kGzip;
  int level = 5;                    // gzip/zlib/zstd level, blosc clevel (encoding only)
  std::string blosc_cname = "lz4";  // blosc inner compressor (encoding only)
  int blosc_shuffle = 1;            // 0 none, 1 byte, 2 bit (encoding only)
  uint32_t blosc_typesize = 1;      // element size the shuffle works on (encoding only)
};

const char* codec_name(CodecId id);

// A v2 "compressor" object ({"id": "blosc", "cname": ...}). Errors are
// messages without the file name: "'compressor': unknown id 'lzma' (...)".
Result<BytesCodec> parse_v2_compressor(const nlohmann::json& j);
// A v3 codec object ({"name": "gzip", "configuration": {...}}) that is known
// to be bytes-to-bytes; `where` names it in errors ("'codecs'[1]").
Result<BytesCodec> parse_v3_bytes_codec(const nlohmann::json& j, const std::string& where);
// True for the v3 codec names parse_v3_bytes_codec takes.
bool is_v3_bytes_codec(const std::string& name);

// One codec. `expected_size` is the decoded size when known (0 when not): a
// different size is an error, never truncated or padded data. Errors are
// messages without the chunk's name: "gzip: data is corrupt (...)".
Result<std::vector<uint8_t>> decode(const BytesCodec& codec, std::span<const uint8_t> in, size_t expected_size);
Result<std::vector<uint8_t>> encode(const BytesCodec& codec, std::span<const uint8_t> in);

// A chain as stored: encode applies codecs[0] first, decode undoes the last first.
Result<std::vector<uint8_t>> decode_chain(const std::vector<BytesCodec>& codecs, std::vector<uint8_t> in,
                                          size_t expected_size);
Result<std::vector<uint8_t>> encode_chain(const std::vector<BytesCodec>& codecs, std::vector<uint8_t> in);

// CRC-32C (Castagnoli), as the v3 crc32c codec stores it.
uint32_t crc32c(std::span<const uint8_t> bytes);

}  // namespace vxr::zarr
