// What a multi-channel, multi-timepoint volume is, independent of storage.
#pragma once

#include <array>
#include <cstdint>
#include <optional>
#include <string>
#include <vector>

#include "volume/dtype.h"

namespace vxr {

// How the file says one channel is shown, where it says so (OME-XML Channel,
// OME-Zarr omero.channels, Imaris DataSetInfo/Channel N). Every field is
// optional: a viewer falls back to its own choice for what is missing.
struct ChannelDisplay {
  std::string name;                              // empty: none stated
  std::optional<std::array<uint8_t, 3>> color;   // RGB, 0..255
  std::optional<std::array<double, 2>> window;   // display range lo < hi, in data units

  bool empty() const { return name.empty() && !color && !window; }
};

struct VolumeInfo {
  std::array<uint64_t, 3> dims{0, 0, 0};      // level-0 voxels along x, y, z
  DType dtype = DType::kU8;
  uint32_t channels = 1;
  uint32_t timepoints = 1;
  std::array<double, 3> voxel_size{1, 1, 1};  // physical size of one level-0 voxel
  std::string unit = "um";                    // "um", "nm", "mm", ... ("px" when unknown)
  // Physical position (in `unit`) of voxel (0, 0, 0): OME-Zarr's translation,
  // so volumes of one experiment keep their relative placement. 0 when unknown.
  std::array<double, 3> origin{0, 0, 0};
  // What the file says about showing each channel: empty (nothing stated),
  // or exactly `channels` entries.
  std::vector<ChannelDisplay> channel_display;

  // Channel c's display metadata; an empty one when the file states none.
  const ChannelDisplay& display(uint32_t c) const {
    static const ChannelDisplay kNone;
    return c < channel_display.size() ? channel_display[c] : kNone;
  }

  uint64_t voxels_per_volume() const { return dims[0] * dims[1] * dims[2]; }
};

// An axis-aligned block of voxels: [origin, origin + size).
struct Box3 {
  std::array<uint64_t, 3> origin{0, 0, 0};
  std::array<uint64_t, 3> size{0, 0, 0};
  uint64_t voxels() const { return size[0] * size[1] * size[2]; }
};

}  // namespace vxr
