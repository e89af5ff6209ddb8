#include "volume/container_io.h"

#include <fcntl.h>
#include <sys/stat.h>
#include <unistd.h>

#include <cerrno>
#include <cstring>
#include <vector>

#include <xxhash.h>

#include "volume/chunk_buffers.h"
#include "volume/chunk_codec.h"

namespace vxr {

ContainerFile::~ContainerFile() {
  if (fd_ >= 0) ::close(fd_);
}

ContainerFile& ContainerFile::operator=(ContainerFile&& o) noexcept {
  if (this != &o) {
    if (fd_ >= 0) ::close(fd_);
    fd_ = o.fd_;
    path_ = std::move(o.path_);
    o.fd_ = -1;
  }
  return *this;
}

Result<ContainerFile> ContainerFile::open_read(const std::string& path) {
  ContainerFile f;
  // O_NONBLOCK: opening a FIFO must not wait for a writer; it is refused below.
  f.fd_ = ::open(path.c_str(), O_RDONLY | O_CLOEXEC | O_NONBLOCK);
  if (f.fd_ < 0) {
    const int e = errno;
    if (e == ENOENT) return not_found(path + ": no such file");
    return io_error(path + ": cannot open (" + std::strerror(e) + ")");
  }
  f.path_ = path;
  struct stat st{};
  if (::fstat(f.fd_, &st) != 0 || !S_ISREG(st.st_mode))
    return invalid_argument(path + ": is not a regular file (a folder, FIFO or device); give a .vxc file");
  (void)::fcntl(f.fd_, F_SETFL, 0);
  return f;
}

Result<ContainerFile> ContainerFile::open_write(const std::string& path, bool create_new) {
  ContainerFile f;
  // O_NOFOLLOW | O_EXCL: a symlink or file planted under the temp name is never written through.
  f.fd_ = ::open(path.c_str(), O_RDWR | O_CLOEXEC | O_NOFOLLOW | (create_new ? O_CREAT | O_EXCL : 0), 0644);
  if (f.fd_ < 0) {
    if (errno == ELOOP) return invalid_argument(path + ": is a symbolic link; refusing to write through it");
    return io_error(path + ": cannot " + (create_new ? "create" : "open") + " (" + std::string(std::strerror(errno)) +
                    "); check that the folder exists and is writable");
  }
  f.path_ = path;
  struct stat st{};
  if (::fstat(f.fd_, &st) != 0 || !S_ISREG(st.st_mode))
    return invalid_argument(path + ": is not a regular file; refusing to write to it");
  return f;
}

Status ContainerFile::read_at(void* dst, uint64_t bytes, uint64_t offset) const {
  auto* p = static_cast<uint8_t*>(dst);
  while (bytes > 0) {
    const ssize_t n = ::pread(fd_, p, bytes, static_cast<off_t>(offset));
    if (n < 0) {
      if (errno == EINTR) continue;
      return io_error(path_ + ": read failed (" + std::strerror(errno) + ")");
    }
    if (n == 0) return corrupt(path_ + ": unexpected end of file");
    p += n;
    bytes -= static_cast<uint64_t>(n);
    offset += static_cast<uint64_t>(n);
  }
  return Status::ok();
}

Status ContainerFile::write_at(const void* src, uint64_t bytes, uint64_t offset) {
  const auto* p = static_cast<const uint8_t*>(src);
  while (bytes > 0) {
    const ssize_t n = ::pwrite(fd_, p, bytes, static_cast<off_t>(offset));
    if (n < 0) {
      if (errno == EINTR) continue;
      return io_error(path_ + ": write failed (" + std::strerror(errno) + "); check free disk space");
    }
    p += n;
    bytes -= static_cast<uint64_t>(n);
    offset += static_cast<uint64_t>(n);
  }
  return Status::ok();
}

Result<uint64_t> ContainerFile::size() const {
  struct stat st;
  if (::fstat(fd_, &st) != 0) return io_error(path_ + ": cannot stat (" + std::strerror(errno) + ")");
  return static_cast<uint64_t>(st.st_size);
}

Status ContainerFile::truncate(uint64_t bytes) {
  if (::ftruncate(fd_, static_cast<off_t>(bytes)) != 0)
    return io_error(path_ + ": cannot truncate (" + std::strerror(errno) + ")");
  return Status::ok();
}

Status ContainerFile::sync() {
  if (::fsync(fd_) != 0) return io_error(path_ + ": fsync failed (" + std::strerror(errno) + ")");
  return Status::ok();
}

std::string describe_key(const ChunkKey& k) {
  return "level " + std::to_string(k.level) + " chunk (" + std::to_string(k.x) + "," + std::to_string(k.y) + "," +
         std::to_string(k.z) + ") channel " + std::to_string(k.channel) + " timepoint " + std::to_string(k.timepoint);
}

Result<vxc::RecordHeader> read_record_header(const ContainerFile& file, uint64_t offset, uint64_t limit) {
  vxc::RecordHeader r;
  if (offset + sizeof r > limit || offset + sizeof r < offset)
    return corrupt(file.path() + ": chunk record at offset " + std::to_string(offset) + " runs past its region");
  VXR_RETURN_IF_ERROR(file.read_at(&r, sizeof r, offset));
  if (std::memcmp(r.magic, vxc::kRecordMagic, 8) != 0)
    return corrupt(file.path() + ": no chunk record at offset " + std::to_string(offset));
  if (r.header_checksum != vxc::checksum(&r, sizeof r - 8))
    return corrupt(file.path() + ": chunk record header at offset " + std::to_string(offset) + " fails its checksum");
  if (r.codec > 3) return corrupt(file.path() + ": chunk record at offset " + std::to_string(offset) + " has an unknown codec");
  if (offset + sizeof r + r.stored_size > limit || r.stored_size > (uint64_t(1) << 40))
    return corrupt(file.path() + ": chunk payload at offset " + std::to_string(offset) + " runs past its region");
  return r;
}

vxc::IndexEntry entry_from_record(const vxc::RecordHeader& r, uint64_t offset) {
  vxc::IndexEntry e;
  std::memset(&e, 0, sizeof e);
  e.level = r.level;
  e.x = r.x;
  e.y = r.y;
  e.z = r.z;
  e.channel = r.channel;
  e.timepoint = r.timepoint;
  e.codec = r.codec;
  e.offset = offset;
  e.raw_size = r.raw_size;
  e.stored_size = r.stored_size;
  e.min = r.min;
  e.max = r.max;
  e.payload_checksum = r.payload_checksum;
  return e;
}

ChunkKey key_of(const vxc::IndexEntry& e) {
  ChunkKey k;
  k.level = e.level;
  k.x = e.x;
  k.y = e.y;
  k.z = e.z;
  k.channel = e.channel;
  k.timepoint = e.timepoint;
  return k;
}

namespace {
bool same_entry(const vxc::IndexEntry& a, const vxc::IndexEntry& b) {
  // Compare every field except offset (the record does not store its own offset).
  return a.level == b.level && a.x == b.x && a.y == b.y && a.z == b.z && a.channel == b.channel &&
         a.timepoint == b.timepoint && a.codec == b.codec && a.raw_size == b.raw_size &&
         a.stored_size == b.stored_size && std::memcmp(&a.min, &b.min, 8) == 0 &&
         std::memcmp(&a.max, &b.max, 8) == 0 && a.payload_checksum == b.payload_checksum;
}
}  // namespace

namespace {

// The checks shared by read_chunk_record and check_chunk_record: the record
// header agrees with the entry, the sizes are possible for the codec (before
// anything is allocated from them), and the stored bytes pass their checksum.
// Returns the stored bytes: a view of a per-thread buffer that is reused from
// read to read (a fresh buffer per chunk cost playback a page fault every 4 KiB),
// valid until this thread's next call.
Result<std::span<const uint8_t>> load_record(const ContainerFile& file, const ContainerLayout& layout,
                                             const vxc::IndexEntry& entry, uint64_t limit, const std::string& what) {
  auto rec = read_record_header(file, entry.offset, limit);
  if (!rec) return corrupt(what + ": " + rec.status().message() + "; run `vxr verify`");
  if (!same_entry(entry_from_record(*rec, entry.offset), entry))
    return corrupt(what + ": chunk record disagrees with the index; run `vxr verify`");
  if (entry.raw_size != layout.payload_bytes())
    return corrupt(what + ": chunk size " + std::to_string(entry.raw_size) + " does not match the header");
  const auto codec = static_cast<vxc::Codec>(entry.codec);
  const bool lz4 = codec == vxc::Codec::kLz4 || codec == vxc::Codec::kShuffleLz4;
  if ((codec == vxc::Codec::kUniform && entry.stored_size != 0) ||
      (codec == vxc::Codec::kRaw && entry.stored_size != entry.raw_size) ||
      (lz4 && entry.raw_size > max_lz4_output(entry.stored_size)))
    return corrupt(what + ": stored size " + std::to_string(entry.stored_size) + " is impossible for its codec; run `vxr verify`");
  // stored_size <= raw_size here (or LZ4's bound of the file's own bytes): read_record_header checked it fits the file.
  thread_local std::vector<uint8_t> buffer;
  if (buffer.size() < entry.stored_size) buffer.resize(entry.stored_size);
  const std::span<const uint8_t> stored(buffer.data(), entry.stored_size);
  if (!stored.empty()) {
    VXR_RETURN_IF_ERROR(file.read_at(buffer.data(), stored.size(), entry.offset + sizeof(vxc::RecordHeader)));
    if (vxc::checksum(stored.data(), stored.size()) != entry.payload_checksum)
      return corrupt(what + ": payload fails its checksum (the file is damaged); run `vxr verify`");
  }
  return stored;
}

}  // namespace

Result<std::shared_ptr<const Chunk>> read_chunk_record(const ContainerFile& file, const ContainerLayout& layout,
                                                       const vxc::IndexEntry& entry, uint64_t limit) {
  const ChunkKey key = key_of(entry);
  const std::string what = file.path() + ": " + describe_key(key);
  VXR_ASSIGN_OR_RETURN(const std::span<const uint8_t> stored, load_record(file, layout, entry, limit, what));
  auto chunk = std::make_unique<Chunk>();
  chunk->key = key;
  chunk->edge = layout.edge();
  chunk->dtype = layout.info.dtype;
  chunk->stats = {entry.min, entry.max};
  chunk->data = take_chunk_buffer(entry.raw_size);  // every byte is written by the decoder
  if (Status s = decode_payload(static_cast<vxc::Codec>(entry.codec), chunk->dtype, chunk->stats, stored, chunk->data); !s)
    return corrupt(what + ": " + s.message());
  return share_recycling(std::move(chunk));
}

Status check_chunk_record(const ContainerFile& file, const ContainerLayout& layout, const vxc::IndexEntry& entry,
                          uint64_t limit) {
  const std::string what = file.path() + ": " + describe_key(key_of(entry));
  VXR_ASSIGN_OR_RETURN(const std::span<const uint8_t> stored, load_record(file, layout, entry, limit, what));
  const auto codec = static_cast<vxc::Codec>(entry.codec);
  Status s = Status::ok();
  if (codec == vxc::Codec::kUniform) {
    // Nothing to decode: filling edge^3 voxels would cost work the file's bytes do not bound.
    s = check_uniform_value(layout.info.dtype, entry.min);
  } else {
    std::vector<uint8_t> data(entry.raw_size);  // at most ~255x the stored bytes (load_record checked)
    s = decode_payload(codec, layout.info.dtype, {entry.min, entry.max}, stored, data);
  }
  if (!s) return corrupt(what + ": " + s.message());
  return Status::ok();
}

Result<IndexScan> scan_index(const ContainerFile& file, uint64_t index_offset, uint64_t count,
                             const std::function<void(uint64_t, const vxc::IndexEntry&)>& visit) {
  IndexScan scan;
  std::unique_ptr<XXH64_state_t, decltype(&XXH64_freeState)> state(XXH64_createState(), &XXH64_freeState);
  if (!state) return internal_error(file.path() + ": out of memory hashing the index");
  XXH64_reset(state.get(), 0);
  VXR_RETURN_IF_ERROR(file.read_at(&scan.header, sizeof scan.header, index_offset));
  XXH64_update(state.get(), &scan.header, sizeof scan.header);
  constexpr uint64_t kBlockEntries = (uint64_t(1) << 20) / sizeof(vxc::IndexEntry);
  std::vector<vxc::IndexEntry> block(std::min(count, kBlockEntries));
  for (uint64_t i = 0; i < count; i += kBlockEntries) {
    const uint64_t n = std::min(kBlockEntries, count - i);
    const uint64_t bytes = n * sizeof(vxc::IndexEntry);
    VXR_RETURN_IF_ERROR(file.read_at(block.data(), bytes, index_offset + sizeof scan.header + i * sizeof(vxc::IndexEntry)));
    XXH64_update(state.get(), block.data(), bytes);
    for (uint64_t j = 0; j < n; ++j) visit(i + j, block[j]);
  }
  scan.checksum = XXH64_digest(state.get());
  return scan;
}

}  // namespace vxr
