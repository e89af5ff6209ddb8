// Time-versus-error Pareto fronts for `vxr bench accuracy`.
#pragma once

#include <cstddef>
#include <vector>

namespace vxr::bench {

struct TradeoffPoint {
  double time = 0.0;   // lower is better
  double error = 0.0;  // lower is better
};

// Indices of the points no other point beats in both time and error (a point
// that is equal in one and better in the other beats it), sorted by time.
std::vector<size_t> pareto_front(const std::vector<TradeoffPoint>& points);

// The front's time at `error`: the least time of any front point whose error
// is at most `error` (the staircase through the front), or +inf if none is
// that accurate.
double front_time_at_error(const std::vector<TradeoffPoint>& points, const std::vector<size_t>& front, double error);

}  // namespace vxr::bench
