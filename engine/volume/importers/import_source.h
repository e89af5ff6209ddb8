// The one entry point from user inputs to a SlabSource: picks the importer by
// content and extension. Each format lives in its own file in this folder.
#pragma once

#include <array>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "core/status.h"
#include "volume/slab_source.h"

namespace vxr {

// What the user said on the command line; overrides what files claim.
struct ImportHints {
  std::optional<std::array<double, 3>> voxel_size;
  std::optional<std::string> unit;
  // The import's memory budget (--memory); readers refuse buffers a header
  // sizes past it. Unset: the current budget (import_limits.h) stays.
  std::optional<uint64_t> memory_bytes;
};

// Finite, positive and at most 1e6 between the largest and smallest axis.
bool voxel_size_usable(const std::array<double, 3>& voxel_size);

// inputs: one file, several files (a slice series), a folder, or a glob.
// Errors name the offending file and the problem.
Result<std::unique_ptr<SlabSource>> open_import_source(const std::vector<std::string>& inputs,
                                                       const ImportHints& hints = {});

}  // namespace vxr
