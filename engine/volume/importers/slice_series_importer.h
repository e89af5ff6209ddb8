// Slice series: one 2D picture per z slice (TIFF, PNG or JPEG), from a
// folder, a glob ("scan/img*.png"), or a list of files. Files are taken in
// natural order (img2 < img10). Every slice must have the first one's size,
// channels and type; the odd file is named otherwise.
#pragma once

#include <memory>
#include <string>
#include <string_view>
#include <vector>

#include "core/status.h"
#include "volume/slab_source.h"

namespace vxr {

// inputs: one folder, one glob pattern, or several files.
Result<std::unique_ptr<SlabSource>> open_slice_series_import(const std::vector<std::string>& inputs);

// Natural order: digit runs compare as numbers ("img2" < "img10"), letters case-insensitively.
bool natural_less(std::string_view a, std::string_view b);

// True for names ending in .tif, .tiff, .png, .jpg, .jpeg (any case).
bool is_slice_file_name(std::string_view name);

}  // namespace vxr
