#include "volume/importers/import_limits.h"

#include <atomic>

namespace vxr {
namespace {
std::atomic<uint64_t> g_budget{kDefaultImportMemoryBytes};
}

uint64_t import_memory_budget() { return g_budget.load(std::memory_order_relaxed); }
void set_import_memory_budget(uint64_t bytes) { g_budget.store(bytes, std::memory_order_relaxed); }

}  // namespace vxr
