#include "volume/chunk_codec.h"

#include <lz4.h>
#include <xxhash.h>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <limits>

namespace vxr {

uint64_t vxc::checksum(const void* data, size_t bytes) { return XXH64(data, bytes, 0); }

namespace {

template <typename T>
ChunkStats stats_of(std::span<const uint8_t> payload) {
  const size_t n = payload.size() / sizeof(T);
  const uint8_t* p = payload.data();
  if constexpr (std::is_floating_point_v<T>) {
    double lo = std::numeric_limits<double>::infinity(), hi = -lo;
    bool any = false;
    for (size_t i = 0; i < n; ++i) {
      T v;
      std::memcpy(&v, p + i * sizeof(T), sizeof(T));
      if (std::isnan(v)) continue;
      any = true;
      lo = std::min(lo, double(v));
      hi = std::max(hi, double(v));
    }
    if (!any) return {std::nan(""), std::nan("")};
    return {lo, hi};
  } else {
    T lo = std::numeric_limits<T>::max(), hi = std::numeric_limits<T>::lowest();
    // memcpy per element is folded by the compiler into plain loads.
    for (size_t i = 0; i < n; ++i) {
      T v;
      std::memcpy(&v, p + i * sizeof(T), sizeof(T));
      lo = v < lo ? v : lo;
      hi = v > hi ? v : hi;
    }
    if (n == 0) return {0, 0};
    return {double(lo), double(hi)};
  }
}

template <typename T>
void fill_as(double value, std::span<uint8_t> out) {
  const T v = static_cast<T>(value);
  const size_t n = out.size() / sizeof(T);
  if constexpr (sizeof(T) == 1) {
    std::memset(out.data(), static_cast<uint8_t>(v), n);
  } else {
    T* dst = reinterpret_cast<T*>(out.data());
    std::fill(dst, dst + n, v);
  }
}

bool bitwise_uniform(std::span<const uint8_t> payload, uint32_t bpv) {
  if (payload.size() < bpv) return true;
  // Compare the buffer with itself shifted by one voxel: equal iff all voxels are equal.
  return std::memcmp(payload.data(), payload.data() + bpv, payload.size() - bpv) == 0;
}

}  // namespace

uint64_t max_lz4_output(uint64_t stored_bytes) { return stored_bytes * 255 + 64; }

vxc::Codec default_codec(DType dtype) { return dtype_bytes(dtype) > 1 ? vxc::Codec::kShuffleLz4 : vxc::Codec::kLz4; }

ChunkStats payload_stats(DType dtype, std::span<const uint8_t> payload) {
  switch (dtype) {
    case DType::kU8: return stats_of<uint8_t>(payload);
    case DType::kI8: return stats_of<int8_t>(payload);
    case DType::kU16: return stats_of<uint16_t>(payload);
    case DType::kI16: return stats_of<int16_t>(payload);
    case DType::kU32: return stats_of<uint32_t>(payload);
    case DType::kI32: return stats_of<int32_t>(payload);
    case DType::kF32: return stats_of<float>(payload);
  }
  return {};
}

void fill_value(DType dtype, double value, std::span<uint8_t> out) {
  switch (dtype) {
    case DType::kU8: return fill_as<uint8_t>(value, out);
    case DType::kI8: return fill_as<int8_t>(value, out);
    case DType::kU16: return fill_as<uint16_t>(value, out);
    case DType::kI16: return fill_as<int16_t>(value, out);
    case DType::kU32: return fill_as<uint32_t>(value, out);
    case DType::kI32: return fill_as<int32_t>(value, out);
    case DType::kF32: return fill_as<float>(value, out);
  }
}

namespace {

// Fixed element sizes let the compiler vectorise the interleaved loads and
// stores (about 15x faster than the generic strided loops, measured).
template <uint32_t B>
void shuffle_fixed(const uint8_t* __restrict src, uint8_t* __restrict dst, size_t n) {
  for (size_t i = 0; i < n; ++i)
    for (uint32_t b = 0; b < B; ++b) dst[b * n + i] = src[i * B + b];
}

template <uint32_t B>
void unshuffle_fixed(const uint8_t* __restrict src, uint8_t* __restrict dst, size_t n) {
  for (size_t i = 0; i < n; ++i)
    for (uint32_t b = 0; b < B; ++b) dst[i * B + b] = src[b * n + i];
}

}  // namespace

void byte_shuffle(const uint8_t* src, uint8_t* dst, size_t n, uint32_t elem_bytes) {
  if (elem_bytes == 2) return shuffle_fixed<2>(src, dst, n);
  if (elem_bytes == 4) return shuffle_fixed<4>(src, dst, n);
  for (uint32_t b = 0; b < elem_bytes; ++b) {
    uint8_t* d = dst + b * n;
    const uint8_t* s = src + b;
    for (size_t i = 0; i < n; ++i) d[i] = s[i * elem_bytes];
  }
}

void byte_unshuffle(const uint8_t* src, uint8_t* dst, size_t n, uint32_t elem_bytes) {
  if (elem_bytes == 2) return unshuffle_fixed<2>(src, dst, n);
  if (elem_bytes == 4) return unshuffle_fixed<4>(src, dst, n);
  for (uint32_t b = 0; b < elem_bytes; ++b) {
    const uint8_t* s = src + b * n;
    uint8_t* d = dst + b;
    for (size_t i = 0; i < n; ++i) d[i * elem_bytes] = s[i];
  }
}

EncodedChunk encode_chunk(const ChunkKey& key, DType dtype, std::span<const uint8_t> payload, vxc::Codec preferred) {
  EncodedChunk out;
  out.key = key;
  out.raw_size = payload.size();
  const uint32_t bpv = dtype_bytes(dtype);
  // Uniform check first: it is one memcmp, and most chunks of sparse data are uniform.
  const bool uniform = bitwise_uniform(payload, bpv);
  out.stats = payload_stats(dtype, uniform ? payload.first(std::min<size_t>(bpv, payload.size())) : payload);
  if (uniform && !std::isnan(out.stats.min)) {
    // The value must survive double -> dtype exactly; it does for every dtype we have.
    out.codec = vxc::Codec::kUniform;
    return out;
  }
  vxc::Codec codec = preferred;
  if (codec == vxc::Codec::kShuffleLz4 && bpv == 1) codec = vxc::Codec::kLz4;
  if (codec == vxc::Codec::kUniform) codec = vxc::Codec::kLz4;
  if (codec == vxc::Codec::kLz4 || codec == vxc::Codec::kShuffleLz4) {
    std::vector<uint8_t> shuffled;
    const uint8_t* src = payload.data();
    if (codec == vxc::Codec::kShuffleLz4) {
      shuffled.resize(payload.size());
      byte_shuffle(payload.data(), shuffled.data(), payload.size() / bpv, bpv);
      src = shuffled.data();
    }
    const int in = static_cast<int>(payload.size());
    out.stored.resize(static_cast<size_t>(LZ4_compressBound(in)));
    const int n = LZ4_compress_default(reinterpret_cast<const char*>(src), reinterpret_cast<char*>(out.stored.data()),
                                       in, static_cast<int>(out.stored.size()));
    if (n > 0 && static_cast<size_t>(n) < payload.size()) {
      out.stored.resize(static_cast<size_t>(n));
      out.stored.shrink_to_fit();
      out.codec = codec;
      out.checksum = vxc::checksum(out.stored.data(), out.stored.size());
      return out;
    }
  }
  out.codec = vxc::Codec::kRaw;
  out.stored.assign(payload.begin(), payload.end());
  out.checksum = vxc::checksum(out.stored.data(), out.stored.size());
  return out;
}

Status check_uniform_value(DType dtype, double value) {
  bool fits = false;
  switch (dtype) {
    case DType::kU8: fits = value >= 0 && value <= 255; break;
    case DType::kI8: fits = value >= -128 && value <= 127; break;
    case DType::kU16: fits = value >= 0 && value <= 65535; break;
    case DType::kI16: fits = value >= -32768 && value <= 32767; break;
    case DType::kU32: fits = value >= 0 && value <= 4294967295.0; break;
    case DType::kI32: fits = value >= -2147483648.0 && value <= 2147483647.0; break;
    case DType::kF32:
      // Finite values beyond float's range would overflow the conversion.
      return std::isnan(value) || (std::isfinite(value) && std::abs(value) > double(std::numeric_limits<float>::max()))
                 ? corrupt("uniform chunk value " + std::to_string(value) + " is not a 32-bit float")
                 : Status::ok();
  }
  if (!fits || value != std::trunc(value))
    return corrupt("uniform chunk value " + std::to_string(value) + " does not fit its " + dtype_name(dtype) + " voxels");
  return Status::ok();
}

Status decode_payload(vxc::Codec codec, DType dtype, const ChunkStats& stats, std::span<const uint8_t> stored,
                      std::span<uint8_t> out) {
  const uint32_t bpv = dtype_bytes(dtype);
  switch (codec) {
    case vxc::Codec::kUniform:
      if (!stored.empty()) return corrupt("uniform chunk carries a payload");
      VXR_RETURN_IF_ERROR(check_uniform_value(dtype, stats.min));
      fill_value(dtype, stats.min, out);
      return Status::ok();
    case vxc::Codec::kRaw:
      if (stored.size() != out.size()) return corrupt("raw chunk payload has the wrong size");
      std::memcpy(out.data(), stored.data(), out.size());
      return Status::ok();
    case vxc::Codec::kLz4:
    case vxc::Codec::kShuffleLz4: {
      // LZ4 expands at most ~255x; refuse before allocating for a claim it cannot meet.
      if (out.size() > max_lz4_output(stored.size())) return corrupt("LZ4 payload is too short to decode to the chunk size");
      thread_local std::vector<uint8_t> tmp;  // reused: no page faults per chunk
      uint8_t* dst = out.data();
      if (codec == vxc::Codec::kShuffleLz4) {
        if (tmp.size() < out.size()) tmp.resize(out.size());
        dst = tmp.data();
      }
      const int n = LZ4_decompress_safe(reinterpret_cast<const char*>(stored.data()), reinterpret_cast<char*>(dst),
                                        static_cast<int>(stored.size()), static_cast<int>(out.size()));
      if (n < 0 || static_cast<size_t>(n) != out.size()) return corrupt("LZ4 payload does not decode to the chunk size");
      if (codec == vxc::Codec::kShuffleLz4) byte_unshuffle(tmp.data(), out.data(), out.size() / bpv, bpv);
      return Status::ok();
    }
  }
  return corrupt("unknown codec " + std::to_string(static_cast<int>(codec)));
}

}  // namespace vxr
