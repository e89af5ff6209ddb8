#include "volume/channel_display.h"

#include <cerrno>
#include <cmath>
#include <cstdlib>
#include <sstream>

namespace vxr {

std::optional<Rgb8> color_from_ome_int(std::string_view text) {
  const std::string s(text);
  char* end = nullptr;
  errno = 0;
  const long long v = std::strtoll(s.c_str(), &end, 10);
  if (s.empty() || *end != '\0' || errno == ERANGE || v < INT32_MIN || v > int64_t(UINT32_MAX)) return std::nullopt;
  const uint32_t rgba = static_cast<uint32_t>(v);
  return Rgb8{uint8_t(rgba >> 24), uint8_t(rgba >> 16), uint8_t(rgba >> 8)};
}

std::optional<Rgb8> color_from_hex(std::string_view text) {
  if (!text.empty() && text.front() == '#') text.remove_prefix(1);
  if (text.size() != 6) return std::nullopt;
  Rgb8 out{};
  for (int i = 0; i < 3; ++i) {
    int v = 0;
    for (char ch : text.substr(2 * i, 2)) {
      const int d = ch >= '0' && ch <= '9' ? ch - '0'
                    : ch >= 'a' && ch <= 'f' ? ch - 'a' + 10
                    : ch >= 'A' && ch <= 'F' ? ch - 'A' + 10
                                             : -1;
      if (d < 0) return std::nullopt;
      v = v * 16 + d;
    }
    out[i] = uint8_t(v);
  }
  return out;
}

std::optional<Rgb8> color_from_unit_floats(std::string_view text) {
  std::istringstream in{std::string(text)};
  double v[3];
  if (!(in >> v[0] >> v[1] >> v[2])) return std::nullopt;
  std::string rest;
  if (in >> rest) return std::nullopt;
  Rgb8 out{};
  for (int i = 0; i < 3; ++i) {
    if (!(v[i] >= 0.0 && v[i] <= 1.0)) return std::nullopt;
    out[i] = uint8_t(std::lround(v[i] * 255.0));
  }
  return out;
}

std::string color_hex(const Rgb8& c) {
  static const char* digits = "0123456789abcdef";
  std::string s = "#";
  for (uint8_t v : c) s += digits[v >> 4], s += digits[v & 15];
  return s;
}

std::string clean_channel_name(std::string_view text) {
  std::string s;
  for (char ch : text)
    if (static_cast<unsigned char>(ch) >= 0x20 && ch != 0x7f) s += ch;
  const size_t first = s.find_first_not_of(' ');
  if (first == std::string::npos) return "";
  s = s.substr(first, s.find_last_not_of(' ') - first + 1);
  if (s.size() > kMaxChannelNameBytes) {
    size_t cut = kMaxChannelNameBytes;
    while (cut > 0 && (static_cast<unsigned char>(s[cut]) & 0xC0) == 0x80) --cut;  // not inside a character
    s.resize(cut);
    s = s.substr(0, s.find_last_not_of(' ') + 1);
  }
  return s;
}

}  // namespace vxr
