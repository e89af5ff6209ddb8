#include "volume/zarr/zarr_chunk_source.h"

#include <algorithm>
#include <cfloat>
#include <cmath>
#include <cstring>
#include <limits>

namespace vxr {
namespace {

// Range of every value a dtype can hold: what a chunk not read yet may contain.
ChunkStats dtype_range(DType t) {
  switch (t) {
    case DType::kU8:
      return {0, 255};
    case DType::kI8:
      return {-128, 127};
    case DType::kU16:
      return {0, 65535};
    case DType::kI16:
      return {-32768, 32767};
    case DType::kU32:
      return {0, 4294967295.0};
    case DType::kI32:
      return {-2147483648.0, 2147483647.0};
    case DType::kF32:
      return {-double(FLT_MAX), double(FLT_MAX)};
  }
  return {0, 0};
}

template <typename T>
ChunkStats typed_range(const std::vector<uint8_t>& data) {
  const size_t n = data.size() / sizeof(T);
  double lo = std::numeric_limits<double>::infinity(), hi = -lo;
  for (size_t i = 0; i < n; ++i) {
    T v;
    std::memcpy(&v, data.data() + i * sizeof(T), sizeof(T));
    const double d = static_cast<double>(v);
    if (std::isnan(d)) continue;
    lo = std::min(lo, d);
    hi = std::max(hi, d);
  }
  if (lo > hi) return {0, 0};  // all NaN
  return {lo, hi};
}

ChunkStats payload_range(DType t, const std::vector<uint8_t>& data) {
  switch (t) {
    case DType::kU8:
      return typed_range<uint8_t>(data);
    case DType::kI8:
      return typed_range<int8_t>(data);
    case DType::kU16:
      return typed_range<uint16_t>(data);
    case DType::kI16:
      return typed_range<int16_t>(data);
    case DType::kU32:
      return typed_range<uint32_t>(data);
    case DType::kI32:
      return typed_range<int32_t>(data);
    case DType::kF32:
      return typed_range<float>(data);
  }
  return {0, 0};
}

bool near(double v, double target) {
  return std::abs(v - target) <= 0.02 * target;
}

}  // namespace

Result<std::unique_ptr<ZarrChunkSource>> ZarrChunkSource::open(const std::string& path, uint32_t chunk_size,
                                                               uint32_t apron) {
  VXR_ASSIGN_OR_RETURN(std::unique_ptr<zarr::OmeZarrImage> image, zarr::OmeZarrImage::open(path));
  return create(std::move(image), chunk_size, apron);
}

Result<std::unique_ptr<ZarrChunkSource>> ZarrChunkSource::create(std::shared_ptr<const zarr::OmeZarrImage> image,
                                                                 uint32_t chunk_size, uint32_t apron) {
  if (chunk_size < 8 || chunk_size > 512 || apron < 1 || apron > 4)
    return invalid_argument("zarr chunk source: chunk size must be 8..512 and apron 1..4");
  std::unique_ptr<ZarrChunkSource> s(new ZarrChunkSource());
  s->image_ = std::move(image);
  s->chunk_size_ = chunk_size;
  s->apron_ = apron;
  s->warnings_ = s->image_->warnings();
  const auto& levels = s->image_->levels();
  for (size_t l = 0; l < levels.size(); ++l) {
    LevelInfo li;
    bool ok = true;
    for (int a = 0; a < 3; ++a) {
      const double f = levels[l].factor[a];
      const uint32_t whole = static_cast<uint32_t>(std::lround(f));
      // The LOD traversal splits a chunk into 1 or 2 children per axis.
      const double prev = l == 0 ? 1.0 : double(s->levels_.back().downsample[a]);
      ok = ok && levels[l].dims[a] > 0 && whole >= 1 && near(f, whole) &&
           (l == 0 ? whole == 1 : near(f / prev, 1.0) || near(f / prev, 2.0));
      li.downsample[a] = whole;
      li.dims[a] = levels[l].dims[a];
      li.chunk_counts[a] = static_cast<uint32_t>((li.dims[a] + chunk_size - 1) / chunk_size);
    }
    if (l > 0 && li.downsample == s->levels_.back().downsample) ok = false;  // not coarser: no use to LOD
    if (!ok) {
      if (l == 0) {
        s->levels_.push_back(li);  // level 0 is level 0, whatever its transform says
        for (int a = 0; a < 3; ++a) s->levels_[0].downsample[a] = 1;
        continue;
      }
      s->warnings_.push_back("dataset '" + levels[l].path + "' is not a 2x step from the previous level (factors " +
                             std::to_string(levels[l].factor[0]) + ", " + std::to_string(levels[l].factor[1]) + ", " +
                             std::to_string(levels[l].factor[2]) + "); the out-of-core view uses the " +
                             std::to_string(l) + " levels before it");
      break;
    }
    s->levels_.push_back(li);
  }
  // Every payload read should find the zarr chunks of the previous one (and
  // of one read on another loader thread) still decoded: with slice-shaped
  // chunks (bioformats2raw writes 1x1024x1024) one payload spans edge chunks.
  const uint32_t edge = chunk_size + 2 * apron;
  for (size_t l = 0; l < s->levels_.size(); ++l) {
    zarr::ZarrArray& array = *levels[l].array;
    const zarr::ArrayMeta& m = array.meta();
    long double span = dtype_bytes(m.dtype);
    for (size_t d = 0; d < m.shape.size(); ++d) {
      const uint64_t c = m.chunks[d];
      // Chunks a box of `edge` voxels can touch along this axis (t and c axes
      // are read one voxel at a time: this over-counts them, harmlessly).
      const uint64_t extent = std::min<uint64_t>(m.shape[d], edge);
      span *= static_cast<long double>(std::min<uint64_t>((extent + c - 2) / c + 1, (m.shape[d] + c - 1) / c) * c);
    }
    array.raise_cache_bytes(static_cast<uint64_t>(std::min<long double>(2 * span, kMaxLevelCache)));
  }
  return s;
}

Status ZarrChunkSource::check_key(const ChunkKey& key) const {
  if (key.level >= levels_.size() || key.channel >= info().channels || key.timepoint >= info().timepoints)
    return not_found(image_->path() + ": no chunk at level " + std::to_string(key.level));
  const LevelInfo& li = levels_[key.level];
  if (key.x >= li.chunk_counts[0] || key.y >= li.chunk_counts[1] || key.z >= li.chunk_counts[2])
    return not_found(image_->path() + ": chunk outside level " + std::to_string(key.level));
  return Status();
}

Result<ChunkStats> ZarrChunkSource::stats(const ChunkKey& key) const {
  VXR_RETURN_IF_ERROR(check_key(key));
  {
    std::lock_guard lock(stats_mutex_);
    if (auto it = stats_.find(key); it != stats_.end()) return it->second;
  }
  return dtype_range(info().dtype);
}

Result<std::shared_ptr<const Chunk>> ZarrChunkSource::read(const ChunkKey& key) const {
  VXR_RETURN_IF_ERROR(check_key(key));
  const LevelInfo& li = levels_[key.level];
  const uint32_t item = dtype_bytes(info().dtype);
  const uint32_t edge = chunk_size_ + 2 * apron_;
  const std::array<uint32_t, 3> c{key.x, key.y, key.z};
  // The payload's first voxel (may be -apron) and the part of the level it
  // covers: [lo, hi). Payload voxels outside repeat the nearest edge voxel.
  std::array<int64_t, 3> first{};
  Box3 box;
  for (int a = 0; a < 3; ++a) {
    first[a] = int64_t(c[a]) * chunk_size_ - apron_;
    const int64_t dim = static_cast<int64_t>(li.dims[a]);
    const int64_t lo = std::clamp<int64_t>(first[a], 0, dim - 1);
    const int64_t hi = std::clamp<int64_t>(first[a] + edge, lo + 1, dim);
    box.origin[a] = static_cast<uint64_t>(lo);
    box.size[a] = static_cast<uint64_t>(hi - lo);
  }
  std::vector<uint8_t> region(box.voxels() * item);
  if (Status st = image_->read_region(key.level, key.channel, key.timepoint, box, region); !st) return st;

  auto chunk = std::make_shared<Chunk>();
  chunk->key = key;
  chunk->edge = edge;
  chunk->dtype = info().dtype;
  chunk->data.resize(uint64_t(edge) * edge * edge * item);
  std::array<std::vector<uint64_t>, 3> src;  // payload coordinate -> region coordinate, per axis
  for (int a = 0; a < 3; ++a) {
    src[a].resize(edge);
    const int64_t lo = static_cast<int64_t>(box.origin[a]), hi = lo + static_cast<int64_t>(box.size[a]);
    for (uint32_t p = 0; p < edge; ++p)
      src[a][p] = static_cast<uint64_t>(std::clamp<int64_t>(first[a] + p, lo, hi - 1) - lo);
  }
  uint8_t* out = chunk->data.data();
  for (uint32_t z = 0; z < edge; ++z)
    for (uint32_t y = 0; y < edge; ++y) {
      const uint8_t* row = region.data() + ((src[2][z] * box.size[1] + src[1][y]) * box.size[0]) * item;
      for (uint32_t x = 0; x < edge; ++x, out += item) std::memcpy(out, row + src[0][x] * item, item);
    }
  chunk->stats = payload_range(chunk->dtype, chunk->data);
  {
    std::lock_guard lock(stats_mutex_);
    if (stats_.size() < kStatsMemo) stats_[key] = chunk->stats;
  }
  return std::shared_ptr<const Chunk>(std::move(chunk));
}

}  // namespace vxr
