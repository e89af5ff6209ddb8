// One Zarr array (v2 `.zarray` or v3 `zarr.json`): its metadata, and reads of
// any box of it as C-order native-endian voxels.
//
//   auto a = ZarrArray::open(store, "scale0/image");
//   if (!a) return a.status();                      // "x.zarr/scale0/image/.zarray: 'chunks' must be ..."
//   a->read(start, size, bytes);                    // chunks decoded, edges clipped, holes = fill_value
//
// What is read: dtypes u1 i1 u2 i2 u4 i4 f4 of either byte order; C or F
// order (v2) and the v3 transpose codec; v2 compressors and v3 codecs of
// zarr_codecs.h; v2 dimension_separator '.' or '/'; v3 chunk_key_encoding
// default ("c/1/2/3", or '.') and v2; the v3 sharding_indexed codec (index at
// the start or end, bytes + crc32c index codecs). A sharded array is read by
// its inner chunks: one range read of the shard's index (kept in a small
// cache) and one of the inner chunk.
//
// Decoded chunks are kept in an LRU cache of at most cache_bytes, shared by
// all threads (a mutex guards it; decoding runs outside the lock, so two
// threads wanting the same absent chunk may both decode it).
//
// Errors: a malformed metadata file is kInvalidArgument or kUnsupported naming
// the file and the key; a missing chunk is the fill value; a chunk that does
// not decode to the chunk's size is kCorrupt naming the chunk's key.
#pragma once

#include <cstdint>
#include <list>
#include <memory>
#include <mutex>
#include <span>
#include <string>
#include <unordered_map>
#include <vector>

#include "core/status.h"
#include "volume/dtype.h"
#include "volume/zarr/zarr_codecs.h"
#include "volume/zarr/zarr_store.h"

namespace vxr::zarr {

struct ArrayMeta {
  int zarr_format = 2;
  std::vector<uint64_t> shape;   // array dims, slowest first (as stored: e.g. t,c,z,y,x)
  std::vector<uint64_t> chunks;  // shape of one read unit (a v3 shard's inner chunk)
  DType dtype = DType::kU8;
  bool big_endian = false;          // as stored; reads return native order
  std::vector<uint8_t> fill;        // one element, native byte order
  std::vector<uint32_t> transpose;  // stored = transpose(chunk, order); empty when C order
  std::vector<BytesCodec> codecs;   // applied in order when writing
  std::string key_prefix;           // "c" for v3 default keys, "" otherwise
  char separator = '.';
  std::vector<std::string> dimension_names;  // v3 dimension_names (may be empty)
  // v3 sharding_indexed: each stored object is a shard of shard_shape holding
  // inner chunks of `chunks`.
  bool sharded = false;
  std::vector<uint64_t> shard_shape;
  std::vector<BytesCodec> index_codecs;  // after the little-endian (offset, nbytes) table
  bool index_at_end = true;

  uint64_t chunk_elements() const;
};

// Parses metadata text; `what` names the file in messages.
Result<ArrayMeta> parse_v2_array(const std::string& text, const std::string& what);
Result<ArrayMeta> parse_v3_array(const std::string& text, const std::string& what);

class ZarrArray {
 public:
  // `path`: the array's key prefix in the store ("" for the root).
  // Reads `path/.zarray` or `path/zarr.json`, whichever exists.
  static Result<std::unique_ptr<ZarrArray>> open(std::shared_ptr<const ZarrStore> store, const std::string& path,
                                                 uint64_t cache_bytes = uint64_t(128) << 20);

  const ArrayMeta& meta() const { return meta_; }
  size_t ndim() const { return meta_.shape.size(); }
  // Where messages point: "x.zarr/scale0/image".
  std::string describe() const { return store_->describe(path_); }

  // Reads the box [start, start + size) (within the shape) into dst, C order
  // (last dimension fastest), native byte order; dst must hold exactly
  // prod(size) * dtype_bytes bytes. Thread-safe.
  Status read(std::span<const uint64_t> start, std::span<const uint64_t> size, std::span<uint8_t> dst) const;

  // The store key of a read unit (a chunk, or a shard for sharded arrays).
  std::string chunk_key(std::span<const uint64_t> grid_index) const;

  // Raises the decoded-chunk budget to at least `bytes` (never lowers it):
  // a reader whose boxes span many chunks (thin slice-shaped chunks) needs
  // the chunks of one box resident, or every box decodes them all again.
  void raise_cache_bytes(uint64_t bytes);
  uint64_t cache_budget() const;

  // Decoded chunks held now, and how often a chunk had to be decoded.
  uint64_t cached_bytes() const;
  uint64_t decodes() const;

 private:
  ZarrArray(std::shared_ptr<const ZarrStore> store, std::string path, ArrayMeta meta, uint64_t cache_bytes)
      : store_(std::move(store)), path_(std::move(path)), meta_(std::move(meta)), cache_bytes_(cache_bytes) {}

  using Bytes = std::vector<uint8_t>;
  // The decoded read unit at `index` (chunk grid coordinates), or nullptr when
  // it is absent (fill value).
  Result<std::shared_ptr<const Bytes>> chunk(const std::vector<uint64_t>& index) const;
  Result<std::shared_ptr<const Bytes>> load_chunk(const std::vector<uint64_t>& index) const;
  // Offset and size of an inner chunk inside its shard; both ~0 when absent.
  struct ShardEntry {
    uint64_t offset = 0, nbytes = 0;
  };
  // The index of the shard stored at `key`; nullptr when the shard is absent.
  Result<std::shared_ptr<const std::vector<ShardEntry>>> shard_index(const std::string& key) const;
  Result<Bytes> decode_unit(Bytes stored, const std::string& key) const;

  std::shared_ptr<const ZarrStore> store_;
  std::string path_;
  ArrayMeta meta_;
  uint64_t cache_bytes_;

  // LRU of decoded chunks keyed by store key (+ "#inner" for shards).
  struct Entry {
    std::shared_ptr<const Bytes> bytes;  // nullptr: absent (fill)
    std::list<std::string>::iterator lru;
  };
  mutable std::mutex mutex_;
  mutable std::list<std::string> lru_;  // front = most recent
  mutable std::unordered_map<std::string, Entry> cache_;
  mutable uint64_t held_ = 0;
  mutable uint64_t decodes_ = 0;
  // Shard indexes, a few at most (16 bytes per inner chunk each).
  mutable std::list<std::pair<std::string, std::shared_ptr<const std::vector<ShardEntry>>>> shard_indexes_;
};

}  // namespace vxr::zarr
