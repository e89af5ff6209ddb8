// Overflow-checked arithmetic for sizes that come from files.
//
// Every byte count or element count computed from numbers a file claims
// (dimensions, chunk counts, strip sizes) goes through these helpers, so a
// hostile header is refused with a message instead of wrapping around into a
// small allocation (out-of-bounds writes) or a huge one (bad_alloc, OOM).
#pragma once

#include <cstdint>
#include <initializer_list>
#include <optional>

namespace vxr {

// a * b * ..., or nullopt when the product does not fit in 64 bits.
inline std::optional<uint64_t> checked_product(std::initializer_list<uint64_t> factors) {
  uint64_t p = 1;
  for (uint64_t f : factors)
    if (__builtin_mul_overflow(p, f, &p)) return std::nullopt;
  return p;
}

// a + b + ..., or nullopt when the sum does not fit in 64 bits.
inline std::optional<uint64_t> checked_sum(std::initializer_list<uint64_t> terms) {
  uint64_t s = 0;
  for (uint64_t t : terms)
    if (__builtin_add_overflow(s, t, &s)) return std::nullopt;
  return s;
}

// True when [offset, offset + length) lies inside [0, size), without overflow.
inline bool range_inside(uint64_t offset, uint64_t length, uint64_t size) {
  return offset <= size && length <= size - offset;
}

}  // namespace vxr
