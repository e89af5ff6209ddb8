// Low-level .vxc file access shared by the reader, writer and verifier
// (not a public API: use ContainerReader / ContainerWriter).
#pragma once

#include <cstdint>
#include <functional>
#include <memory>
#include <string>

#include "core/status.h"
#include "volume/chunk_source.h"
#include "volume/container_format.h"
#include "volume/container_layout.h"

namespace vxr {

// An open file descriptor; pread/pwrite are thread-safe.
class ContainerFile {
 public:
  ContainerFile() = default;
  ~ContainerFile();
  ContainerFile(ContainerFile&& o) noexcept : fd_(o.fd_), path_(std::move(o.path_)) { o.fd_ = -1; }
  ContainerFile& operator=(ContainerFile&& o) noexcept;
  ContainerFile(const ContainerFile&) = delete;
  ContainerFile& operator=(const ContainerFile&) = delete;

  static Result<ContainerFile> open_read(const std::string& path);
  // Opens for read+write. create_new: the file must not exist yet (O_EXCL);
  // otherwise it must be an existing regular file. Never follows a symlink.
  static Result<ContainerFile> open_write(const std::string& path, bool create_new);

  Status read_at(void* dst, uint64_t bytes, uint64_t offset) const;
  Status write_at(const void* src, uint64_t bytes, uint64_t offset);
  Result<uint64_t> size() const;
  Status truncate(uint64_t bytes);
  Status sync();
  const std::string& path() const { return path_; }

 private:
  int fd_ = -1;
  std::string path_;
};

// Reads the record header at `offset` and checks magic, checksum and that it
// fits before `limit`. kCorrupt otherwise.
Result<vxc::RecordHeader> read_record_header(const ContainerFile& file, uint64_t offset, uint64_t limit);

vxc::IndexEntry entry_from_record(const vxc::RecordHeader& r, uint64_t offset);
ChunkKey key_of(const vxc::IndexEntry& e);

// Reads the chunk record that `entry` points at, checks that the record header
// agrees with the entry and the payload checksum, and decodes the payload.
Result<std::shared_ptr<const Chunk>> read_chunk_record(const ContainerFile& file, const ContainerLayout& layout,
                                                       const vxc::IndexEntry& entry, uint64_t limit);

// The same checks as read_chunk_record, decoding only what the file's bytes
// pay for: a uniform chunk's value is checked, not expanded to edge^3 voxels,
// so verifying costs time in proportion to the file size (a 103 KB file of
// uniform 512^3 chunks took 105 s when every chunk was filled).
Status check_chunk_record(const ContainerFile& file, const ContainerLayout& layout, const vxc::IndexEntry& entry,
                          uint64_t limit);

// Reads the index region (IndexHeader, then `count` IndexEntry records, at
// `index_offset`) in blocks of at most 1 MiB, calling visit(i, entry) for
// every entry in file order, so even a multi-GB index is checked in bounded
// memory. Returns the index header and the XXH64 of the whole region (what
// the footer's index_checksum covers); I/O errors only: the caller judges.
struct IndexScan {
  vxc::IndexHeader header{};
  uint64_t checksum = 0;
};
Result<IndexScan> scan_index(const ContainerFile& file, uint64_t index_offset, uint64_t count,
                             const std::function<void(uint64_t, const vxc::IndexEntry&)>& visit);

// "level 0 chunk (1,2,3) channel 0 timepoint 0"
std::string describe_key(const ChunkKey& k);

}  // namespace vxr
