#include "volume/container_writer.h"

#include <fcntl.h>
#include <unistd.h>

#include <algorithm>
#include <csignal>
#include <cstdlib>
#include <cstring>
#include <filesystem>

#include <xxhash.h>

#include "core/log.h"

namespace vxr {
namespace {

void fsync_dir_of(const std::string& path) {
  const std::string dir = std::filesystem::path(path).parent_path().string();
  const int fd = ::open(dir.empty() ? "." : dir.c_str(), O_RDONLY | O_DIRECTORY | O_CLOEXEC);
  if (fd >= 0) {
    ::fsync(fd);
    ::close(fd);
  }
}

}  // namespace

ContainerWriter::~ContainerWriter() = default;

Status ContainerWriter::write_tracked(const void* data, uint64_t bytes, uint64_t offset) {
  if (kill_at_ && offset + bytes > kill_at_) {
    // Test hook: die exactly at byte kill_at_, as a SIGKILL or power cut would.
    if (kill_at_ > offset) (void)file_.write_at(data, kill_at_ - offset, offset);
    std::raise(SIGKILL);
  }
  return file_.write_at(data, bytes, offset);
}

Result<std::unique_ptr<ContainerWriter>> ContainerWriter::create(const std::string& path, const ContainerLayout& layout,
                                                                 bool resume) {
  std::unique_ptr<ContainerWriter> w(new ContainerWriter());
  w->path_ = path;
  w->partial_ = path + ".partial";
  w->layout_ = layout;
  w->entries_.resize(layout.total_chunks());  // zeroed: offset 0 marks "not written"
  if (const char* k = std::getenv("VXR_FAULT_KILL_AT_BYTE")) w->kill_at_ = std::strtoull(k, nullptr, 10);
  const std::vector<uint8_t> header = serialize_header(layout);
  std::memcpy(&w->header_checksum_, header.data() + header.size() - 8, 8);

  std::error_code ec;
  const bool exists = std::filesystem::exists(std::filesystem::symlink_status(w->partial_, ec));
  if (exists && !resume)
    return invalid_argument(w->partial_ + ": an interrupted import exists; continue it with --resume, or delete it");
  bool fresh = true;
  if (exists) {
    VXR_ASSIGN_OR_RETURN(w->file_, ContainerFile::open_write(w->partial_, false));
    VXR_ASSIGN_OR_RETURN(const uint64_t size, w->file_.size());
    std::vector<uint8_t> have(std::min<uint64_t>(size, vxc::kMaxHeaderBytes));
    VXR_RETURN_IF_ERROR(w->file_.read_at(have.data(), have.size(), 0));
    uint64_t hb = 0;
    auto parsed = parse_header(have, w->partial_, &hb);
    if (!parsed.is_ok() && size > header.size())
      return corrupt(w->partial_ + ": header is damaged, so the import cannot be resumed; delete it to start over");
    if (parsed.is_ok()) {
      if (hb != header.size() || std::memcmp(have.data(), header.data(), header.size()) != 0)
        return invalid_argument(w->partial_ +
                                ": was started from different input or settings (dims, dtype, chunk size, voxel "
                                "size...); delete it to start over");
      fresh = false;
      // Keep every record that checks out; the first one that does not is the torn tail.
      uint64_t off = header.size();
      std::vector<uint8_t> payload;
      while (off < size) {
        auto rec = read_record_header(w->file_, off, size);
        if (!rec) break;
        const vxc::IndexEntry e = entry_from_record(*rec, off);
        const ChunkKey key = key_of(e);
        if (!layout.contains(key) || e.raw_size != layout.payload_bytes() || w->present(key)) break;
        payload.resize(e.stored_size);
        if (!payload.empty() && !w->file_.read_at(payload.data(), payload.size(), off + sizeof(vxc::RecordHeader)))
          break;
        if (!payload.empty() && vxc::checksum(payload.data(), payload.size()) != e.payload_checksum) break;
        if (payload.empty() && e.codec != static_cast<uint8_t>(vxc::Codec::kUniform)) break;
        w->entries_[layout.index_position(key)] = e;
        ++w->count_;
        off += sizeof(vxc::RecordHeader) + e.stored_size;
      }
      if (off < size) VXR_RETURN_IF_ERROR(w->file_.truncate(off));
      w->end_ = off;
      w->resumed_ = w->count_;
      log_info(w->partial_ + ": resuming with " + std::to_string(w->resumed_) + " chunks already written");
    }
    // A partial file no longer than a torn header holds nothing worth keeping: start over.
  }
  if (fresh) {
    if (exists) {  // a torn header only: start over in a new file
      w->file_ = ContainerFile();
      std::filesystem::remove(w->partial_, ec);
    }
    VXR_ASSIGN_OR_RETURN(w->file_, ContainerFile::open_write(w->partial_, true));
    VXR_RETURN_IF_ERROR(w->write_tracked(header.data(), header.size(), 0));
    w->end_ = header.size();
  }
  return w;
}

bool ContainerWriter::has(const ChunkKey& key) const {
  std::lock_guard<std::mutex> lock(mutex_);
  return present(key);
}

uint64_t ContainerWriter::chunk_count() const {
  std::lock_guard<std::mutex> lock(mutex_);
  return count_;
}

uint64_t ContainerWriter::bytes_written() const {
  std::lock_guard<std::mutex> lock(mutex_);
  return end_;
}

Status ContainerWriter::append(const EncodedChunk& c) {
  if (!layout_.contains(c.key)) return internal_error("append: " + describe_key(c.key) + " is outside the layout");
  if (c.raw_size != layout_.payload_bytes()) return internal_error("append: chunk payload has the wrong size");
  vxc::RecordHeader r;
  std::memset(&r, 0, sizeof r);
  std::memcpy(r.magic, vxc::kRecordMagic, 8);
  r.level = c.key.level;
  r.x = c.key.x;
  r.y = c.key.y;
  r.z = c.key.z;
  r.channel = c.key.channel;
  r.timepoint = c.key.timepoint;
  r.codec = static_cast<uint8_t>(c.codec);
  r.dtype = static_cast<uint8_t>(layout_.info.dtype);
  r.raw_size = c.raw_size;
  r.stored_size = c.stored.size();
  r.min = c.stats.min;
  r.max = c.stats.max;
  r.payload_checksum = c.checksum;
  r.header_checksum = vxc::checksum(&r, sizeof r - 8);
  std::vector<uint8_t> buf(sizeof r + c.stored.size());
  std::memcpy(buf.data(), &r, sizeof r);
  if (!c.stored.empty()) std::memcpy(buf.data() + sizeof r, c.stored.data(), c.stored.size());

  std::lock_guard<std::mutex> lock(mutex_);
  if (finished_) return internal_error("append after finish");
  if (present(c.key)) return internal_error("append: " + describe_key(c.key) + " written twice");
  VXR_RETURN_IF_ERROR(write_tracked(buf.data(), buf.size(), end_));
  entries_[layout_.index_position(c.key)] = entry_from_record(r, end_);
  ++count_;
  end_ += buf.size();
  return Status::ok();
}

Result<std::shared_ptr<const Chunk>> ContainerWriter::read(const ChunkKey& key) const {
  vxc::IndexEntry e;
  uint64_t limit;
  {
    std::lock_guard<std::mutex> lock(mutex_);
    if (!present(key)) return not_found(partial_ + ": " + describe_key(key) + " not written yet");
    e = entries_[layout_.index_position(key)];
    limit = end_;
  }
  return read_chunk_record(file_, layout_, e, limit);
}

Result<ChunkStats> ContainerWriter::stats(const ChunkKey& key) const {
  std::lock_guard<std::mutex> lock(mutex_);
  if (!present(key)) return not_found(partial_ + ": " + describe_key(key) + " not written yet");
  const vxc::IndexEntry& e = entries_[layout_.index_position(key)];
  return ChunkStats{e.min, e.max};
}

Status ContainerWriter::finish() {
  std::lock_guard<std::mutex> lock(mutex_);
  if (finished_) return internal_error("finish called twice");
  if (count_ != layout_.total_chunks())
    return internal_error(partial_ + ": finish with " + std::to_string(count_) + " of " +
                          std::to_string(layout_.total_chunks()) + " chunks");
  // entries_ is already in index order (position = index_position(key)): write it as is.
  vxc::IndexHeader ih;
  std::memcpy(ih.magic, vxc::kIndexMagic, 8);
  ih.count = entries_.size();
  const uint64_t entry_bytes = entries_.size() * sizeof(vxc::IndexEntry);
  const uint64_t index_bytes = sizeof ih + entry_bytes;
  std::unique_ptr<XXH64_state_t, decltype(&XXH64_freeState)> hash(XXH64_createState(), &XXH64_freeState);
  if (!hash) return internal_error(partial_ + ": out of memory hashing the index");
  XXH64_reset(hash.get(), 0);
  XXH64_update(hash.get(), &ih, sizeof ih);
  XXH64_update(hash.get(), entries_.data(), entry_bytes);

  vxc::Footer f;
  std::memset(&f, 0, sizeof f);
  f.index_offset = end_;
  f.index_bytes = index_bytes;
  f.chunk_count = entries_.size();
  f.index_checksum = XXH64_digest(hash.get());
  f.header_checksum = header_checksum_;
  f.file_bytes = end_ + index_bytes + sizeof f;
  f.footer_checksum = vxc::checksum(&f, 48);
  std::memcpy(f.magic, vxc::kFooterMagic, 8);

  VXR_RETURN_IF_ERROR(write_tracked(&ih, sizeof ih, end_));
  if (entry_bytes) VXR_RETURN_IF_ERROR(write_tracked(entries_.data(), entry_bytes, end_ + sizeof ih));
  VXR_RETURN_IF_ERROR(write_tracked(&f, sizeof f, end_ + index_bytes));
  // The file must be durable before its name says it is finished.
  VXR_RETURN_IF_ERROR(file_.sync());
  if (kill_at_ && kill_at_ >= f.file_bytes) std::raise(SIGKILL);  // test hook: die just before the rename
  if (std::rename(partial_.c_str(), path_.c_str()) != 0)
    return io_error(path_ + ": cannot rename the finished " + partial_ + " (" + std::strerror(errno) + ")");
  fsync_dir_of(path_);
  finished_ = true;
  return Status::ok();
}

}  // namespace vxr
