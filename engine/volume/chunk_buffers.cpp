#include "volume/chunk_buffers.h"

#include <mutex>
#include <unordered_map>

namespace vxr {
namespace {

// At most this many bytes wait in the pool: a few volumes' worth of churn
// between eviction and the next decode, not a second cache.
constexpr uint64_t kPoolCapBytes = 64ull << 20;

struct Pool {
  std::mutex mutex;
  std::unordered_map<size_t, std::vector<std::vector<uint8_t>>> by_size;
  uint64_t bytes = 0;
};

Pool& pool() {
  static Pool* p = new Pool;  // never destroyed: chunks may drop during static destruction
  return *p;
}

void give_back(std::vector<uint8_t>&& buffer) {
  const size_t n = buffer.size();
  if (n == 0 || n != buffer.capacity()) return;  // only exact-size buffers are handed out again
  Pool& p = pool();
  std::lock_guard<std::mutex> lock(p.mutex);
  if (p.bytes + n > kPoolCapBytes) return;
  p.by_size[n].push_back(std::move(buffer));
  p.bytes += n;
}

}  // namespace

std::vector<uint8_t> take_chunk_buffer(size_t bytes) {
  if (bytes > 0) {
    Pool& p = pool();
    std::lock_guard<std::mutex> lock(p.mutex);
    auto it = p.by_size.find(bytes);
    if (it != p.by_size.end() && !it->second.empty()) {
      std::vector<uint8_t> b = std::move(it->second.back());
      it->second.pop_back();
      p.bytes -= bytes;
      return b;
    }
  }
  std::vector<uint8_t> fresh;
  fresh.reserve(bytes);  // exact capacity, so it can be pooled later
  fresh.resize(bytes);
  return fresh;
}

std::shared_ptr<const Chunk> share_recycling(std::unique_ptr<Chunk> chunk) {
  return std::shared_ptr<const Chunk>(chunk.release(), [](const Chunk* c) {
    give_back(std::move(const_cast<Chunk*>(c)->data));  // the chunk is being destroyed: nobody reads it
    delete c;
  });
}

uint64_t pooled_chunk_buffer_bytes() {
  Pool& p = pool();
  std::lock_guard<std::mutex> lock(p.mutex);
  return p.bytes;
}

}  // namespace vxr
