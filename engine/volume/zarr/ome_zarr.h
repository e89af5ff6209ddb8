// An OME-Zarr image (OME-NGFF 0.4 on Zarr v2, 0.5 on Zarr v3): the
// multiscales metadata and reads of any level.
//
//   auto img = OmeZarrImage::open("cells.ome.zarr");
//   img->info();                                   // level-0 dims (x,y,z), dtype, channels, voxel size + unit
//   img->read_region(level, c, t, box, bytes);     // x fastest, like SlabSource
//
// Metadata read: the first entry of `multiscales` (0.4: `.zattrs`; 0.5:
// `zarr.json` attributes.ome), its `axes` (2..5 of t, c, z, y, x; names or
// 0.3-style strings; missing axes are taken by rank as [t][c][z]yx), units
// (UDUNITS names, see importers/units.h), and the scale/translation
// coordinateTransformations of each dataset and of the multiscale. A
// bioformats2raw folder opens its first image ("0"); a bare Zarr array opens
// as a one-level image with axes by rank.
//
// 2-D images are a volume one voxel deep whose z voxel size is the x one.
// Spatial axes are taken by position (the last is x), as the spec orders them.
#pragma once

#include <array>
#include <memory>
#include <span>
#include <string>
#include <vector>

#include "core/status.h"
#include "volume/volume_info.h"
#include "volume/zarr/zarr_array.h"

namespace vxr::zarr {

struct OmeLevel {
  std::string path;  // the dataset's path in the store
  std::unique_ptr<ZarrArray> array;
  std::array<uint64_t, 3> dims{1, 1, 1};  // x, y, z voxels
  std::array<double, 3> scale{1, 1, 1};   // physical size of one voxel, x, y, z (in the image's unit)
  std::array<double, 3> translation{0, 0, 0};
  std::array<double, 3> factor{1, 1, 1};  // level-0 voxels per voxel of this level (scale ratio, or shape ratio)
};

// True when `path` is a folder holding Zarr metadata (.zgroup, .zattrs,
// .zarray or zarr.json), or one of those files.
bool looks_like_zarr(const std::string& path);

class OmeZarrImage {
 public:
  // cache_bytes: decoded-chunk budget shared out between the levels.
  static Result<std::unique_ptr<OmeZarrImage>> open(const std::string& path, uint64_t cache_bytes = uint64_t(256)
                                                                                                    << 20);

  const VolumeInfo& info() const { return info_; }
  const std::vector<OmeLevel>& levels() const { return levels_; }
  const std::string& path() const { return root_; }
  const std::string& version() const { return version_; }  // "0.4", "0.5", ... or "" for a bare array
  int zarr_format() const { return levels_.front().array->meta().zarr_format; }
  std::vector<std::string> warnings() const { return warnings_; }
  // The metadata files the image was opened from (groups' and arrays'), for
  // "outputs never touch inputs" checks. Chunk files are not listed: a large
  // image has millions.
  std::vector<std::string> metadata_files() const;

  // Reads `box` (within the level's dims) of one channel and timepoint, x
  // fastest, native byte order. Thread-safe.
  Status read_region(uint32_t level, uint32_t channel, uint32_t timepoint, const Box3& box,
                     std::span<uint8_t> dst) const;

 private:
  OmeZarrImage() = default;
  static Result<std::unique_ptr<OmeZarrImage>> open_checked(const std::string& path, uint64_t cache_bytes);

  std::string root_;
  std::string version_;
  VolumeInfo info_;
  std::vector<OmeLevel> levels_;
  std::vector<std::string> warnings_;
  // Array axis of each role, -1 when the image has none.
  int t_axis_ = -1, c_axis_ = -1;
  std::array<int, 3> space_axis_{-1, -1, -1};  // x, y, z
};

}  // namespace vxr::zarr
