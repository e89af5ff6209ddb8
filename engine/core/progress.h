// Progress reporting for long work (import, conversion, benchmarks, export).
//
// Work code calls Progress::advance(); the reporter draws a one-line bar with
// percent, throughput and ETA on stderr (only when stderr is a terminal, or
// VXR_PROGRESS=1), at most every 200 ms, so it costs nothing in tight loops.
#pragma once

#include <atomic>
#include <chrono>
#include <cstdint>
#include <mutex>
#include <string>

namespace vxr {

class Progress {
 public:
  // total: units of work (bytes for I/O-bound work, so MB/s is meaningful).
  // unit_is_bytes: show MB/s rather than items/s.
  Progress(std::string label, uint64_t total, bool unit_is_bytes = true);
  ~Progress();

  // Thread-safe; adds done units and redraws if due.
  void advance(uint64_t units);
  // Sets absolute progress (for resumed work that starts part-way).
  void set_done(uint64_t units);
  // Draws the final line with total time.
  void finish();

  uint64_t done() const { return done_.load(); }
  uint64_t total() const { return total_; }

  // The line that would be drawn now, e.g. "import  42.0%  120.3 MB/s  ETA 0:12".
  std::string status_line() const;

 private:
  void maybe_draw(bool force);

  std::string label_;
  uint64_t total_;
  bool bytes_;
  bool visible_;
  bool finished_ = false;
  std::atomic<uint64_t> done_{0};
  uint64_t start_done_ = 0;
  std::chrono::steady_clock::time_point start_;
  std::chrono::steady_clock::time_point last_draw_;
  mutable std::mutex mutex_;
};

}  // namespace vxr
