// A ChunkSource over volumes already in memory (an imported TIFF, raw file,
// Imaris file, the bundled sample): the small-volume case of the out-of-core
// renderer. The constructor builds the pyramid in memory (2x box means, as
// shrink_by_two: an axis of one voxel stays one voxel) until one chunk covers
// the top level, and the min/max of every chunk for empty-space skipping;
// read() cuts a chunk with its apron (edge voxels repeated) on demand.
#pragma once

#include <memory>
#include <vector>

#include "core/status.h"
#include "volume/chunk_source.h"
#include "volume/dense_volume.h"

namespace vxr {

class DenseChunkSource final : public ChunkSource {
 public:
  // `channels`: one volume per channel (timepoint 0), same dims and dtype.
  static Result<std::shared_ptr<DenseChunkSource>> create(std::vector<DenseVolume> channels,
                                                          uint32_t chunk_size = 64, uint32_t apron = 2);
  // A time series: timepoints[t][c], every volume the same dims and dtype.
  static Result<std::shared_ptr<DenseChunkSource>> create_series(std::vector<std::vector<DenseVolume>> timepoints,
                                                                 uint32_t chunk_size = 64, uint32_t apron = 2);

  // The file's channel names and colours (empty, or one per channel), shown in info().
  Status set_channel_display(std::vector<ChannelDisplay> display);

  const VolumeInfo& info() const override { return info_; }
  const std::vector<LevelInfo>& levels() const override { return levels_; }
  uint32_t chunk_size() const override { return cs_; }
  uint32_t apron() const override { return apron_; }
  Result<ChunkStats> stats(const ChunkKey& key) const override;
  Result<std::shared_ptr<const Chunk>> read(const ChunkKey& key) const override;

 private:
  DenseChunkSource() = default;
  Status check_key(const ChunkKey& key) const;
  size_t chunk_index(const ChunkKey& key) const;
  void cut(const ChunkKey& key, Chunk& out) const;

  VolumeInfo info_;
  std::vector<LevelInfo> levels_;
  uint32_t cs_ = 64, apron_ = 2;
  std::vector<std::vector<std::vector<DenseVolume>>> data_;  // [timepoint][level][channel]
  std::vector<size_t> first_chunk_;  // per level: index of its chunk 0 in stats_ (per timepoint and channel)
  std::vector<std::vector<std::vector<ChunkStats>>> stats_;  // [timepoint][channel][chunk]
};

}  // namespace vxr
