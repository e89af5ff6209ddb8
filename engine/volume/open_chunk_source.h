// The one place that decides which inputs are read in place as a ChunkSource
// (drawn by the out-of-core renderer, no import needed): .vxc containers and
// OME-Zarr folders. `vxr render`, `vxr view` and load_for_render ask here.
#pragma once

#include <memory>
#include <string>
#include <vector>

#include "core/status.h"
#include "volume/chunk_source.h"

namespace vxr {

// True for a path ending in .vxc or starting with the .vxc magic, or a folder (or zarr.json/.zattrs file) with Zarr metadata.
bool is_chunk_source_input(const std::string& path);

struct OpenedChunkSource {
  std::unique_ptr<ChunkSource> source;
  std::string format;                 // "vxc container", "OME-Zarr 0.4 (Zarr v2)", ...
  std::vector<std::string> warnings;  // worth showing the user
};

// Opens a path is_chunk_source_input() accepts; errors name the file.
Result<OpenedChunkSource> open_chunk_source(const std::string& path);

}  // namespace vxr
