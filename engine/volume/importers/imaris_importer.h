// Imaris .ims (HDF5, Imaris5FileFormat): resolution level 0 of
// DataSet/ResolutionLevel 0/TimePoint t/Channel c/Data, (Z, Y, X) order,
// cropped from the chunk-padded datasets to ImageSizeX/Y/Z; voxel size from
// DataSetInfo/Image ExtMin/ExtMax. Attributes are char arrays, one element
// per character. All HDF5 calls are serialised (the Debian build is not
// thread-safe).
#pragma once

#include <memory>
#include <string>

#include "core/status.h"
#include "volume/slab_source.h"

namespace vxr {

Result<std::unique_ptr<SlabSource>> open_imaris_import(const std::string& path);

// True when `path` starts with the HDF5 signature.
bool has_hdf5_magic(const std::string& path);

}  // namespace vxr
