#include "volume/playback.h"

#include <algorithm>
#include <cmath>
#include <unordered_set>

#include "volume/dtype.h"

namespace vxr {

PlaybackClock::PlaybackClock(uint32_t timepoint_count, PlaybackOptions options)
    : count_(std::max<uint32_t>(1, timepoint_count)), options_(options) {
  if (!(options_.fps > 0.0)) options_.fps = 10.0;
  if (!(options_.speed > 0.0)) options_.speed = 1.0;
}

void PlaybackClock::anchor(double now) {
  waiting_ = false;
  anchor_position_ = shown_position_;
  anchor_time_ = now;
}

uint64_t PlaybackClock::due_steps(double now) const {
  const double steps = (now - anchor_time_) * options_.fps * options_.speed;
  // The epsilon keeps exact frame times (k / fps) from rounding down.
  return steps <= 0.0 ? 0 : static_cast<uint64_t>(std::floor(steps + 1e-6));
}

void PlaybackClock::play(double now) {
  // Playing again after the end of a non-looping movie starts over.
  if (!options_.loop && current_ + 1 >= count_ && count_ > 1) {
    current_ = 0;
    shown_position_ = 0;
    current_shown_ = false;
  }
  playing_ = true;
  anchor(now);
}

void PlaybackClock::pause(double) { playing_ = false; }

void PlaybackClock::step(int delta, double now) {
  playing_ = false;
  int64_t t = int64_t(current_) + delta;
  if (options_.loop)
    t = ((t % int64_t(count_)) + int64_t(count_)) % int64_t(count_);
  else
    t = std::clamp<int64_t>(t, 0, int64_t(count_) - 1);
  if (uint32_t(t) != current_) current_shown_ = false;
  current_ = uint32_t(t);
  shown_position_ = current_;
  anchor(now);
}

void PlaybackClock::set_speed(double speed, double now) {
  if (!(speed > 0.0)) return;
  if (playing_) {
    // Keep the progress made at the old speed, then continue at the new one.
    if (!waiting_) anchor_position_ += due_steps(now);
    anchor_time_ = now;
  }
  options_.speed = speed;
}

PlaybackFrame PlaybackClock::tick(double now, const std::function<bool(uint32_t)>& ready) {
  PlaybackFrame frame;
  frame.timepoint = current_;
  if (!current_shown_) {
    // First frame (or after a step): the current timepoint, once loaded.
    if (!ready(current_)) {
      ++counters_.stalls;
      if (playing_) anchor(now);
      return frame;
    }
    current_shown_ = true;
    frame.is_new = true;
    ++counters_.shown;
    if (playing_) anchor(now);
    if (!options_.loop && current_ + 1 >= count_) playing_ = false;  // the last (or only) timepoint
    return frame;
  }
  if (!playing_) return frame;

  uint64_t target = waiting_ ? anchor_position_ : anchor_position_ + due_steps(now);
  if (!options_.loop) target = std::min<uint64_t>(target, count_ - 1);
  if (target <= shown_position_) return frame;

  const uint32_t t = uint32_t(target % count_);
  if (!ready(t)) {
    // Wait on the current picture; the due timepoint stays due (no drops
    // from waiting, no going back).
    ++counters_.stalls;
    waiting_ = true;
    anchor_position_ = target;
    return frame;
  }
  if (waiting_) {
    // The awaited timepoint arrived: real time restarts from it.
    waiting_ = false;
    anchor_position_ = target;
    anchor_time_ = now;
  }
  frame.dropped = uint32_t(target - shown_position_ - 1);
  const uint64_t loops = target / count_ - shown_position_ / count_;
  frame.wrapped = loops > 0;
  counters_.loops += loops;
  counters_.dropped += frame.dropped;
  ++counters_.shown;
  shown_position_ = target;
  current_ = t;
  frame.timepoint = t;
  frame.is_new = true;
  if (!options_.loop && current_ + 1 >= count_) playing_ = false;
  return frame;
}

std::vector<uint32_t> PlaybackClock::upcoming(uint32_t count) const {
  std::vector<uint32_t> out;
  if (!current_shown_) out.push_back(current_);
  // Waiting on a due timepoint: it comes first (the ones before it will be
  // dropped); listing from the shown one would never load it.
  uint64_t position = waiting_ && anchor_position_ > shown_position_ ? anchor_position_ - 1 : shown_position_;
  while (out.size() < count) {
    ++position;
    if (!options_.loop && position >= count_) break;
    const uint32_t t = uint32_t(position % count_);
    if (t == current_ && current_shown_) break;  // all timepoints listed once
    out.push_back(t);
  }
  return out;
}

TimepointPrefetcher::TimepointPrefetcher(ChunkCache& cache, const ChunkSource& source, uint32_t level,
                                         uint32_t channel, double budget_share)
    : cache_(cache), source_(source), level_(level), channel_(channel), budget_share_(budget_share) {
  const uint64_t edge = source_.chunk_size() + 2ull * source_.apron();
  const uint64_t chunk = edge * edge * edge * dtype_bytes(source_.info().dtype) + sizeof(Chunk) + 64;
  bytes_per_timepoint_ = chunk * keys(0).size();
}

std::vector<ChunkKey> TimepointPrefetcher::keys(uint32_t timepoint) const {
  std::vector<ChunkKey> out;
  if (level_ >= source_.levels().size()) return out;
  const auto& counts = source_.levels()[level_].chunk_counts;
  out.reserve(size_t(counts[0]) * counts[1] * counts[2]);
  for (uint32_t z = 0; z < counts[2]; ++z)
    for (uint32_t y = 0; y < counts[1]; ++y)
      for (uint32_t x = 0; x < counts[0]; ++x) out.push_back(ChunkKey{level_, x, y, z, channel_, timepoint});
  return out;
}

uint32_t TimepointPrefetcher::update(const std::vector<uint32_t>& timepoints) {
  const double budget = double(cache_.budget_bytes()) * budget_share_;
  size_t fit = bytes_per_timepoint_ ? size_t(budget / double(bytes_per_timepoint_)) : timepoints.size();
  fit = std::clamp<size_t>(fit, 1, timepoints.size());
  std::vector<uint32_t> wanted(timepoints.begin(), timepoints.begin() + std::min(fit, timepoints.size()));

  // Cancel what is no longer upcoming (e.g. after a step or a drop).
  const std::unordered_set<uint32_t> keep(wanted.begin(), wanted.end());
  for (uint32_t t : queued_timepoints_)
    if (!keep.count(t))
      for (const ChunkKey& k : keys(t)) cache_.cancel(k);

  for (size_t i = 0; i < wanted.size(); ++i)
    for (const ChunkKey& k : keys(wanted[i])) cache_.request(k, -double(i));  // nearest first
  queued_timepoints_ = std::move(wanted);
  return uint32_t(queued_timepoints_.size());
}

bool TimepointPrefetcher::ready(uint32_t timepoint) const {
  for (const ChunkKey& k : keys(timepoint))
    if (!cache_.contains(k)) return false;
  return true;
}

Result<std::vector<std::shared_ptr<const Chunk>>> TimepointPrefetcher::chunks(uint32_t timepoint) {
  std::vector<std::shared_ptr<const Chunk>> out;
  for (const ChunkKey& k : keys(timepoint)) {
    auto c = cache_.get_or_load(k);
    if (!c) return c.status();
    out.push_back(std::move(c.value()));
  }
  return out;
}

}  // namespace vxr
