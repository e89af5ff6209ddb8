#include "gpu/timer.h"

#include "core/trace.h"
#include "gpu/vk_check.h"

namespace vxr::gpu {

Result<GpuTimer> GpuTimer::create(const Context& ctx) {
  GpuTimer t;
  t.device_ = ctx.device();
  t.period_ns_ = ctx.timestamp_period_ns();
  if (t.period_ns_ <= 0.0) return t;  // no timestamps on this queue: a timer that records nothing
  VkQueryPoolCreateInfo ci{VK_STRUCTURE_TYPE_QUERY_POOL_CREATE_INFO};
  ci.queryType = VK_QUERY_TYPE_TIMESTAMP;
  ci.queryCount = 2 * kMaxPasses;
  VkQueryPool pool = VK_NULL_HANDLE;
  VXR_VK_TRY(vkCreateQueryPool(ctx.device(), &ci, nullptr, &pool));
  t.pool_ = Handle<VkQueryPool>(ctx.device(), pool);
  vkResetQueryPool(ctx.device(), pool, 0, 2 * kMaxPasses);
  return t;
}

bool GpuTimer::active() const { return pool_ && trace::enabled(); }

void GpuTimer::begin(VkCommandBuffer cmd, const std::string& pass) {
  if (!active() || names_.size() >= kMaxPasses) return;
  if (names_.empty()) cpu_anchor_us_ = trace::now_us();
  const uint32_t q = static_cast<uint32_t>(names_.size()) * 2;
  names_.push_back(pass);
  vkCmdWriteTimestamp2(cmd, VK_PIPELINE_STAGE_2_TOP_OF_PIPE_BIT, pool_, q);
}

void GpuTimer::end(VkCommandBuffer cmd) {
  if (!active() || names_.empty()) return;
  const uint32_t q = static_cast<uint32_t>(names_.size()) * 2 - 1;
  vkCmdWriteTimestamp2(cmd, VK_PIPELINE_STAGE_2_BOTTOM_OF_PIPE_BIT, pool_, q);
}

Result<std::vector<std::pair<std::string, double>>> GpuTimer::collect() {
  std::vector<std::pair<std::string, double>> out;
  if (!active() || names_.empty()) return out;
  std::vector<uint64_t> ticks(names_.size() * 2);
  VXR_VK_TRY(vkGetQueryPoolResults(device_, pool_, 0, static_cast<uint32_t>(ticks.size()),
                                   ticks.size() * sizeof(uint64_t), ticks.data(), sizeof(uint64_t),
                                   VK_QUERY_RESULT_64_BIT | VK_QUERY_RESULT_WAIT_BIT));
  const uint64_t origin = ticks[0];
  for (size_t i = 0; i < names_.size(); ++i) {
    const double start_us = static_cast<double>(ticks[2 * i] - origin) * period_ns_ * 1e-3;
    const double dur_us = static_cast<double>(ticks[2 * i + 1] - ticks[2 * i]) * period_ns_ * 1e-3;
    trace::add_complete(names_[i], "gpu", cpu_anchor_us_ + start_us, dur_us);
    out.emplace_back(names_[i], dur_us * 1e-3);
  }
  vkResetQueryPool(device_, pool_, 0, 2 * kMaxPasses);
  names_.clear();
  return out;
}

}  // namespace vxr::gpu
