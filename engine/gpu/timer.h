// GPU pass timing with timestamp queries, reported into the Chrome trace.
//
// Usage: timer.begin(cmd, "raycast"); ...dispatch...; timer.end(cmd);
// after the submission's fence: timer.collect(). Without a profile build and
// --trace, begin/end record nothing.
#pragma once

#include <string>
#include <vector>

#include "core/status.h"
#include "gpu/context.h"
#include "gpu/handle.h"

namespace vxr::gpu {

class GpuTimer {
 public:
  static constexpr uint32_t kMaxPasses = 64;
  static Result<GpuTimer> create(const Context& ctx);

  void begin(VkCommandBuffer cmd, const std::string& pass);
  void end(VkCommandBuffer cmd);
  // Reads finished queries, adds "gpu" trace events, returns each pass's ms.
  Result<std::vector<std::pair<std::string, double>>> collect();

 private:
  bool active() const;
  VkDevice device_ = VK_NULL_HANDLE;
  double period_ns_ = 0.0;
  Handle<VkQueryPool> pool_;
  std::vector<std::string> names_;
  double cpu_anchor_us_ = 0.0;  // CPU trace time when the first pass was recorded
};

}  // namespace vxr::gpu
