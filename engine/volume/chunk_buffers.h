// Recycled chunk buffers: a decoded chunk's bytes go back to a small pool
// when the last reference to the chunk drops, and the next chunk of the same
// size reuses them. Playing a movie decodes tens of MB per volume; fresh
// buffers cost a page fault and a kernel page clear every 4 KiB plus a
// zero-fill (measured with `vxr bench movie`: about a third of the data
// path's CPU), recycled ones cost nothing.
//
//   auto chunk = std::make_unique<Chunk>();
//   chunk->data = take_chunk_buffer(bytes);   // contents unspecified: overwrite all
//   ... decode into chunk->data ...
//   return share_recycling(std::move(chunk));
#pragma once

#include <cstddef>
#include <cstdint>
#include <memory>
#include <vector>

#include "volume/chunk_source.h"

namespace vxr {

// A buffer of exactly `bytes` bytes, recycled when one of that size is
// pooled (its old contents remain: the caller overwrites every byte).
std::vector<uint8_t> take_chunk_buffer(size_t bytes);

// Shares `chunk`; when its last reference drops, its data buffer returns to
// the pool (kept while the pool holds under its cap, else freed).
std::shared_ptr<const Chunk> share_recycling(std::unique_ptr<Chunk> chunk);

// Bytes the pool holds now (tests).
uint64_t pooled_chunk_buffer_bytes();

}  // namespace vxr
