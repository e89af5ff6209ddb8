// Writes a .vxc container append-only, so a killed conversion can resume.
//
// Crash safety (docs/container-format.md, "Writing and resuming"): data goes
// to `<path>.partial`; every chunk is one self-checking record appended at the
// end; finish() appends the index and footer, fsyncs and renames the file to
// `<path>`. A reader only accepts a file with a valid footer, so a killed run
// never leaves a file that `vxr info` accepts. Resuming rescans the partial
// file's records, keeps every one that passes its checksums and cuts the torn
// tail; the scan is the journal.
#pragma once

#include <memory>
#include <mutex>
#include <string>
#include <vector>

#include "core/status.h"
#include "volume/chunk_codec.h"
#include "volume/chunk_source.h"
#include "volume/container_io.h"
#include "volume/container_layout.h"

namespace vxr {

class ContainerWriter {
 public:
  // Starts `path`.partial with the header for `layout`.
  // resume=false: fails (kInvalidArgument) if a partial file exists, so an
  //   interrupted conversion is never thrown away by accident.
  // resume=true: keeps a partial file made with the same layout (kInvalidArgument
  //   if the layout differs), or starts fresh when there is none (or its header
  //   was torn before completion).
  // An unwritable location gives kIo naming the path.
  static Result<std::unique_ptr<ContainerWriter>> create(const std::string& path, const ContainerLayout& layout,
                                                         bool resume);
  ~ContainerWriter();

  const ContainerLayout& layout() const { return layout_; }
  // Thread-safe. True when `key` is already in the file (written or resumed).
  bool has(const ChunkKey& key) const;
  // Thread-safe. Appends one chunk record; a key may be appended only once.
  Status append(const EncodedChunk& chunk);
  // Thread-safe. Reads back a chunk already in the file (checksummed, decoded).
  Result<std::shared_ptr<const Chunk>> read(const ChunkKey& key) const;
  // Stats of a chunk already in the file.
  Result<ChunkStats> stats(const ChunkKey& key) const;

  uint64_t chunk_count() const;
  uint64_t resumed_chunks() const { return resumed_; }
  uint64_t bytes_written() const;

  // Requires every chunk of the layout. Appends index and footer, fsyncs,
  // renames to the final path. After finish() the writer accepts nothing.
  Status finish();

 private:
  ContainerWriter() = default;
  Status write_tracked(const void* data, uint64_t bytes, uint64_t offset);
  bool present(const ChunkKey& key) const {
    return layout_.contains(key) && entries_[layout_.index_position(key)].offset != 0;
  }

  std::string path_, partial_;
  ContainerLayout layout_;
  ContainerFile file_;
  mutable std::mutex mutex_;
  // Every chunk's entry at its index position (80 bytes a chunk, already in
  // index order for finish()); offset 0 means not written yet.
  std::vector<vxc::IndexEntry> entries_;
  uint64_t count_ = 0;
  uint64_t end_ = 0;
  uint64_t header_checksum_ = 0;
  uint64_t resumed_ = 0;
  uint64_t kill_at_ = 0;  // test hook: VXR_FAULT_KILL_AT_BYTE (0 = off)
  bool finished_ = false;
};

}  // namespace vxr
