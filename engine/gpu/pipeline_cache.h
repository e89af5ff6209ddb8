// The VkPipelineCache vxr keeps on disk, so a second run (and every pose of a
// run) builds no shader twice.
//
// File: VXR_PIPELINE_CACHE (a path; "off" disables it), else
// $XDG_CACHE_HOME/vxr/pipelines.bin, else $HOME/.cache/vxr/pipelines.bin.
// Layout: a vxr header (magic, the device's vendor/device id and pipeline
// cache UUID, payload size, FNV-1a 64 of the payload), then the driver's
// cache data. A file that fails any check is refused with a warning naming
// the file and the problem, and the cache starts empty (it is rewritten at
// exit); a driver never sees bytes that did not pass.
#pragma once

#include <vulkan/vulkan.h>

#include <cstdint>
#include <string>
#include <vector>

#include "core/status.h"

namespace vxr::gpu {

// Where the cache lives; empty when disabled.
std::string pipeline_cache_path();

// The driver payload of `path`, validated against `props`. kNotFound when the
// file does not exist; kCorrupt (with the reason) when it is refused.
Result<std::vector<uint8_t>> read_pipeline_cache(const std::string& path, const VkPhysicalDeviceProperties& props);

// Writes `payload` under the vxr header (to a temporary file, then renamed, so
// concurrent processes never see half a file). Creates the folder.
Status write_pipeline_cache(const std::string& path, const VkPhysicalDeviceProperties& props,
                            const std::vector<uint8_t>& payload);

}  // namespace vxr::gpu
