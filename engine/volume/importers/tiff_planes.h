// A SlabSource over 2D TIFF pages: each (z, channel, timepoint) plane of the
// volume is one page of one file. Plain TIFF stacks, ImageJ hyperstacks,
// OME-TIFF (one or many files) and TIFF slice folders all build a
// TiffPlaneLayout and share this reader.
//
// Thread safety: a pool of libtiff handles (one per concurrent reader per
// file), so read_region may be called from several threads at once.
#pragma once

#include <cstdint>
#include <memory>
#include <mutex>
#include <string>
#include <unordered_map>
#include <vector>

#include "volume/importers/tiff_reader.h"
#include "volume/slab_source.h"

namespace vxr {

struct TiffPlane {
  int32_t file = -1;  // index into TiffPlaneLayout::files; -1: no data for this plane (reads as zeros)
  uint32_t page = 0;  // index into TiffPlaneLayout::pages[file]
};

struct TiffPlaneLayout {
  VolumeInfo info;                                  // dims, dtype, channels, timepoints, voxel size
  std::vector<std::string> files;
  std::vector<std::vector<tiff::PageInfo>> pages;   // per file: the pages it holds
  uint32_t samples = 1;                             // channels stored inside one page (samples per pixel)
  std::vector<TiffPlane> planes;                    // index ((t * plane_channels + pc) * dims.z + z)

  uint32_t plane_channels() const { return info.channels / samples; }
  TiffPlane& plane(uint32_t z, uint32_t pc, uint32_t t) {
    return planes[(uint64_t(t) * plane_channels() + pc) * info.dims[2] + z];
  }
};

class TiffPlaneSource final : public SlabSource {
 public:
  // Checks that every plane's page has the volume's width, height, samples and
  // voxel size in bytes; errors name the file and page. `first` is an already
  // open handle on files[0] (kept in the pool) or null.
  static Result<std::unique_ptr<SlabSource>> create(TiffPlaneLayout layout, std::string format_name,
                                                    std::vector<std::string> warnings,
                                                    std::unique_ptr<tiff::TiffFile> first = nullptr);

  const VolumeInfo& info() const override { return layout_.info; }
  Status read_region(uint32_t channel, uint32_t timepoint, const Box3& box, std::span<uint8_t> dst) override;
  std::vector<std::string> warnings() const override { return warnings_; }
  std::string format_name() const override { return format_; }
  std::vector<std::string> files() const override { return layout_.files; }

 private:
  TiffPlaneSource() = default;
  Result<std::unique_ptr<tiff::TiffFile>> acquire(int32_t file);
  void release(int32_t file, std::unique_ptr<tiff::TiffFile> handle);

  TiffPlaneLayout layout_;
  std::string format_;
  std::vector<std::string> warnings_;
  std::mutex pool_mutex_;
  std::unordered_map<int32_t, std::vector<std::unique_ptr<tiff::TiffFile>>> pool_;
  size_t pooled_ = 0;
};

}  // namespace vxr
