// Where a Zarr hierarchy's bytes live. Arrays and groups ask a store for keys
// ("0/.zarray", "scale0/image/c/0/0"); the store says what the bytes are or
// that the key is absent (a missing chunk is the fill value, not an error).
//
// Only a local folder exists today (DirectoryStore); an HTTP store can be added
// behind the same interface, which is why reads take byte ranges: sharded
// arrays fetch a shard's index and one inner chunk, never the whole shard.
#pragma once

#include <cstdint>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "core/status.h"

namespace vxr::zarr {

// Which bytes of a value to read: all of it, [offset, offset + length), or the
// last `length` bytes (suffix, for a shard index stored at the end).
struct ByteRange {
  enum class Kind : uint8_t { kAll, kRange, kSuffix };
  Kind kind = Kind::kAll;
  uint64_t offset = 0;
  uint64_t length = 0;
  static ByteRange all() { return {}; }
  static ByteRange range(uint64_t offset, uint64_t length) { return {Kind::kRange, offset, length}; }
  static ByteRange suffix(uint64_t length) { return {Kind::kSuffix, 0, length}; }
};

class ZarrStore {
 public:
  virtual ~ZarrStore() = default;
  // The value's bytes, std::nullopt when the key does not exist, an error for
  // I/O failures or a range past the end (kCorrupt: the value is truncated).
  // Thread-safe.
  virtual Result<std::optional<std::vector<uint8_t>>> get(const std::string& key,
                                                          ByteRange range = ByteRange::all()) const = 0;
  // What to call `key` in messages: a path a user can find ("x.zarr/0/.zarray").
  virtual std::string describe(const std::string& key) const = 0;
};

// Keys are '/'-separated paths under a root folder.
class DirectoryStore final : public ZarrStore {
 public:
  explicit DirectoryStore(std::string root);
  Result<std::optional<std::vector<uint8_t>>> get(const std::string& key, ByteRange range) const override;
  std::string describe(const std::string& key) const override;
  const std::string& root() const { return root_; }

 private:
  std::string root_;  // without a trailing '/'
};

}  // namespace vxr::zarr
