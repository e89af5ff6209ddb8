// Raw voxels described by a JSON sidecar (the format of assets/mri-stack):
//   {"file": "x.raw", "dims": [x, y, z], "dtype": "u16", "channels": 1,
//    "timepoints": 1, "voxel_size": [1, 1, 1], "unit": "um", "endian": "little"}
// Data order: x fastest, then y, z, channel, timepoint.
#pragma once

#include <memory>
#include <string>

#include "core/status.h"
#include "volume/slab_source.h"

namespace vxr {

Result<std::unique_ptr<SlabSource>> open_raw_import(const std::string& json_path);

}  // namespace vxr
