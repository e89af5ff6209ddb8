// Sanitizer builds (the `asan` preset, the fuzzers): the options every vxr
// process starts with, so a child process that a test spawns, or a test that
// ctest started without our environment, reports leaks the same way. Leaks
// inside third-party drivers and libraries are suppressed by name in
// tests/lsan.supp (each with its reason); a leak in vxr code fails.
// Include in exactly one file per executable (the one with main); a no-op in
// other builds.
#pragma once

#if defined(__SANITIZE_ADDRESS__)  // gcc
#define VXR_SANITIZER_DEFAULTS 1
#elif defined(__has_feature)  // clang
#if __has_feature(address_sanitizer)
#define VXR_SANITIZER_DEFAULTS 1
#endif
#endif

#ifdef VXR_SANITIZER_DEFAULTS
extern "C" const char* __asan_default_options() { return "detect_leaks=1:halt_on_error=1:detect_odr_violation=0"; }
extern "C" const char* __lsan_default_options() {
  return "suppressions=" VXR_SOURCE_DIR "/tests/lsan.supp:print_suppressions=0";
}
extern "C" const char* __ubsan_default_options() { return "halt_on_error=1:print_stacktrace=1"; }
#endif
