// Converts a SlabSource (an importer's output) into a .vxc container with its
// whole resolution pyramid, in bounded memory, resumably.
//
// Level 0 is read from the source in tiles (full rows of chunks, one chunk
// layer thick, shrunk to fit the memory budget); level l+1 is computed from
// level l's chunks read back from the file being written. Every chunk is a
// pure function of the source, so a resumed conversion writes the same chunks
// as an uninterrupted one. A reader thread prefetches the next tile while
// worker threads encode the current one.
#pragma once

#include <cstdint>
#include <optional>
#include <string>

#include "core/progress.h"
#include "core/status.h"
#include "volume/container_layout.h"
#include "volume/slab_source.h"

namespace vxr {

struct ImportOptions {
  uint32_t chunk_size = 64;
  uint32_t apron = 1;
  uint64_t memory_bytes = uint64_t(512) << 20;  // budget for voxel buffers (tiles, chunk scratch)
  bool resume = false;
  vxc::Downsample downsample = vxc::Downsample::kMean;
  std::optional<vxc::Codec> codec;  // default_codec(dtype) when unset
  uint32_t threads = 2;             // encoder threads (>= 1)
};

struct ImportSummary {
  ContainerLayout layout;
  uint64_t chunks = 0;          // chunks in the finished file
  uint64_t chunks_resumed = 0;  // of those, found in the partial file
  uint64_t input_bytes = 0;     // level-0 voxel bytes (all channels and timepoints)
  uint64_t file_bytes = 0;
  double seconds = 0;
};

// Builds `path` from `source`. On failure the partial file `path`.partial is
// left for --resume (unless nothing was written); `path` itself only appears
// when the container is complete. `progress` (optional) counts voxel bytes
// of every level.
Result<ImportSummary> build_container(SlabSource& source, const std::string& path, const ImportOptions& options,
                                      Progress* progress = nullptr);

// The layout build_container will write for a source with `info`.
Result<ContainerLayout> import_layout(const VolumeInfo& info, const ImportOptions& options);

// Total work units build_container reports to Progress for `layout`.
uint64_t pyramid_work_bytes(const ContainerLayout& layout);

// Parses "512M", "2G", "300k", "1048576" (binary multiples). nullopt if malformed.
std::optional<uint64_t> parse_byte_size(const std::string& text);

}  // namespace vxr
