// TIFF, BigTIFF, ImageJ and OME-TIFF files through the importer, as
// `vxr import x.tif` opens them, then a read of a few corner boxes.
#include "fuzz_util.h"
#include "volume/importers/import_source.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  const std::string path = vxr::fuzz::write_temp("in.tif", data, size);
  auto source = vxr::open_import_source({path});
  if (source) vxr::fuzz::read_some(**source);
  return 0;
}
