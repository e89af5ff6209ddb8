// A .vxc container: open (header, footer, index checks), read the first and
// last chunk, and run the verifier over it, as `vxr verify` does.
#include "fuzz_util.h"
#include "volume/container_reader.h"
#include "volume/container_verify.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  const std::string path = vxr::fuzz::write_temp("in.vxc", data, size);
  if (auto reader = vxr::ContainerReader::open(path)) {
    const vxr::ContainerReader& r = **reader;
    // A header may legitimately ask for 514^3 x 4-byte chunks (543 MB each);
    // filling those only times memset, so chunk reads are left to small layouts.
    if (r.layout().payload_bytes() <= (uint64_t(8) << 20) && r.chunk_count() > 0) {
      for (uint64_t i : {uint64_t(0), r.chunk_count() - 1}) {
        if (auto e = r.entry_at(i)) {
          (void)r.stats(vxr::key_of(*e));
          (void)r.read(vxr::key_of(*e));
        }
      }
    }
  }
  (void)vxr::verify_container(path);
  return 0;
}
