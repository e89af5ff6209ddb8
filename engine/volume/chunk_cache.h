// CPU chunk cache: decoded chunks of a ChunkSource under a byte budget, with
// asynchronous loader threads.
//
//   ChunkCache cache(source, {.budget_bytes = 2ull << 30, .loader_threads = 2});
//   cache.request(key, priority);          // frame N: ask for what the view needs
//   if (auto c = cache.get(key)) draw(c);  // later: use it if it has arrived
//   else draw(parent);                      //        (the caller falls back)
//
// Eviction is least-recently-used (a list ordered by last use: O(1) per hit,
// insert and evict, better than the paper's timestamp min-heap's O(log n)).
// A chunk handed out as shared_ptr stays valid after eviction; only the
// cache's reference is dropped. Every method is thread-safe.
#pragma once

#include <condition_variable>
#include <cstdint>
#include <functional>
#include <list>
#include <map>
#include <memory>
#include <mutex>
#include <thread>
#include <unordered_map>
#include <unordered_set>
#include <vector>

#include "core/status.h"
#include "volume/chunk_source.h"

namespace vxr {

struct ChunkCacheOptions {
  uint64_t budget_bytes = uint64_t(1) << 30;  // decoded bytes kept (chunk data + bookkeeping)
  uint32_t loader_threads = 2;                // 0: no async loading (request() only queues)
};

struct ChunkCacheCounters {
  uint64_t hits = 0;         // get()/get_or_load() found the chunk
  uint64_t misses = 0;       // ... did not
  uint64_t loads = 0;        // chunks read from the source (sync and async)
  uint64_t load_errors = 0;  // reads that failed (errors kept for take_errors())
  uint64_t evictions = 0;    // chunks dropped to stay within the budget
  uint64_t cancelled = 0;    // queued requests removed before loading
  uint64_t bytes = 0;        // bytes held now
  uint64_t entries = 0;      // chunks held now
};

class ChunkCache {
 public:
  // `source` must outlive the cache (or be shared: the cache keeps the shared_ptr).
  ChunkCache(std::shared_ptr<const ChunkSource> source, ChunkCacheOptions options = {});
  // Cancels queued requests and joins the loader threads (loads in flight finish).
  ~ChunkCache();
  ChunkCache(const ChunkCache&) = delete;
  ChunkCache& operator=(const ChunkCache&) = delete;

  // The cached chunk, marked most recently used; nullptr when not cached.
  // Counts a hit or a miss. Never blocks on I/O.
  std::shared_ptr<const Chunk> get(const ChunkKey& key);

  // The cached chunk, or reads it now on the calling thread and caches it
  // (waiting instead when a loader thread is reading it already; a queued
  // request for it is taken over). Errors of the source come back unchanged
  // (nothing is cached then).
  Result<std::shared_ptr<const Chunk>> get_or_load(const ChunkKey& key);

  // Queues an asynchronous load; higher priority loads first (ties: first
  // come, first served). Already cached or loading: no-op. Already queued:
  // the priority is updated.
  void request(const ChunkKey& key, double priority);

  // Removes a queued request; false if it was not queued (absent, loading or
  // done). A load already running is not interrupted; its result is cached.
  bool cancel(const ChunkKey& key);
  // Removes every queued request; returns how many.
  size_t cancel_all();

  // Blocks until no request is queued or loading.
  void wait_idle();

  // Failed async loads since the last call (key and the source's Status).
  std::vector<std::pair<ChunkKey, Status>> take_errors();

  // Called on a loader thread after each async load (ok or not). Keep it short.
  void set_on_loaded(std::function<void(const ChunkKey&, const Status&)> callback);

  bool contains(const ChunkKey& key) const;
  size_t queued() const;
  ChunkCacheCounters counters() const;
  uint64_t budget_bytes() const { return options_.budget_bytes; }
  // Changes the budget; evicts at once if needed.
  void set_budget_bytes(uint64_t bytes);
  // Drops every cached chunk (not the queue).
  void clear();

 private:
  struct Entry {
    std::shared_ptr<const Chunk> chunk;
    std::list<ChunkKey>::iterator lru;  // position in lru_ (front = most recent)
    uint64_t bytes = 0;
  };
  using QueueKey = std::pair<double, uint64_t>;  // (-priority, sequence): begin() is the next load

  void loader_main();
  void insert_locked(const ChunkKey& key, std::shared_ptr<const Chunk> chunk);
  void evict_locked();
  static uint64_t chunk_bytes(const Chunk& c) { return c.data.size() + sizeof(Chunk) + 64; }

  std::shared_ptr<const ChunkSource> source_;
  ChunkCacheOptions options_;
  mutable std::mutex mutex_;
  std::condition_variable work_cv_, idle_cv_;
  std::condition_variable loaded_cv_;  // a load finished (get_or_load waits on one in flight)
  std::unordered_map<ChunkKey, Entry, ChunkKeyHash> entries_;
  std::list<ChunkKey> lru_;
  std::map<QueueKey, ChunkKey> queue_;
  std::unordered_map<ChunkKey, QueueKey, ChunkKeyHash> queued_;
  std::unordered_set<ChunkKey, ChunkKeyHash> loading_;
  std::vector<std::pair<ChunkKey, Status>> errors_;
  std::function<void(const ChunkKey&, const Status&)> on_loaded_;
  ChunkCacheCounters counters_;
  uint64_t sequence_ = 0;
  bool stopping_ = false;
  std::vector<std::thread> threads_;
};

// A ChunkSource that reads through a cache: read() is the cache's
// get_or_load, so whatever the loader threads decoded ahead is used as is.
// For code that takes a ChunkSource (the brick pool) and should share the
// cache's work (playback).
class CachedChunkSource final : public ChunkSource {
 public:
  CachedChunkSource(const ChunkSource& inner, ChunkCache& cache) : inner_(inner), cache_(cache) {}
  const VolumeInfo& info() const override { return inner_.info(); }
  const std::vector<LevelInfo>& levels() const override { return inner_.levels(); }
  uint32_t chunk_size() const override { return inner_.chunk_size(); }
  uint32_t apron() const override { return inner_.apron(); }
  Result<ChunkStats> stats(const ChunkKey& key) const override { return inner_.stats(key); }
  Result<std::shared_ptr<const Chunk>> read(const ChunkKey& key) const override { return cache_.get_or_load(key); }

 private:
  const ChunkSource& inner_;
  ChunkCache& cache_;
};

}  // namespace vxr
