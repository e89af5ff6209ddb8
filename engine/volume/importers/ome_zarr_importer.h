// OME-Zarr (NGFF 0.4 / Zarr v2 and 0.5 / Zarr v3) as an import source: level 0
// of the image (see zarr/ome_zarr.h for what is read).
#pragma once

#include <memory>
#include <string>

#include "core/status.h"
#include "volume/slab_source.h"

namespace vxr {

// `path`: the image folder (or its zarr.json / .zattrs). Errors name the
// metadata file and key, or the chunk that failed.
Result<std::unique_ptr<SlabSource>> open_ome_zarr_import(const std::string& path);

}  // namespace vxr
