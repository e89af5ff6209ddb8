// Timepoint playback for 3D movies: a frame clock and a prefetcher.
//
//   PlaybackClock clock(source.info().timepoints, {.fps = 10});
//   TimepointPrefetcher prefetch(cache, source, /*level=*/0);
//   clock.play(now);
//   each frame: prefetch.update(clock.upcoming(8));
//               auto f = clock.tick(now, [&](uint32_t t) { return prefetch.ready(t); });
//               if (f.is_new) upload_and_draw(f.timepoint);
//
// The clock never shows a timepoint out of order within a loop and never
// shows one twice in a row while playing: when the data or the renderer is
// late it skips (drops) timepoints, and when the due one is not loaded yet it
// keeps the current picture and waits (a stall) rather than going back.
// Time is passed in (seconds, any origin), so tests drive it with a fake clock.
#pragma once

#include <cstdint>
#include <functional>
#include <vector>

#include "volume/chunk_cache.h"
#include "volume/chunk_source.h"

namespace vxr {

struct PlaybackOptions {
  double fps = 10.0;   // timepoints per second at speed 1
  double speed = 1.0;  // multiplier; > 0
  bool loop = false;   // after the last timepoint: back to 0 (else pause at the last)
};

struct PlaybackFrame {
  uint32_t timepoint = 0;  // what to show now
  bool is_new = false;     // differs from the previous tick's timepoint (upload + draw)
  uint32_t dropped = 0;    // timepoints skipped since the previous shown one
  bool wrapped = false;    // this frame started a new loop
};

struct PlaybackCounters {
  uint64_t shown = 0;    // new timepoints shown
  uint64_t dropped = 0;  // timepoints skipped because they were due before they could be shown
  uint64_t stalls = 0;   // ticks that waited for a due timepoint's data
  uint64_t loops = 0;    // wraps back to timepoint 0
};

class PlaybackClock {
 public:
  explicit PlaybackClock(uint32_t timepoint_count, PlaybackOptions options = {});

  void play(double now);
  void pause(double now);
  void toggle(double now) { playing_ ? pause(now) : play(now); }
  // Pauses and moves by `delta` timepoints (wraps when looping, else clamps).
  void step(int delta, double now);
  // Keeps the current timepoint; later timepoints come at the new rate.
  void set_speed(double speed, double now);
  void set_loop(bool loop) { options_.loop = loop; }

  // Decides what to show at `now`. `ready(t)` says whether timepoint t's data
  // is loaded; a due timepoint that is not ready makes the clock wait on the
  // current one (and re-anchor, so the wait does not cause drops later).
  PlaybackFrame tick(double now, const std::function<bool(uint32_t)>& ready);

  // The next `count` timepoints playback will need, in order (for prefetch).
  std::vector<uint32_t> upcoming(uint32_t count) const;

  uint32_t timepoint() const { return current_; }
  uint32_t timepoint_count() const { return count_; }
  bool playing() const { return playing_; }
  double speed() const { return options_.speed; }
  bool loop() const { return options_.loop; }
  double fps() const { return options_.fps; }
  const PlaybackCounters& counters() const { return counters_; }

 private:
  // Timepoints advanced since the anchor at `now` (unwrapped).
  uint64_t due_steps(double now) const;
  void anchor(double now);

  uint32_t count_;
  PlaybackOptions options_;
  bool playing_ = false;
  uint32_t current_ = 0;
  bool current_shown_ = false;  // the first tick shows timepoint 0 as new
  bool waiting_ = false;        // anchor_position_ is due but not loaded: hold it until it is
  uint64_t anchor_position_ = 0;  // unwrapped position (loops * count + timepoint) at anchor_time_
  uint64_t shown_position_ = 0;   // unwrapped position of current_
  double anchor_time_ = 0.0;
  PlaybackCounters counters_;
};

// Keeps the chunks of the next timepoints queued in a ChunkCache (nearest
// first), within a share of the cache budget, and cancels requests for
// timepoints no longer upcoming. Decoding runs on the cache's loader threads.
class TimepointPrefetcher {
 public:
  // `budget_share`: at most this fraction of the cache budget is prefetched ahead.
  TimepointPrefetcher(ChunkCache& cache, const ChunkSource& source, uint32_t level, uint32_t channel = 0,
                      double budget_share = 0.5);

  // Queues the chunks of `timepoints` (in order of need); returns how many
  // timepoints fit in the budget and were queued.
  uint32_t update(const std::vector<uint32_t>& timepoints);
  // Every chunk of timepoint t at the level is in the cache.
  bool ready(uint32_t timepoint) const;
  // The chunks of timepoint t (for upload), loading missing ones on this thread.
  Result<std::vector<std::shared_ptr<const Chunk>>> chunks(uint32_t timepoint);

  std::vector<ChunkKey> keys(uint32_t timepoint) const;
  uint64_t bytes_per_timepoint() const { return bytes_per_timepoint_; }

 private:
  ChunkCache& cache_;
  const ChunkSource& source_;
  uint32_t level_, channel_;
  double budget_share_;
  uint64_t bytes_per_timepoint_ = 0;
  std::vector<uint32_t> queued_timepoints_;
};

}  // namespace vxr
