#include "volume/zarr/zarr_store.h"

#include <cerrno>
#include <cstdio>
#include <cstring>
#include <filesystem>

namespace vxr::zarr {

DirectoryStore::DirectoryStore(std::string root) : root_(std::move(root)) {
  while (root_.size() > 1 && root_.back() == '/') root_.pop_back();
}

std::string DirectoryStore::describe(const std::string& key) const {
  return key.empty() ? root_ : root_ + "/" + key;
}

Result<std::optional<std::vector<uint8_t>>> DirectoryStore::get(const std::string& key, ByteRange range) const {
  // Keys come from metadata and chunk coordinates; refuse anything that could
  // climb out of the root.
  if (key.find("..") != std::string::npos || (!key.empty() && key.front() == '/'))
    return invalid_argument(describe(key) + ": key leaves the store's folder");
  const std::string path = describe(key);
  std::error_code ec;
  if (!std::filesystem::is_regular_file(path, ec)) return std::optional<std::vector<uint8_t>>();
  std::FILE* f = std::fopen(path.c_str(), "rb");
  if (!f) return io_error(path + ": cannot open (" + std::strerror(errno) + ")");
  struct Closer {
    std::FILE* f;
    ~Closer() { std::fclose(f); }
  } closer{f};
  if (std::fseek(f, 0, SEEK_END) != 0) return io_error(path + ": cannot seek");
  const long end = std::ftell(f);
  if (end < 0) return io_error(path + ": cannot tell its size");
  const uint64_t size = static_cast<uint64_t>(end);
  uint64_t offset = 0, length = size;
  if (range.kind == ByteRange::Kind::kRange) {
    if (range.offset > size || range.length > size - range.offset)
      return corrupt(path + ": truncated (" + std::to_string(size) + " bytes, a read needs bytes " +
                     std::to_string(range.offset) + ".." + std::to_string(range.offset + range.length) + ")");
    offset = range.offset;
    length = range.length;
  } else if (range.kind == ByteRange::Kind::kSuffix) {
    if (range.length > size)
      return corrupt(path + ": truncated (" + std::to_string(size) + " bytes, the last " +
                     std::to_string(range.length) + " were asked for)");
    offset = size - range.length;
    length = range.length;
  }
  std::vector<uint8_t> bytes(length);
  if (std::fseek(f, static_cast<long>(offset), SEEK_SET) != 0 ||
      (length > 0 && std::fread(bytes.data(), 1, length, f) != length))
    return io_error(path + ": read failed");
  return std::optional<std::vector<uint8_t>>(std::move(bytes));
}

}  // namespace vxr::zarr
