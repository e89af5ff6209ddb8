// Shared GPU context for tests, with validation forced on. Each test that
// uses it checks the validation counter at its end (GpuTestScope).
#pragma once

#include <doctest/doctest.h>

#include <memory>

#include "gpu/context.h"

namespace vxr::test {

inline gpu::Context& gpu_context() {
  static std::unique_ptr<gpu::Context> ctx = [] {
    gpu::ContextOptions o = gpu::ContextOptions::from_env();
    o.validation = true;
    auto r = gpu::Context::create(o);
    if (!r) {
      FAIL("cannot create the Vulkan context: " << r.status().to_string());
    }
    return std::move(r).value();
  }();
  return *ctx;
}

// Fails the current test if validation reported anything during it.
struct GpuTestScope {
  GpuTestScope() { gpu::reset_validation_messages(); }
  ~GpuTestScope() {
    CHECK_MESSAGE(gpu::validation_message_count() == 0,
                  "Vulkan validation: " << gpu::first_validation_message());
  }
};

}  // namespace vxr::test
