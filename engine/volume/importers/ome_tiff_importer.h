// OME-TIFF: OME-XML (in the first IFD's ImageDescription, or a
// .companion.ome file) gives the sizes, DimensionOrder, pixel type and
// physical sizes; TiffData elements map each (z, c, t) plane to an IFD of a
// file, so one dataset may span many files (UUID FileName). A file whose XML
// is only a BinaryOnly stub leads to the file holding the full metadata.
// Image 0 (the first series) is imported; pyramids in SubIFDs are ignored.
#pragma once

#include <memory>
#include <string>
#include <string_view>

#include "core/status.h"
#include "volume/slab_source.h"

namespace vxr {

// path: an .ome.tif(f) file (any file of a multi-file set) or a .companion.ome.
Result<std::unique_ptr<SlabSource>> open_ome_tiff_import(const std::string& path);

// True when a TIFF ImageDescription holds OME-XML.
bool looks_like_ome_xml(std::string_view description);

}  // namespace vxr
