// Chunk payload encoding for the .vxc container: statistics, uniform
// detection, byte shuffle and LZ4 (spec and measurements: docs/container-format.md).
#pragma once

#include <cstdint>
#include <span>
#include <vector>

#include "core/status.h"
#include "volume/chunk_source.h"
#include "volume/container_format.h"
#include "volume/dtype.h"

namespace vxr {

// A chunk ready to append: what the container stores about it.
struct EncodedChunk {
  ChunkKey key;
  vxc::Codec codec = vxc::Codec::kRaw;
  ChunkStats stats;         // over the whole payload, apron included
  uint64_t raw_size = 0;    // decoded payload bytes
  std::vector<uint8_t> stored;  // empty for kUniform
  uint64_t checksum = 0;    // XXH64 of `stored` (0 for kUniform)
};

// The codec used for data chunks of `dtype` unless the user picks one:
// shuffle+LZ4 for 16/32-bit voxels, LZ4 for 8-bit (measured; see the spec).
vxc::Codec default_codec(DType dtype);

// Min/max over `payload` (NaNs ignored; all-NaN gives min = max = NaN).
ChunkStats payload_stats(DType dtype, std::span<const uint8_t> payload);

// Encodes `payload` (edge^3 voxels of `dtype`). A payload whose voxels are all
// bitwise one value (and not NaN) becomes kUniform with no bytes; otherwise
// `preferred` is tried (kShuffleLz4 falls back to kLz4 for 8-bit data) and the
// raw bytes are stored when compression would not make them smaller.
EncodedChunk encode_chunk(const ChunkKey& key, DType dtype, std::span<const uint8_t> payload, vxc::Codec preferred);

// Decodes `stored` into `out` (exactly raw_size bytes). Never writes outside
// `out`; malformed input gives kCorrupt.
Status decode_payload(vxc::Codec codec, DType dtype, const ChunkStats& stats, std::span<const uint8_t> stored,
                      std::span<uint8_t> out);

// The most bytes an LZ4 block of `stored_bytes` can decode to (a match byte
// encodes at most 255 bytes), so a payload claiming more is refused unread.
uint64_t max_lz4_output(uint64_t stored_bytes);

// kOk when `value` is what a uniform chunk of `dtype` may hold: a number the
// dtype represents exactly (integers in range; any non-NaN value for f32).
// Values come from files, and converting one that does not fit is undefined.
Status check_uniform_value(DType dtype, double value);

// Byte shuffle: dst[b * n + i] = byte b of element i (n elements of elem_bytes);
// src and dst must not overlap.
void byte_shuffle(const uint8_t* src, uint8_t* dst, size_t n, uint32_t elem_bytes);
void byte_unshuffle(const uint8_t* src, uint8_t* dst, size_t n, uint32_t elem_bytes);

// Fills `out` with `value` converted to `dtype`.
void fill_value(DType dtype, double value, std::span<uint8_t> out);

}  // namespace vxr
