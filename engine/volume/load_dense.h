// Loading what `vxr render` draws: any importable input (raw+JSON sidecar,
// TIFF, OME-TIFF, slice folders, Imaris, ...) as whole channels in memory,
// shrunk by 2x box averaging until each fits the GPU's 3D texture limits;
// chunk sources (.vxc, OME-Zarr; see open_chunk_source.h) give their finest
// pyramid level that fits instead.
#pragma once

#include <string>
#include <vector>

#include "core/status.h"
#include "volume/dense_volume.h"
#include "volume/volume_info.h"

namespace vxr {

struct LoadedVolume {
  std::vector<DenseVolume> channels;  // timepoint 0, 1..4 channels
  // Timepoints 1.. of a time series (each as `channels`), when the whole
  // series fits the per-channel byte budget; else empty (timepoint 0 only).
  std::vector<std::vector<DenseVolume>> later_timepoints;
  uint32_t shrink = 1;                // 1, 2, 4, ...: how much was averaged away to fit
  std::string format;                 // what read it
  std::vector<std::string> notes;     // warnings worth showing
  std::vector<ChannelDisplay> channel_display;  // the file's, for `channels`; empty: none stated
};

// max_dim: the device's maxImageDimension3D; max_bytes: per-channel budget.
Result<LoadedVolume> load_for_render(const std::string& path, uint32_t max_dim, uint64_t max_bytes);

// 2x mean in every axis (odd edges keep their last voxel); same dtype.
DenseVolume shrink_by_two(const DenseVolume& v);

}  // namespace vxr
