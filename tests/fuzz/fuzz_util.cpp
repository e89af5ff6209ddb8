#include "fuzz_util.h"

#include <unistd.h>

#include <algorithm>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <vector>

#include "volume/dtype.h"

namespace vxr::fuzz {

std::string write_temp(const std::string& name, const uint8_t* data, size_t size) {
  static const std::string dir = [] {
    const char* tmp = std::getenv("TMPDIR");
    std::string d = std::string(tmp && *tmp ? tmp : "/tmp") + "/vxr_fuzz_" + std::to_string(::getpid());
    std::filesystem::create_directories(d);
    return d;
  }();
  // Registered once `dir` is fully built, so it runs before `dir` is destroyed.
  static const bool cleanup = std::atexit([] {
    std::error_code ec;
    std::filesystem::remove_all(dir, ec);
  }) == 0;
  (void)cleanup;
  const std::string path = dir + "/" + name;
  FILE* f = std::fopen(path.c_str(), "wb");
  if (!f) {
    std::perror(path.c_str());
    std::abort();  // the harness itself is broken: say so loudly
  }
  if (size) std::fwrite(data, 1, size, f);
  std::fclose(f);
  return path;
}

void read_some(SlabSource& source) {
  const VolumeInfo& info = source.info();
  const uint32_t bpv = dtype_bytes(info.dtype);
  for (uint32_t t = 0; t < std::min<uint32_t>(info.timepoints, 2); ++t)
    for (uint32_t c = 0; c < std::min<uint32_t>(info.channels, 4); ++c)
      for (int far = 0; far < 2; ++far) {
        Box3 box;
        for (int a = 0; a < 3; ++a) {
          box.size[a] = std::min<uint64_t>(info.dims[a], a == 2 ? 2 : 64);
          box.origin[a] = far ? info.dims[a] - box.size[a] : 0;
        }
        std::vector<uint8_t> buf(box.voxels() * bpv);
        (void)source.read_region(c, t, box, buf);
      }
}

}  // namespace vxr::fuzz
