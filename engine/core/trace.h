// Chrome trace-event recorder (opens in Perfetto and chrome://tracing).
//
// CPU scopes (VXR_TRACE_SCOPE) and GPU pass timings (added by gpu/GpuTimer) go
// into one process-wide recorder. Scopes compile to nothing unless the build
// defines VXR_PROFILE (cmake --preset profile), so release builds pay nothing.
#pragma once

#include <chrono>
#include <cstdint>
#include <string>

#include "core/status.h"

namespace vxr::trace {

// True once start() was called in a profile build.
bool enabled();
// Starts recording; events are kept in memory until write().
void start();
// Writes every recorded event as {"traceEvents":[...]} JSON.
Status write(const std::string& path);

// Microseconds on the trace clock (steady, process start = 0).
double now_us();

// Adds a complete ("X") event. track: "cpu" events go to the calling thread's
// lane; "gpu" events go to a lane of their own.
void add_complete(const std::string& name, const char* track, double start_us, double dur_us);

class Scope {
 public:
  explicit Scope(const char* name) : name_(name), start_(enabled() ? now_us() : -1.0) {}
  ~Scope() {
    if (start_ >= 0.0) add_complete(name_, "cpu", start_, now_us() - start_);
  }
  Scope(const Scope&) = delete;
  Scope& operator=(const Scope&) = delete;

 private:
  const char* name_;
  double start_;
};

}  // namespace vxr::trace

#ifdef VXR_PROFILE
#define VXR_TRACE_SCOPE(name) ::vxr::trace::Scope VXR_CONCAT(vxr_trace_scope_, __LINE__)(name)
#else
#define VXR_TRACE_SCOPE(name) \
  do {                        \
  } while (0)
#endif
