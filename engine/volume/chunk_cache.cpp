#include "volume/chunk_cache.h"

namespace vxr {

ChunkCache::ChunkCache(std::shared_ptr<const ChunkSource> source, ChunkCacheOptions options)
    : source_(std::move(source)), options_(options) {
  for (uint32_t i = 0; i < options_.loader_threads; ++i) threads_.emplace_back([this] { loader_main(); });
}

ChunkCache::~ChunkCache() {
  {
    std::lock_guard<std::mutex> lock(mutex_);
    stopping_ = true;
    queue_.clear();
    queued_.clear();
  }
  work_cv_.notify_all();
  for (auto& t : threads_) t.join();
}

std::shared_ptr<const Chunk> ChunkCache::get(const ChunkKey& key) {
  std::lock_guard<std::mutex> lock(mutex_);
  auto it = entries_.find(key);
  if (it == entries_.end()) {
    ++counters_.misses;
    return nullptr;
  }
  ++counters_.hits;
  lru_.splice(lru_.begin(), lru_, it->second.lru);
  return it->second.chunk;
}

Result<std::shared_ptr<const Chunk>> ChunkCache::get_or_load(const ChunkKey& key) {
  {
    std::unique_lock<std::mutex> lock(mutex_);
    bool counted = false;
    for (;;) {
      if (auto it = entries_.find(key); it != entries_.end()) {
        if (!counted) ++counters_.hits;
        lru_.splice(lru_.begin(), lru_, it->second.lru);
        return it->second.chunk;
      }
      if (!counted) ++counters_.misses;
      counted = true;
      if (!loading_.count(key)) break;
      // Another thread is decoding it: wait for that rather than decode it twice.
      loaded_cv_.wait(lock);
    }
    // This thread loads it now: a queued request for it would load it again.
    if (auto q = queued_.find(key); q != queued_.end()) {
      queue_.erase(q->second);
      queued_.erase(q);
    }
    loading_.insert(key);
  }
  auto r = source_->read(key);
  std::lock_guard<std::mutex> lock(mutex_);
  ++counters_.loads;
  loading_.erase(key);
  loaded_cv_.notify_all();
  if (queue_.empty() && loading_.empty()) idle_cv_.notify_all();
  if (!r) {
    ++counters_.load_errors;
    return r.status();
  }
  insert_locked(key, *r);
  return *r;
}

void ChunkCache::request(const ChunkKey& key, double priority) {
  {
    std::lock_guard<std::mutex> lock(mutex_);
    if (stopping_ || entries_.count(key) || loading_.count(key)) return;
    auto q = queued_.find(key);
    if (q != queued_.end()) {
      if (q->second.first == -priority) return;
      queue_.erase(q->second);
      queued_.erase(q);
    }
    const QueueKey qk{-priority, sequence_++};
    queue_.emplace(qk, key);
    queued_.emplace(key, qk);
  }
  work_cv_.notify_one();
}

bool ChunkCache::cancel(const ChunkKey& key) {
  std::lock_guard<std::mutex> lock(mutex_);
  auto q = queued_.find(key);
  if (q == queued_.end()) return false;
  queue_.erase(q->second);
  queued_.erase(q);
  ++counters_.cancelled;
  if (queue_.empty() && loading_.empty()) idle_cv_.notify_all();
  return true;
}

size_t ChunkCache::cancel_all() {
  std::lock_guard<std::mutex> lock(mutex_);
  const size_t n = queue_.size();
  queue_.clear();
  queued_.clear();
  counters_.cancelled += n;
  if (loading_.empty()) idle_cv_.notify_all();
  return n;
}

void ChunkCache::wait_idle() {
  std::unique_lock<std::mutex> lock(mutex_);
  if (threads_.empty()) return;  // nothing would ever drain the queue
  idle_cv_.wait(lock, [this] { return queue_.empty() && loading_.empty(); });
}

std::vector<std::pair<ChunkKey, Status>> ChunkCache::take_errors() {
  std::lock_guard<std::mutex> lock(mutex_);
  return std::exchange(errors_, {});
}

void ChunkCache::set_on_loaded(std::function<void(const ChunkKey&, const Status&)> callback) {
  std::lock_guard<std::mutex> lock(mutex_);
  on_loaded_ = std::move(callback);
}

bool ChunkCache::contains(const ChunkKey& key) const {
  std::lock_guard<std::mutex> lock(mutex_);
  return entries_.count(key) != 0;
}

size_t ChunkCache::queued() const {
  std::lock_guard<std::mutex> lock(mutex_);
  return queue_.size();
}

ChunkCacheCounters ChunkCache::counters() const {
  std::lock_guard<std::mutex> lock(mutex_);
  ChunkCacheCounters c = counters_;
  c.entries = entries_.size();
  return c;
}

void ChunkCache::set_budget_bytes(uint64_t bytes) {
  std::lock_guard<std::mutex> lock(mutex_);
  options_.budget_bytes = bytes;
  evict_locked();
}

void ChunkCache::clear() {
  std::lock_guard<std::mutex> lock(mutex_);
  entries_.clear();
  lru_.clear();
  counters_.bytes = 0;
}

void ChunkCache::insert_locked(const ChunkKey& key, std::shared_ptr<const Chunk> chunk) {
  auto it = entries_.find(key);
  if (it != entries_.end()) {  // loaded twice (sync and async raced): keep one
    lru_.splice(lru_.begin(), lru_, it->second.lru);
    return;
  }
  lru_.push_front(key);
  Entry e;
  e.bytes = chunk_bytes(*chunk);
  e.chunk = std::move(chunk);
  e.lru = lru_.begin();
  counters_.bytes += e.bytes;
  entries_.emplace(key, std::move(e));
  evict_locked();
}

void ChunkCache::evict_locked() {
  // Oldest first; the newest entry stays even if it alone exceeds the budget.
  while (counters_.bytes > options_.budget_bytes && lru_.size() > 1) {
    const ChunkKey victim = lru_.back();
    lru_.pop_back();
    auto it = entries_.find(victim);
    counters_.bytes -= it->second.bytes;
    entries_.erase(it);
    ++counters_.evictions;
  }
}

void ChunkCache::loader_main() {
  for (;;) {
    ChunkKey key;
    {
      std::unique_lock<std::mutex> lock(mutex_);
      work_cv_.wait(lock, [this] { return stopping_ || !queue_.empty(); });
      if (stopping_) return;
      auto first = queue_.begin();
      key = first->second;
      queued_.erase(key);
      queue_.erase(first);
      if (entries_.count(key) || loading_.count(key)) {  // loaded meanwhile by get_or_load
        if (queue_.empty() && loading_.empty()) idle_cv_.notify_all();
        continue;
      }
      loading_.insert(key);
    }
    auto r = source_->read(key);
    std::function<void(const ChunkKey&, const Status&)> callback;
    {
      std::lock_guard<std::mutex> lock(mutex_);
      ++counters_.loads;
      if (r) {
        insert_locked(key, *r);
      } else {
        ++counters_.load_errors;
        errors_.emplace_back(key, r.status());
      }
      callback = on_loaded_;
    }
    if (callback) callback(key, r.status());
    {
      std::lock_guard<std::mutex> lock(mutex_);
      loading_.erase(key);
      loaded_cv_.notify_all();
      if (queue_.empty() && loading_.empty()) idle_cv_.notify_all();
    }
  }
}

}  // namespace vxr
