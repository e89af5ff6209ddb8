// Reading JSON numbers from files into fixed-width types without undefined
// behaviour: nlohmann's get<uint32_t>() of 1e300 is an out-of-range
// float-to-integer conversion (undefined), and of -1 silently wraps.
//
// Header-only: the modules that parse JSON link nlohmann_json themselves.
#pragma once

#include <cmath>
#include <limits>
#include <optional>
#include <type_traits>

#include <nlohmann/json.hpp>

namespace vxr {

// `v` as T when it is a number that T holds exactly (integers: an integral
// value in range; floating point: any finite number); nullopt otherwise.
template <typename T>
std::optional<T> json_number(const nlohmann::json& v) {
  static_assert(std::is_arithmetic_v<T> && !std::is_same_v<T, bool>);
  if (!v.is_number()) return std::nullopt;
  if constexpr (std::is_integral_v<T>) {
    if (v.is_number_unsigned()) {
      const auto u = v.get<uint64_t>();
      if (u > uint64_t(std::numeric_limits<T>::max())) return std::nullopt;
      return T(u);
    }
    if (v.is_number_integer()) {
      const auto i = v.get<int64_t>();
      if (i < 0 && !std::is_signed_v<T>) return std::nullopt;
      if (i < int64_t(std::numeric_limits<T>::lowest()) ||
          (i > 0 && uint64_t(i) > uint64_t(std::numeric_limits<T>::max())))
        return std::nullopt;
      return T(i);
    }
    // A float such as 3.0 is accepted when it is an integer inside T's range.
    const double d = v.get<double>();
    if (!std::isfinite(d) || d != std::trunc(d) || d < double(std::numeric_limits<T>::lowest()) ||
        d >= std::ldexp(1.0, std::numeric_limits<T>::digits))
      return std::nullopt;
    return T(d);
  } else {
    const double d = v.get<double>();
    if (!std::isfinite(d) || std::abs(d) > double(std::numeric_limits<T>::max())) return std::nullopt;
    return T(d);
  }
}

}  // namespace vxr
