// The per-channel display metadata formats state (VolumeInfo::channel_display),
// parsed from each format's spelling, and the one text form vxr writes.
#pragma once

#include <array>
#include <cstdint>
#include <optional>
#include <string>
#include <string_view>

namespace vxr {

using Rgb8 = std::array<uint8_t, 3>;

// OME-XML Channel@Color: a signed 32-bit integer packing R, G, B, A (R in the
// top byte). Alpha is dropped: opacity comes from the data. nullopt when the
// text is not an integer within 32 bits (signed or unsigned).
std::optional<Rgb8> color_from_ome_int(std::string_view text);

// OME-Zarr omero.channels[].color and vxr's own form: "RRGGBB" hex, with or
// without a leading '#'. nullopt for anything else.
std::optional<Rgb8> color_from_hex(std::string_view text);

// Imaris DataSetInfo/Channel N@Color: "r g b", three numbers in 0..1
// (rounded to 0..255). nullopt when it is not that.
std::optional<Rgb8> color_from_unit_floats(std::string_view text);

// "#rrggbb", lower case: the colormap name of the single hue `c` (black to c).
std::string color_hex(const Rgb8& c);

// A channel name as vxr keeps it: control characters dropped, surrounding
// spaces trimmed, at most kMaxChannelNameBytes bytes (cut at a UTF-8
// character boundary).
constexpr size_t kMaxChannelNameBytes = 63;
std::string clean_channel_name(std::string_view text);

}  // namespace vxr
