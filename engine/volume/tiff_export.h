// Exports one level of a ChunkSource (a .vxc container) as a multi-page TIFF
// (tiff_writer.h), so data leaves as it came: level 0 of integer data round-
// trips bit for bit.
#pragma once

#include <cstdint>
#include <optional>
#include <string>

#include "core/progress.h"
#include "core/status.h"
#include "volume/chunk_source.h"

namespace vxr {

struct TiffExportOptions {
  uint32_t level = 0;
  std::optional<uint32_t> channel;    // unset: every channel (an ImageJ hyperstack)
  std::optional<uint32_t> timepoint;  // unset: every timepoint
  uint64_t memory_budget = uint64_t(512) << 20;  // decoded voxels held at once (one chunk layer when it fits)
  Progress* progress = nullptr;       // advanced by bytes written
};

// Writes `out_path` atomically. Errors name the file and the problem; on error
// no file is left at out_path.
Status export_tiff(const ChunkSource& source, const std::string& out_path, const TiffExportOptions& options = {});

}  // namespace vxr
