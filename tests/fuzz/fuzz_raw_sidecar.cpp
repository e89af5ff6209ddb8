// A raw volume with its JSON sidecar. Input: the sidecar text, a NUL byte,
// then the raw file's bytes (written as vol.raw beside the sidecar; the
// seeds' sidecars name it, a mutated one may name anything).
#include <cstring>

#include "fuzz_util.h"
#include "volume/importers/import_source.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  const auto* nul = static_cast<const uint8_t*>(std::memchr(data, 0, size));
  const size_t json_size = nul ? size_t(nul - data) : size;
  const size_t raw_offset = nul ? json_size + 1 : size;
  vxr::fuzz::write_temp("vol.raw", data + raw_offset, size - raw_offset);
  const std::string path = vxr::fuzz::write_temp("in.json", data, json_size);
  auto source = vxr::open_import_source({path});
  if (source) vxr::fuzz::read_some(**source);
  return 0;
}
