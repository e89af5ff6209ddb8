// Test entry: doctest, plus a final check that no Vulkan validation message
// slipped through a test that did not look for it.
#define DOCTEST_CONFIG_IMPLEMENT
#include <doctest/doctest.h>

#include <cstdio>

#include "gpu/context.h"

int main(int argc, char** argv) {
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
