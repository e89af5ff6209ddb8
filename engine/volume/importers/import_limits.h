// The memory budget that readers size their own buffers against.
//
// `vxr import --memory` bounds the pyramid builder's voxel buffers; the
// readers underneath (a TIFF strip decoded whole, libtiff's own buffers) must
// not allocate past it either, whatever sizes a file's header claims. The
// budget is process-wide because one import runs per process and the readers
// sit several layers below the command (handles are reopened per thread).
#pragma once

#include <cstdint>

namespace vxr {

constexpr uint64_t kDefaultImportMemoryBytes = uint64_t(512) << 20;

// The budget set by the last set_import_memory_budget() (512 MiB until then).
uint64_t import_memory_budget();
void set_import_memory_budget(uint64_t bytes);

// Most bytes one decoded block (TIFF strip or tile) may take: a slice of the
// budget, since a pool of reader handles may each hold one.
inline uint64_t max_decoded_block_bytes() { return import_memory_budget() / 8; }

}  // namespace vxr
