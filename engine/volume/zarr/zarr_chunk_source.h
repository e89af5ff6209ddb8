// An OME-Zarr image read in place as a ChunkSource, so the out-of-core
// renderer draws it like a .vxc: each cubic chunk (with its apron, see
// chunk_source.h) is assembled from the zarr chunks it overlaps, read through
// the image's bounded cache of decoded zarr chunks.
//
// Levels: the image's datasets in order, as long as each halves the previous
// one or keeps it, per axis (factors from the scale transforms); the first
// dataset that does not (a 3x step, a finer level after a coarser one) ends
// the pyramid and is named in warnings(). Level dims are the arrays' shapes.
//
// Each level's decoded-chunk cache is raised to hold the zarr chunks of two
// payloads (up to kMaxLevelCache), so neighbouring reads reuse them even when
// chunks are thin slices.
//
// stats(): zarr stores no statistics, and reading chunks to find them would
// make stats() as slow as read(). A chunk not read yet reports the dtype's
// whole range (conservative: never skipped as empty); once read(), its exact
// payload range is remembered (up to kStatsMemo chunks) and reported.
#pragma once

#include <memory>
#include <mutex>
#include <string>
#include <unordered_map>
#include <vector>

#include "volume/chunk_source.h"
#include "volume/zarr/ome_zarr.h"

namespace vxr {

class ZarrChunkSource final : public ChunkSource {
 public:
  static constexpr size_t kStatsMemo = size_t(1) << 18;
  // Upper bound on the decoded-chunk cache create() asks each level's array
  // for: twice the zarr chunks one payload spans, at most this.
  static constexpr uint64_t kMaxLevelCache = uint64_t(1) << 30;

  // chunk_size 8..512, apron 1..4 (the brick renderer needs an apron).
  static Result<std::unique_ptr<ZarrChunkSource>> open(const std::string& path, uint32_t chunk_size = 64,
                                                       uint32_t apron = 1);
  static Result<std::unique_ptr<ZarrChunkSource>> create(std::shared_ptr<const zarr::OmeZarrImage> image,
                                                         uint32_t chunk_size = 64, uint32_t apron = 1);

  const VolumeInfo& info() const override { return image_->info(); }
  const std::vector<LevelInfo>& levels() const override { return levels_; }
  uint32_t chunk_size() const override { return chunk_size_; }
  uint32_t apron() const override { return apron_; }
  Result<ChunkStats> stats(const ChunkKey& key) const override;
  Result<std::shared_ptr<const Chunk>> read(const ChunkKey& key) const override;

  const zarr::OmeZarrImage& image() const { return *image_; }
  std::vector<std::string> warnings() const { return warnings_; }

 private:
  ZarrChunkSource() = default;
  Status check_key(const ChunkKey& key) const;

  std::shared_ptr<const zarr::OmeZarrImage> image_;
  std::vector<LevelInfo> levels_;
  uint32_t chunk_size_ = 64, apron_ = 1;
  std::vector<std::string> warnings_;
  mutable std::mutex stats_mutex_;
  mutable std::unordered_map<ChunkKey, ChunkStats, ChunkKeyHash> stats_;
};

}  // namespace vxr
