// What a .vxc container holds, independent of bytes: volume info, chunking,
// the resolution pyramid. The writer plans it, the header stores it.
#pragma once

#include <cstdint>
#include <span>
#include <string>
#include <vector>

#include "core/status.h"
#include "volume/chunk_source.h"
#include "volume/container_format.h"
#include "volume/volume_info.h"

namespace vxr {

struct ContainerLayout {
  VolumeInfo info;
  uint32_t chunk_size = 64;  // interior voxels per side
  uint32_t apron = 1;
  vxc::Downsample downsample = vxc::Downsample::kMean;
  vxc::Codec codec = vxc::Codec::kLz4;  // preferred codec for data chunks
  std::vector<LevelInfo> levels;

  uint32_t edge() const { return chunk_size + 2 * apron; }
  uint64_t payload_bytes() const { return uint64_t(edge()) * edge() * edge() * dtype_bytes(info.dtype); }
  // Chunks of one level for one channel and timepoint.
  uint64_t chunks_in_level(uint32_t level) const;
  // Every chunk of the container.
  uint64_t total_chunks() const;
  // True when `key` names a chunk inside the volume.
  bool contains(const ChunkKey& key) const;
  // The index lists every chunk once, sorted by (level, timepoint, channel,
  // z, y, x), so a chunk's entry sits at a computable position: these map a
  // key (which must be contains()) to its position and back (position <
  // total_chunks()).
  uint64_t index_position(const ChunkKey& key) const;
  ChunkKey key_at(uint64_t position) const;
};

// The resolution pyramid for a volume: level 0 is `dims`; each next level
// halves (rounding up) the axes that are finer than the coarsest by more than
// sqrt(2) (all axes once roughly isotropic), until one chunk covers the level.
std::vector<LevelInfo> plan_pyramid(const std::array<uint64_t, 3>& dims, const std::array<double, 3>& voxel_size,
                                    uint32_t chunk_size);

// A layout with its pyramid planned; checks the settings (chunk size 8..512,
// apron 0..4, dims and voxel sizes positive, unit at most 15 bytes).
Result<ContainerLayout> make_layout(const VolumeInfo& info, uint32_t chunk_size, uint32_t apron,
                                    vxc::Downsample downsample, vxc::Codec codec);

// Header bytes (FileHeader, level records, checksum) for `layout`.
std::vector<uint8_t> serialize_header(const ContainerLayout& layout);

// Parses and checks header bytes (magic, version, checksum, field sanity).
// `bytes` may be longer than the header; `header_bytes` receives its length.
// `what` names the file in messages.
Result<ContainerLayout> parse_header(std::span<const uint8_t> bytes, const std::string& what, uint64_t* header_bytes);

}  // namespace vxr
