// Plain TIFF files (single images, multi-page stacks, RGB and palette
// pictures) and ImageJ hyperstacks. A file whose description is OME-XML is
// handed to the OME-TIFF importer.
//
// Pages: the first series is the leading run of pages with page 0's size,
// channel count and type (reduced-resolution pages are skipped); later pages
// that differ are left out with a warning. A 2D or RGB picture is a one-slice
// volume with one channel per sample; a palette picture becomes RGB.
#pragma once

#include <memory>
#include <string>

#include "core/status.h"
#include "volume/importers/tiff_reader.h"
#include "volume/slab_source.h"

namespace vxr {

Result<std::unique_ptr<SlabSource>> open_tiff_import(const std::string& path);

// X/Y pixel size and unit a TIFF page itself claims: ImageJ calibration when
// `imagej_unit` is set, else ResolutionUnit=centimetre; "px" and 1 otherwise.
struct PageCalibration {
  double x = 1, y = 1;
  std::string unit = "px";
};
PageCalibration page_calibration(const tiff::PageInfo& page, const std::string& imagej_unit);

}  // namespace vxr
