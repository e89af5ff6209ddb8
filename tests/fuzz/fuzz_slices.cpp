// One slice of a slice series (PNG, JPEG or TIFF, named by its signature as
// a user's folder would name it) through the slice-series importer.
#include <cstring>

#include "fuzz_util.h"
#include "volume/importers/slice_series_importer.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  const char* name = "slice.tif";
  if (size >= 4 && std::memcmp(data, "\x89PNG", 4) == 0) name = "slice.png";
  else if (size >= 2 && data[0] == 0xff && data[1] == 0xd8) name = "slice.jpg";
  const std::string path = vxr::fuzz::write_temp(name, data, size);
  auto source = vxr::open_slice_series_import({path});
  if (source) vxr::fuzz::read_some(**source);
  return 0;
}
