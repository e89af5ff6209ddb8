// Reads a finished .vxc container (spec: docs/container-format.md) as a
// ChunkSource.
//
//   auto reader = ContainerReader::open("brain.vxc");
//   if (!reader) return reader.status();          // one-line message naming the file
//   auto chunk = (*reader)->read({.level = 2, .x = 1});
//
// open() checks the header, the footer and the index (checksums, bounds,
// no duplicates); read() checks the chunk's record header against the index
// and the payload checksum before decoding, so damage comes back as kCorrupt,
// never as wrong voxels or a crash.
#pragma once

#include <memory>
#include <string>
#include <vector>

#include "core/status.h"
#include "volume/chunk_source.h"
#include "volume/container_format.h"
#include "volume/container_io.h"
#include "volume/container_layout.h"
#include "volume/dense_volume.h"

namespace vxr {

class ContainerReader final : public ChunkSource {
 public:
  // Opens `path`. kNotFound if it does not exist; kCorrupt (naming the damaged
  // part) if the header, footer or index fail their checks, or if the file is
  // an unfinished conversion (no footer).
  static Result<std::unique_ptr<ContainerReader>> open(const std::string& path);

  const VolumeInfo& info() const override { return layout_.info; }
  const std::vector<LevelInfo>& levels() const override { return layout_.levels; }
  uint32_t chunk_size() const override { return layout_.chunk_size; }
  uint32_t apron() const override { return layout_.apron; }
  Result<ChunkStats> stats(const ChunkKey& key) const override;
  Result<std::shared_ptr<const Chunk>> read(const ChunkKey& key) const override;

  const ContainerLayout& layout() const { return layout_; }
  const std::string& path() const { return path_; }
  // Every index entry, sorted by (level, timepoint, channel, z, y, x).
  const std::vector<vxc::IndexEntry>& entries() const { return entries_; }
  uint64_t file_bytes() const { return file_bytes_; }
  // Voxel bytes of every level (interior voxels only: no apron, no edge
  // padding), all channels and timepoints, divided by the file size.
  double compression_ratio() const;

 private:
  ContainerReader() = default;
  const vxc::IndexEntry* find(const ChunkKey& key) const;

  std::string path_;
  ContainerFile file_;
  ContainerLayout layout_;
  std::vector<vxc::IndexEntry> entries_;
  std::vector<std::vector<int64_t>> slots_;  // per level: dense chunk slot -> entries_ index or -1
  uint64_t file_bytes_ = 0;
  uint64_t index_offset_ = 0;
};

// Reads one whole level of one channel/timepoint into memory (the interior
// voxels of every chunk). For volumes that fit a GPU texture: fails with
// kOutOfRange if a side exceeds 2^32-1 voxels or the level exceeds `max_bytes`.
// voxel_size is the level-0 voxel size times the level's downsample factors.
Result<DenseVolume> read_level_dense(const ChunkSource& source, uint32_t level, uint32_t channel = 0,
                                     uint32_t timepoint = 0, uint64_t max_bytes = uint64_t(4) << 30);

// The finest level whose every side is <= max_side voxels and whose size is <=
// max_bytes (for picking what to upload as one 3D texture). Returns the
// coarsest level if none fits.
uint32_t finest_level_that_fits(const ChunkSource& source, uint64_t max_side, uint64_t max_bytes);

}  // namespace vxr
