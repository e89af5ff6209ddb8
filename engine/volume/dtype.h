// Voxel data types that volumes carry.
#pragma once

#include <cstdint>
#include <optional>
#include <string>
#include <string_view>

namespace vxr {

enum class DType : uint8_t { kU8 = 0, kI8 = 1, kU16 = 2, kI16 = 3, kU32 = 4, kI32 = 5, kF32 = 6 };

inline uint32_t dtype_bytes(DType t) {
  switch (t) {
    case DType::kU8:
    case DType::kI8: return 1;
    case DType::kU16:
    case DType::kI16: return 2;
    default: return 4;
  }
}

// "u8", "i8", "u16", "i16", "u32", "i32", "f32"
const char* dtype_name(DType t);
std::optional<DType> dtype_from_name(std::string_view name);

// The voxel at `p` (native byte order, any alignment) as a double in its own units.
double decode_voxel(const uint8_t* p, DType t);

}  // namespace vxr
