// Test entry: doctest, plus a final check that no Vulkan validation message
// slipped through a test that did not look for it.
#define DOCTEST_CONFIG_IMPLEMENT
#include <doctest/doctest.h>

#include <cstdio>
#include <cstdlib>

#include "gpu/context.h"
#include "core/sanitizer_defaults.h"

int main(int argc, char** argv) {
  // What ctest's environment would say; set here because doctest's test
  // discovery passes only the first entry of an ENVIRONMENT list.
  setenv("XDG_RUNTIME_DIR", "/tmp", 0);
  setenv("VXR_PIPELINE_CACHE", VXR_TEST_OUT_DIR "/../pipelines.bin", 0);
  doctest::Context context(argc, argv);
  int rc = context.run();
  if (context.shouldExit()) return rc;
  if (const uint64_t n = vxr::gpu::validation_message_count(); n > 0) {
    std::fprintf(stderr, "FAILED: %llu Vulkan validation message(s); first: %s\n",
                 static_cast<unsigned long long>(n), vxr::gpu::first_validation_message().c_str());
    return rc ? rc : 3;
  }
  return rc;
}
