// Read side of a multi-resolution volume: fixed-size chunks with an apron.
//
// The container reader, OME-Zarr and procedural sources implement this; the
// CPU cache, LOD traversal and GPU brick pool above it see only this.
//
// Layout: level 0 is full resolution; level l+1 halves level l along the axes
// the pyramid downsampled (anisotropic data halves only its fine axes until
// roughly isotropic). Each level is cut into chunks of chunk_size() interior
// voxels per side. A chunk's payload is (chunk_size + 2*apron)^3 voxels: the
// interior plus `apron` voxels copied from its neighbours on every side (at
// the volume border, edge voxels are repeated), so GPU trilinear filtering is
// seamless across chunk borders. Voxels past the level's dims inside an edge
// chunk repeat the last valid voxel.
#pragma once

#include <array>
#include <cstdint>
#include <memory>
#include <vector>

#include "core/status.h"
#include "volume/volume_info.h"

namespace vxr {

struct ChunkKey {
  uint32_t level = 0;
  uint32_t x = 0, y = 0, z = 0;  // chunk coordinates within the level
  uint32_t channel = 0;
  uint32_t timepoint = 0;
  bool operator==(const ChunkKey&) const = default;
};

struct ChunkKeyHash {
  size_t operator()(const ChunkKey& k) const {
    uint64_t h = k.level;
    for (uint64_t v : {uint64_t(k.x), uint64_t(k.y), uint64_t(k.z), uint64_t(k.channel), uint64_t(k.timepoint)})
      h = (h ^ v) * 0x100000001b3ull + 0x9e3779b97f4a7c15ull;
    return static_cast<size_t>(h ^ (h >> 29));
  }
};

struct LevelInfo {
  std::array<uint64_t, 3> dims{0, 0, 0};          // voxels at this level
  std::array<uint32_t, 3> chunk_counts{0, 0, 0};  // ceil(dims / chunk_size)
  std::array<uint32_t, 3> downsample{1, 1, 1};    // level-0 voxels per voxel of this level, per axis
};

// Min/max of a chunk's whole payload (interior and apron, so a superset of the
// interior's range) in data units; known without decoding. min == max means
// every payload voxel has that value.
struct ChunkStats {
  double min = 0.0;
  double max = 0.0;
  bool uniform() const { return min == max; }
};

struct Chunk {
  ChunkKey key;
  uint32_t edge = 0;  // voxels per side including the apron: chunk_size + 2*apron
  DType dtype = DType::kU8;
  ChunkStats stats;
  std::vector<uint8_t> data;  // edge^3 voxels, x fastest, native byte order
};

class ChunkSource {
 public:
  virtual ~ChunkSource() = default;

  virtual const VolumeInfo& info() const = 0;
  virtual const std::vector<LevelInfo>& levels() const = 0;
  virtual uint32_t chunk_size() const = 0;  // interior voxels per side
  virtual uint32_t apron() const = 0;

  // Cheap: from the index, no payload decoding. kNotFound for keys outside the volume.
  virtual Result<ChunkStats> stats(const ChunkKey& key) const = 0;
  // Decodes one chunk. Errors (corruption, I/O) come back as Status, never as
  // wrong data. Thread-safe.
  virtual Result<std::shared_ptr<const Chunk>> read(const ChunkKey& key) const = 0;
};

}  // namespace vxr
