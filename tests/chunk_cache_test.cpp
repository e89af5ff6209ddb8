// CPU chunk cache: LRU under a byte budget, async loads by priority,
// cancellation, errors, counters, and concurrent use.
#include <doctest/doctest.h>

#include <atomic>
#include <condition_variable>
#include <filesystem>
#include <mutex>
#include <thread>

#include "volume/chunk_buffers.h"
#include "volume/chunk_cache.h"
#include "volume/container_reader.h"
#include "volume/memory_slab_source.h"
#include "volume/pyramid_builder.h"

using namespace vxr;

namespace {

// Chunks of 1000 bytes whose first byte is key.x; x == 99 fails. read() can
// be held at a gate to control the order of async loads.
class FakeSource final : public ChunkSource {
 public:
  FakeSource() {
    info_.dims = {1000, 1000, 1000};
    LevelInfo li;
    li.dims = info_.dims;
    li.chunk_counts = {100, 100, 100};
    levels_.push_back(li);
  }
  const VolumeInfo& info() const override { return info_; }
  const std::vector<LevelInfo>& levels() const override { return levels_; }
  uint32_t chunk_size() const override { return 10; }
  uint32_t apron() const override { return 0; }
  Result<ChunkStats> stats(const ChunkKey&) const override { return ChunkStats{}; }
  Result<std::shared_ptr<const Chunk>> read(const ChunkKey& key) const override {
    {
      std::unique_lock<std::mutex> lock(m_);
      cv_.wait(lock, [this] { return open_; });
      order_.push_back(key.x);
    }
    ++reads_;
    if (key.x == 99) return corrupt("chunk 99 is damaged");
    auto c = std::make_shared<Chunk>();
    c->key = key;
    c->edge = 10;
    c->data.assign(1000, static_cast<uint8_t>(key.x));
    return std::shared_ptr<const Chunk>(c);
  }
  void close_gate() {
    std::lock_guard<std::mutex> lock(m_);
    open_ = false;
  }
  void open_gate() {
    {
      std::lock_guard<std::mutex> lock(m_);
      open_ = true;
    }
    cv_.notify_all();
  }
  std::vector<uint32_t> order() const {
    std::lock_guard<std::mutex> lock(m_);
    return order_;
  }
  mutable std::atomic<int> reads_{0};

 private:
  VolumeInfo info_;
  std::vector<LevelInfo> levels_;
  mutable std::mutex m_;
  mutable std::condition_variable cv_;
  mutable std::vector<uint32_t> order_;
  bool open_ = true;
};

ChunkKey key(uint32_t x) { return ChunkKey{0, x, 0, 0, 0, 0}; }

// Budget for exactly `n` of FakeSource's chunks.
uint64_t budget_for(int n) { return uint64_t(n) * (1000 + sizeof(Chunk) + 64); }

}  // namespace

TEST_CASE("chunk cache: least recently used chunk is evicted first, counters exact") {
  auto src = std::make_shared<FakeSource>();
  ChunkCache cache(src, {.budget_bytes = budget_for(3), .loader_threads = 0});
  for (uint32_t x : {1, 2, 3}) REQUIRE(cache.get_or_load(key(x)).is_ok());
  CHECK(cache.get(key(1)) != nullptr);  // 1 is now the most recent; 2 the least
  REQUIRE(cache.get_or_load(key(4)).is_ok());
  CHECK(cache.contains(key(1)));
  CHECK_FALSE(cache.contains(key(2)));
  CHECK(cache.contains(key(3)));
  CHECK(cache.contains(key(4)));
  auto c = cache.counters();
  CHECK(c.loads == 4);
  CHECK(c.hits == 1);
  CHECK(c.misses == 4);
  CHECK(c.evictions == 1);
  CHECK(c.entries == 3);
  CHECK(c.bytes == budget_for(3));
  auto again = cache.get_or_load(key(3));
  REQUIRE(again.is_ok());
  CHECK((*again)->data[0] == 3);
  CHECK(src->reads_ == 4);  // a hit does not touch the source
  cache.set_budget_bytes(budget_for(1));
  CHECK(cache.counters().entries == 1);
  CHECK(cache.contains(key(3)));  // the most recent survives
}

TEST_CASE("chunk cache: a chunk handed out stays valid after eviction") {
  auto src = std::make_shared<FakeSource>();
  ChunkCache cache(src, {.budget_bytes = budget_for(1), .loader_threads = 0});
  auto a = cache.get_or_load(key(5));
  REQUIRE(a.is_ok());
  REQUIRE(cache.get_or_load(key(6)).is_ok());
  CHECK_FALSE(cache.contains(key(5)));
  CHECK((*a)->data[999] == 5);
}

TEST_CASE("chunk cache: async loads run in priority order and can be cancelled") {
  auto src = std::make_shared<FakeSource>();
  ChunkCache cache(src, {.budget_bytes = budget_for(100), .loader_threads = 1});
  src->close_gate();
  cache.request(key(0), 0.0);  // the loader takes this one and waits at the gate
  while (cache.queued() != 0) std::this_thread::yield();
  cache.request(key(1), 1.0);
  cache.request(key(2), 5.0);
  cache.request(key(3), 3.0);
  cache.request(key(4), 4.0);
  cache.request(key(5), 2.0);
  cache.request(key(1), 10.0);  // re-request raises the priority
  CHECK(cache.cancel(key(4)));
  CHECK_FALSE(cache.cancel(key(42)));
  CHECK(cache.queued() == 4);
  src->open_gate();
  cache.wait_idle();
  CHECK(src->order() == std::vector<uint32_t>{0, 1, 2, 3, 5});
  CHECK_FALSE(cache.contains(key(4)));
  CHECK(cache.get(key(2)) != nullptr);
  auto c = cache.counters();
  CHECK(c.loads == 5);
  CHECK(c.cancelled == 1);

  src->close_gate();
  cache.request(key(10), 1);
  while (cache.queued() != 0) std::this_thread::yield();
  for (uint32_t x = 11; x < 20; ++x) cache.request(key(x), 1);
  CHECK(cache.cancel_all() == 9);
  src->open_gate();
  cache.wait_idle();
  CHECK(cache.contains(key(10)));
  CHECK_FALSE(cache.contains(key(11)));
}

TEST_CASE("chunk cache: source errors come back, are counted, and nothing is cached") {
  auto src = std::make_shared<FakeSource>();
  ChunkCache cache(src, {.budget_bytes = budget_for(10), .loader_threads = 2});
  auto r = cache.get_or_load(key(99));
  CHECK(r.status().code() == ErrorCode::kCorrupt);
  std::atomic<int> callbacks{0};
  cache.set_on_loaded([&](const ChunkKey&, const Status&) { ++callbacks; });
  cache.request(key(99), 1);
  cache.request(key(7), 1);
  cache.wait_idle();
  auto errors = cache.take_errors();
  REQUIRE(errors.size() == 1);
  CHECK(errors[0].first == key(99));
  CHECK(errors[0].second.code() == ErrorCode::kCorrupt);
  CHECK(cache.take_errors().empty());
  CHECK_FALSE(cache.contains(key(99)));
  CHECK(cache.contains(key(7)));
  CHECK(cache.counters().load_errors == 2);
  CHECK(callbacks == 2);
}

TEST_CASE("chunk cache: concurrent readers and loaders keep the budget and return the right chunks") {
  auto src = std::make_shared<FakeSource>();
  ChunkCache cache(src, {.budget_bytes = budget_for(16), .loader_threads = 2});
  std::atomic<int> wrong{0};
  std::vector<std::thread> threads;
  for (int t = 0; t < 4; ++t)
    threads.emplace_back([&, t] {
      for (int i = 0; i < 2000; ++i) {
        const uint32_t x = static_cast<uint32_t>((i * 7 + t * 13) % 64);
        if (i % 3 == 0) cache.request(key(x), double(i % 5));
        auto c = (i % 2) ? cache.get(key(x)) : cache.get_or_load(key(x)).value();
        if (c && (c->data[0] != x || c->key != key(x))) ++wrong;
        if (cache.counters().bytes > budget_for(16)) ++wrong;
      }
    });
  for (auto& th : threads) th.join();
  cache.wait_idle();
  CHECK(wrong == 0);
  const auto c = cache.counters();
  CHECK(c.entries <= 16);
  CHECK(c.hits + c.misses == 8000);
  CHECK(c.evictions > 0);
}

TEST_CASE("chunk cache: over a real container it returns what the reader returns") {
  namespace fs = std::filesystem;
  const fs::path dir = fs::temp_directory_path() / "vxr_cache_container_test";
  fs::remove_all(dir);
  fs::create_directories(dir);
  DenseVolume v;
  v.dims = {40, 30, 20};
  v.data.resize(v.byte_size());
  for (size_t i = 0; i < v.data.size(); ++i) v.data[i] = static_cast<uint8_t>(i * 31 % 251);
  MemorySlabSource src(v);
  ImportOptions opt;
  opt.chunk_size = 16;
  const std::string path = (dir / "c.vxc").string();
  REQUIRE(build_container(src, path, opt).is_ok());
  auto reader = ContainerReader::open(path);
  REQUIRE(reader.is_ok());
  std::shared_ptr<const ChunkSource> shared(std::move(*reader));
  ChunkCache cache(shared, {.budget_bytes = 1 << 20, .loader_threads = 2});
  for (uint32_t z = 0; z < 2; ++z)
    for (uint32_t y = 0; y < 2; ++y)
      for (uint32_t x = 0; x < 3; ++x) cache.request({0, x, y, z, 0, 0}, x + y + z);
  cache.wait_idle();
  CHECK(cache.counters().entries == 12);
  for (uint32_t x = 0; x < 3; ++x) {
    auto cached = cache.get({0, x, 1, 1, 0, 0});
    REQUIRE(cached != nullptr);
    auto direct = shared->read({0, x, 1, 1, 0, 0});
    REQUIRE(direct.is_ok());
    CHECK(cached->data == (*direct)->data);
  }
}

TEST_CASE("chunk buffers: a dropped chunk's buffer is handed to the next chunk of its size, never while in use") {
  const size_t bytes = 123457;  // a size no other test's chunks have
  auto first = std::make_unique<vxr::Chunk>();
  first->data = vxr::take_chunk_buffer(bytes);
  REQUIRE(first->data.size() == bytes);
  first->data[0] = 42;
  const uint8_t* storage = first->data.data();
  std::shared_ptr<const vxr::Chunk> shared = vxr::share_recycling(std::move(first));
  auto copy = shared;
  shared.reset();
  // Still referenced: a new buffer must not be the one in use.
  auto other = vxr::take_chunk_buffer(bytes);
  CHECK(other.data() != storage);
  const uint64_t before = vxr::pooled_chunk_buffer_bytes();
  copy.reset();  // last reference: back to the pool
  CHECK(vxr::pooled_chunk_buffer_bytes() == before + bytes);
  auto again = vxr::take_chunk_buffer(bytes);
  CHECK(again.data() == storage);
  CHECK(again.size() == bytes);
  CHECK(vxr::pooled_chunk_buffer_bytes() == before);
  // Another size is never served from it.
  CHECK(vxr::take_chunk_buffer(bytes + 1).size() == bytes + 1);
}

TEST_CASE("chunk cache: get_or_load waits for a load in flight and takes over a queued one (each chunk read once)") {
  auto src = std::make_shared<FakeSource>();
  ChunkCache cache(src, {.budget_bytes = budget_for(10), .loader_threads = 1});
  src->close_gate();
  cache.request(key(1), 1);
  while (cache.queued() != 0) std::this_thread::yield();  // the loader took chunk 1 (held at the gate)
  cache.request(key(2), 0);                                // queued behind it
  Result<std::shared_ptr<const Chunk>> r1 = internal_error("not run"), r2 = internal_error("not run");
  std::thread waits([&] { r1 = cache.get_or_load(key(1)); });     // in flight: must wait for it
  std::thread takes_over([&] { r2 = cache.get_or_load(key(2)); });  // queued: loads it itself
  while (cache.queued() != 0) std::this_thread::yield();
  src->open_gate();
  waits.join();
  takes_over.join();
  cache.wait_idle();
  REQUIRE(r1.is_ok());
  REQUIRE(r2.is_ok());
  CHECK((*r1)->data[0] == 1);
  CHECK((*r2)->data[0] == 2);
  CHECK(src->reads_.load() == 2);
  CHECK(cache.counters().loads == 2);
}
