// A SlabSource over voxels already in memory: the bundled sample, tests,
// benchmarks. Holds one buffer per (timepoint, channel).
#pragma once

#include <memory>
#include <vector>

#include "volume/dense_volume.h"
#include "volume/slab_source.h"

namespace vxr {

class MemorySlabSource final : public SlabSource {
 public:
  // volumes[t * info.channels + c] holds info.dims voxels of info.dtype, x fastest.
  MemorySlabSource(VolumeInfo info, std::vector<std::vector<uint8_t>> volumes);
  // One channel, one timepoint.
  explicit MemorySlabSource(const DenseVolume& volume);

  const VolumeInfo& info() const override { return info_; }
  Status read_region(uint32_t channel, uint32_t timepoint, const Box3& box, std::span<uint8_t> dst) override;
  std::string format_name() const override { return "in-memory volume"; }

 private:
  VolumeInfo info_;
  std::vector<std::vector<uint8_t>> volumes_;
};

}  // namespace vxr
