#include "bench/pareto.h"

#include <algorithm>
#include <limits>

namespace vxr::bench {

std::vector<size_t> pareto_front(const std::vector<TradeoffPoint>& p) {
  std::vector<size_t> front;
  for (size_t i = 0; i < p.size(); ++i) {
    bool dominated = false;
    for (size_t j = 0; j < p.size() && !dominated; ++j) {
      if (j == i) continue;
      const bool no_worse = p[j].time <= p[i].time && p[j].error <= p[i].error;
      const bool better = p[j].time < p[i].time || p[j].error < p[i].error;
      dominated = no_worse && better;
    }
    if (!dominated) front.push_back(i);
  }
  std::sort(front.begin(), front.end(), [&](size_t a, size_t b) { return p[a].time < p[b].time; });
  return front;
}

double front_time_at_error(const std::vector<TradeoffPoint>& p, const std::vector<size_t>& front, double error) {
  double best = std::numeric_limits<double>::infinity();
  for (size_t i : front)
    if (p[i].error <= error) best = std::min(best, p[i].time);
  return best;
}

}  // namespace vxr::bench
