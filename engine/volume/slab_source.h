// What importers produce: random access to blocks of level-0 voxels of a
// source dataset (TIFF stack, OME-TIFF, Imaris, slice folder, ...).
//
// The pyramid builder pulls blocks through this interface slab by slab, so an
// import never holds more than its memory budget, whatever the dataset size.
#pragma once

#include <cstdint>
#include <span>
#include <string>
#include <vector>

#include "core/status.h"
#include "volume/volume_info.h"

namespace vxr {

class SlabSource {
 public:
  virtual ~SlabSource() = default;

  virtual const VolumeInfo& info() const = 0;

  // Reads `box` of one channel and timepoint into `dst`: x fastest, then y,
  // then z, tightly packed, info().dtype in native byte order. `dst` must hold
  // exactly box.voxels() * dtype_bytes(info().dtype) bytes. Must be safe to
  // call from several threads at once (implementations may serialise).
  virtual Status read_region(uint32_t channel, uint32_t timepoint, const Box3& box, std::span<uint8_t> dst) = 0;

  // Things the user should know about the import ("pages differ in size:
  // imported the first series (128x72), 1 page skipped").
  virtual std::vector<std::string> warnings() const { return {}; }

  // Every file the source reads (outputs must not be one of them).
  virtual std::vector<std::string> files() const { return {}; }

  // A short description of the source for messages ("ImageJ TIFF stack", ...).
  virtual std::string format_name() const = 0;
};

}  // namespace vxr
