#include "core/progress.h"

#include <unistd.h>

#include <cstdio>
#include <cstdlib>

namespace vxr {
namespace {

std::string format_duration(double seconds) {
  if (seconds < 0 || seconds > 1e7) return "--:--";
  const long s = static_cast<long>(seconds + 0.5);
  char buf[32];
  if (s >= 3600)
    std::snprintf(buf, sizeof buf, "%ld:%02ld:%02ld", s / 3600, (s / 60) % 60, s % 60);
  else
    std::snprintf(buf, sizeof buf, "%ld:%02ld", s / 60, s % 60);
  return buf;
}

bool progress_visible() {
  if (const char* v = std::getenv("VXR_PROGRESS")) return v[0] == '1';
  return isatty(STDERR_FILENO);
}

}  // namespace

Progress::Progress(std::string label, uint64_t total, bool unit_is_bytes)
    : label_(std::move(label)),
      total_(total),
      bytes_(unit_is_bytes),
      visible_(progress_visible()),
      start_(std::chrono::steady_clock::now()),
      last_draw_(start_) {}

Progress::~Progress() { finish(); }

void Progress::advance(uint64_t units) {
  done_ += units;
  maybe_draw(false);
}

void Progress::set_done(uint64_t units) {
  std::lock_guard<std::mutex> lock(mutex_);
  done_ = units;
  start_done_ = units;
  start_ = std::chrono::steady_clock::now();
}

std::string Progress::status_line() const {
  const uint64_t done = done_.load();
  const double elapsed =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - start_).count();
  const double pct = total_ ? 100.0 * static_cast<double>(done) / static_cast<double>(total_) : 100.0;
  const double rate = elapsed > 0 ? static_cast<double>(done - start_done_) / elapsed : 0.0;
  const double eta = rate > 0 ? static_cast<double>(total_ - std::min(done, total_)) / rate : -1.0;
  char buf[160];
  if (bytes_)
    std::snprintf(buf, sizeof buf, "%s %5.1f%%  %7.1f MB/s  elapsed %s  ETA %s", label_.c_str(), pct,
                  rate / 1e6, format_duration(elapsed).c_str(), format_duration(eta).c_str());
  else
    std::snprintf(buf, sizeof buf, "%s %5.1f%%  %7.1f /s  elapsed %s  ETA %s", label_.c_str(), pct, rate,
                  format_duration(elapsed).c_str(), format_duration(eta).c_str());
  return buf;
}

void Progress::maybe_draw(bool force) {
  if (!visible_) return;
  std::lock_guard<std::mutex> lock(mutex_);
  if (finished_) return;
  const auto now = std::chrono::steady_clock::now();
  if (!force && now - last_draw_ < std::chrono::milliseconds(200)) return;
  last_draw_ = now;
  const std::string line = status_line();
  std::fprintf(stderr, "\r%-78s", line.c_str());
  std::fflush(stderr);
}

void Progress::finish() {
  if (finished_) return;
  maybe_draw(true);
  std::lock_guard<std::mutex> lock(mutex_);
  if (visible_) std::fprintf(stderr, "\n");
  finished_ = true;
}

}  // namespace vxr
