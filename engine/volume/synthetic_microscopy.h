// A SlabSource that synthesises a u16 volume looking like noisy fluorescence
// microscopy, of any size, without holding it: every voxel is a pure function
// of its coordinates and the seed, so any region can be read in any order and
// reads agree with each other.
//
// Content: a camera offset (100), a smooth dim autofluorescence background,
// Gaussian blobs ("cells", radius 2..24 voxels, about one per 400k voxels)
// and shot noise (Poisson-like: standard deviation sqrt(signal)). Every
// voxel is noisy, so no chunk is uniform and compression sees what it would
// see on real camera data. Used by `vxr bench import --synthetic` and by
// `vxr bench synth-tiff` (tools/measure-import-memory.sh).
#pragma once

#include <array>
#include <cstdint>
#include <memory>
#include <vector>

#include "volume/slab_source.h"

namespace vxr {

class SyntheticMicroscopySource final : public SlabSource {
 public:
  explicit SyntheticMicroscopySource(const std::array<uint64_t, 3>& dims, uint64_t seed = 1234);

  const VolumeInfo& info() const override { return info_; }
  Status read_region(uint32_t channel, uint32_t timepoint, const Box3& box, std::span<uint8_t> dst) override;
  std::string format_name() const override { return "synthetic u16 microscopy"; }

  size_t blob_count() const { return blobs_.size(); }

 private:
  struct Blob {
    double x, y, z, r, amp;
  };
  VolumeInfo info_;
  uint64_t seed_;
  std::vector<Blob> blobs_;  // sorted by z - 3r
};

}  // namespace vxr
