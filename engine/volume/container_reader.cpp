#include "volume/container_reader.h"

#include <algorithm>
#include <cstring>

#include "core/checked_math.h"

namespace vxr {

Result<std::unique_ptr<ContainerReader>> ContainerReader::open(const std::string& path) {
  std::unique_ptr<ContainerReader> r(new ContainerReader());
  r->path_ = path;
  VXR_ASSIGN_OR_RETURN(r->file_, ContainerFile::open_read(path));
  VXR_ASSIGN_OR_RETURN(const uint64_t size, r->file_.size());
  r->file_bytes_ = size;
  std::vector<uint8_t> head(std::min<uint64_t>(size, vxc::kMaxHeaderBytes));
  VXR_RETURN_IF_ERROR(r->file_.read_at(head.data(), head.size(), 0));
  uint64_t header_bytes = 0;
  VXR_ASSIGN_OR_RETURN(r->layout_, parse_header(head, path, &header_bytes));
  r->header_bytes_ = header_bytes;
  const uint64_t header_sum = [&] {
    uint64_t s;
    std::memcpy(&s, head.data() + header_bytes - 8, 8);
    return s;
  }();

  const std::string unfinished = path +
                                 ": has no valid footer: it is an unfinished or damaged conversion "
                                 "(finish it with `vxr import ... --resume`, or run `vxr verify`)";
  if (size < header_bytes + sizeof(vxc::Footer) + sizeof(vxc::IndexHeader)) return corrupt(unfinished);
  vxc::Footer f;
  VXR_RETURN_IF_ERROR(r->file_.read_at(&f, sizeof f, size - sizeof f));
  if (std::memcmp(f.magic, vxc::kFooterMagic, 8) != 0) return corrupt(unfinished);
  if (f.footer_checksum != vxc::checksum(&f, 48))
    return corrupt(path + ": footer fails its checksum (the file is damaged); run `vxr verify`");
  if (f.file_bytes != size) return corrupt(path + ": file is " + std::to_string(size) + " bytes, its footer says " +
                                           std::to_string(f.file_bytes) + " (truncated or appended to)");
  if (f.header_checksum != header_sum) return corrupt(path + ": footer does not belong to this header");
  if (f.index_offset < header_bytes || f.index_offset > size || f.chunk_count > size / sizeof(vxc::IndexEntry) ||
      f.index_bytes != sizeof(vxc::IndexHeader) + f.chunk_count * sizeof(vxc::IndexEntry) ||
      f.index_offset + f.index_bytes + sizeof f != size)
    return corrupt(path + ": footer points at an impossible index");
  const ContainerLayout& L = r->layout_;
  if (f.chunk_count != L.total_chunks())
    return corrupt(path + ": index lists " + std::to_string(f.chunk_count) + " chunks, the pyramid needs " +
                   std::to_string(L.total_chunks()));
  r->chunk_count_ = f.chunk_count;
  r->index_offset_ = f.index_offset;

  // One streaming pass: the checksum of the whole index, and every entry at
  // the position its key implies (so no duplicates, none missing).
  std::string bad_entry;
  uint64_t uniform = 0;
  VXR_ASSIGN_OR_RETURN(const IndexScan scan,
                       scan_index(r->file_, f.index_offset, f.chunk_count, [&](uint64_t i, const vxc::IndexEntry& e) {
                         if (bad_entry.empty()) bad_entry = r->check_entry(i, e);
                         uniform += e.codec == uint8_t(vxc::Codec::kUniform);
                       }));
  if (scan.checksum != f.index_checksum)
    return corrupt(path + ": chunk index fails its checksum (the file is damaged); run `vxr verify`");
  if (std::memcmp(scan.header.magic, vxc::kIndexMagic, 8) != 0 || scan.header.count != f.chunk_count)
    return corrupt(path + ": chunk index is damaged");
  if (!bad_entry.empty()) return corrupt(path + ": " + bad_entry);
  r->uniform_chunks_ = uniform;
  r->cache_.resize(kIndexCacheBlocks);
  return r;
}

std::string ContainerReader::check_entry(uint64_t i, const vxc::IndexEntry& e) const {
  const ContainerLayout& L = layout_;
  const ChunkKey k = key_of(e);
  if (!(k == L.key_at(i)))
    return "index entry " + std::to_string(i) + " is invalid: it names " + describe_key(k) + " where " +
           describe_key(L.key_at(i)) + " belongs (run `vxr verify`)";
  if (e.codec > 3 || e.raw_size != L.payload_bytes() || e.offset < header_bytes_ || e.offset > index_offset_ ||
      e.stored_size > index_offset_ - e.offset || index_offset_ - e.offset - e.stored_size < sizeof(vxc::RecordHeader))
    return "index entry " + std::to_string(i) + " (" + describe_key(k) +
           ") is invalid: bad codec, size or offset (run `vxr verify`)";
  return {};
}

Result<vxc::IndexEntry> ContainerReader::entry_at(uint64_t i) const {
  if (i >= chunk_count_) return out_of_range(path_ + ": no index entry " + std::to_string(i));
  const uint64_t block = i / kIndexBlockEntries;
  CacheSlot& slot = cache_[block % kIndexCacheBlocks];
  vxc::IndexEntry e;
  bool hit = false;
  {
    std::lock_guard lock(cache_mutex_);
    if (slot.block == block) {
      e = slot.entries[i - block * kIndexBlockEntries];
      hit = true;
    }
  }
  if (!hit) {
    // Miss: read the block without holding the lock, then install it.
    const uint64_t first = block * kIndexBlockEntries;
    std::vector<vxc::IndexEntry> entries(std::min(kIndexBlockEntries, chunk_count_ - first));
    VXR_RETURN_IF_ERROR(file_.read_at(entries.data(), entries.size() * sizeof(vxc::IndexEntry),
                                      index_offset_ + sizeof(vxc::IndexHeader) + first * sizeof(vxc::IndexEntry)));
    e = entries[i - first];
    std::lock_guard lock(cache_mutex_);
    slot.block = block;
    slot.entries = std::move(entries);
  }
  // open() checked every entry and the index checksum; this catches a file
  // changed underneath us since.
  if (std::string bad = check_entry(i, e); !bad.empty()) return corrupt(path_ + ": " + bad);
  return e;
}

Result<vxc::IndexEntry> ContainerReader::entry(const ChunkKey& key) const {
  if (!layout_.contains(key)) return not_found(path_ + ": no " + describe_key(key));
  return entry_at(layout_.index_position(key));
}

uint64_t ContainerReader::resident_index_bytes() const {
  std::lock_guard lock(cache_mutex_);
  uint64_t bytes = 0;
  for (const CacheSlot& s : cache_) bytes += s.entries.size() * sizeof(vxc::IndexEntry);
  return bytes;
}

Result<ChunkStats> ContainerReader::stats(const ChunkKey& key) const {
  VXR_ASSIGN_OR_RETURN(const vxc::IndexEntry e, entry(key));
  return ChunkStats{e.min, e.max};
}

Result<std::shared_ptr<const Chunk>> ContainerReader::read(const ChunkKey& key) const {
  VXR_ASSIGN_OR_RETURN(const vxc::IndexEntry e, entry(key));
  return read_chunk_record(file_, layout_, e, index_offset_);
}

double ContainerReader::compression_ratio() const {
  // Voxels of every level (no apron, no padding of edge chunks) over the file size.
  uint64_t voxels = 0;
  for (const auto& li : layout_.levels) voxels += li.dims[0] * li.dims[1] * li.dims[2];
  const double raw = double(voxels) * dtype_bytes(layout_.info.dtype) * layout_.info.channels * layout_.info.timepoints;
  return file_bytes_ ? raw / double(file_bytes_) : 0.0;
}

Result<DenseVolume> read_level_dense(const ChunkSource& source, uint32_t level, uint32_t channel, uint32_t timepoint,
                                     uint64_t max_bytes) {
  if (level >= source.levels().size()) return out_of_range("level " + std::to_string(level) + " does not exist");
  const VolumeInfo& info = source.info();
  if (channel >= info.channels || timepoint >= info.timepoints)
    return out_of_range("channel " + std::to_string(channel) + " / timepoint " + std::to_string(timepoint) +
                        " does not exist");
  const LevelInfo& li = source.levels()[level];
  const uint32_t bpv = dtype_bytes(info.dtype);
  for (int a = 0; a < 3; ++a)
    if (li.dims[a] > 0xffffffffull) return out_of_range("level " + std::to_string(level) + " is too large for memory");
  const uint64_t bytes = checked_product({li.dims[0], li.dims[1], li.dims[2], bpv}).value_or(~uint64_t(0));
  if (bytes > max_bytes)
    return out_of_range("level " + std::to_string(level) + " needs " + std::to_string(bytes >> 20) +
                        " MiB, more than the " + std::to_string(max_bytes >> 20) + " MiB allowed; pick a coarser level");
  DenseVolume v;
  v.dims = {uint32_t(li.dims[0]), uint32_t(li.dims[1]), uint32_t(li.dims[2])};
  v.dtype = info.dtype;
  for (int a = 0; a < 3; ++a) v.voxel_size[a] = info.voxel_size[a] * li.downsample[a];
  v.unit = info.unit;
  v.data.resize(bytes);
  const uint64_t C = source.chunk_size(), A = source.apron();
  for (uint32_t cz = 0; cz < li.chunk_counts[2]; ++cz)
    for (uint32_t cy = 0; cy < li.chunk_counts[1]; ++cy)
      for (uint32_t cx = 0; cx < li.chunk_counts[0]; ++cx) {
        ChunkKey key{level, cx, cy, cz, channel, timepoint};
        VXR_ASSIGN_OR_RETURN(auto chunk, source.read(key));
        const uint64_t E = chunk->edge;
        const uint64_t x0 = cx * C, y0 = cy * C, z0 = cz * C;
        const uint64_t nx = std::min(C, li.dims[0] - x0), ny = std::min(C, li.dims[1] - y0),
                       nz = std::min(C, li.dims[2] - z0);
        for (uint64_t z = 0; z < nz; ++z)
          for (uint64_t y = 0; y < ny; ++y) {
            const uint8_t* src = chunk->data.data() + (((z + A) * E + (y + A)) * E + A) * bpv;
            uint8_t* dst = v.data.data() + (((z0 + z) * li.dims[1] + (y0 + y)) * li.dims[0] + x0) * bpv;
            std::memcpy(dst, src, nx * bpv);
          }
      }
  return v;
}

uint32_t finest_level_that_fits(const ChunkSource& source, uint64_t max_side, uint64_t max_bytes) {
  const auto& levels = source.levels();
  const uint32_t bpv = dtype_bytes(source.info().dtype);
  for (uint32_t l = 0; l < levels.size(); ++l) {
    const auto& d = levels[l].dims;
    const auto bytes = checked_product({d[0], d[1], d[2], bpv});
    if (d[0] <= max_side && d[1] <= max_side && d[2] <= max_side && bytes && *bytes <= max_bytes) return l;
  }
  return static_cast<uint32_t>(levels.size() - 1);
}

}  // namespace vxr
