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
//
// The chunk index (80 bytes a chunk: 2.4 GB for the 30 M chunks of a 16 TB
// volume) is never held whole: open() streams it once in 1 MiB blocks to
// check its checksum and every entry, and lookups then find an entry at its
// computed position (the index is complete and sorted) through a small cache
// of index blocks, at most kIndexCacheBytes, whatever the chunk count.
#pragma once

#include <memory>
#include <mutex>
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
  // Index entries, sorted by (level, timepoint, channel, z, y, x): entry_at(i)
  // for i < chunk_count(), or the entry of `key`. Read through the index
  // cache and checked again (the entry must name the chunk its position
  // implies and point inside the chunk area): kCorrupt otherwise.
  uint64_t chunk_count() const { return chunk_count_; }
  Result<vxc::IndexEntry> entry_at(uint64_t position) const;
  Result<vxc::IndexEntry> entry(const ChunkKey& key) const;
  // Chunks stored without payload (every voxel one value), counted at open().
  uint64_t uniform_chunks() const { return uniform_chunks_; }
  uint64_t file_bytes() const { return file_bytes_; }

  // Index cache: kIndexCacheBlocks blocks of kIndexBlockEntries entries,
  // direct-mapped by block number. resident_index_bytes() is what the reader
  // holds of the index now (<= kIndexCacheBytes).
  static constexpr uint64_t kIndexBlockEntries = 64;
  static constexpr uint64_t kIndexCacheBlocks = 128;
  static constexpr uint64_t kIndexCacheBytes = kIndexBlockEntries * kIndexCacheBlocks * sizeof(vxc::IndexEntry);
  uint64_t resident_index_bytes() const;
  // Voxel bytes of every level (interior voxels only: no apron, no edge
  // padding), all channels and timepoints, divided by the file size.
  double compression_ratio() const;

 private:
  ContainerReader() = default;
  // Checks one entry against its position: names the right chunk, sane codec
  // and size, record inside the chunk area. Empty string when fine.
  std::string check_entry(uint64_t position, const vxc::IndexEntry& e) const;

  struct CacheSlot {
    uint64_t block = ~uint64_t(0);
    std::vector<vxc::IndexEntry> entries;
  };

  std::string path_;
  ContainerFile file_;
  ContainerLayout layout_;
  uint64_t header_bytes_ = 0;
  uint64_t chunk_count_ = 0;
  uint64_t uniform_chunks_ = 0;
  uint64_t file_bytes_ = 0;
  uint64_t index_offset_ = 0;
  mutable std::mutex cache_mutex_;
  mutable std::vector<CacheSlot> cache_;
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
