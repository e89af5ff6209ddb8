#include "volume/dense_chunk_source.h"

#include <algorithm>
#include <array>
#include <cstring>

#include "volume/load_dense.h"

namespace vxr {

Result<std::shared_ptr<DenseChunkSource>> DenseChunkSource::create(std::vector<DenseVolume> channels,
                                                                   uint32_t chunk_size, uint32_t apron) {
  std::vector<std::vector<DenseVolume>> series;
  series.push_back(std::move(channels));
  return create_series(std::move(series), chunk_size, apron);
}

namespace {

// Min/max of a chunk's payload (apron included): the payload repeats edge
// voxels, so its range is the clamped box's.
ChunkStats payload_range(const DenseVolume& v, uint32_t x, uint32_t y, uint32_t z, uint32_t chunk_size, uint32_t apron) {
  double lo = 1e300, hi = -1e300;
  const uint32_t e = chunk_size + 2 * apron;
  const auto clampi = [](int64_t a, uint32_t n) { return uint32_t(std::clamp<int64_t>(a, 0, int64_t(n) - 1)); };
  for (uint32_t k = 0; k < e; ++k) {
    const uint32_t gz = clampi(int64_t(z) * chunk_size + k - apron, v.dims[2]);
    if (k > 0 && gz == clampi(int64_t(z) * chunk_size + k - 1 - apron, v.dims[2])) continue;
    for (uint32_t j = 0; j < e; ++j) {
      const uint32_t gy = clampi(int64_t(y) * chunk_size + j - apron, v.dims[1]);
      if (j > 0 && gy == clampi(int64_t(y) * chunk_size + j - 1 - apron, v.dims[1])) continue;
      for (uint32_t i = 0; i < e; ++i) {
        const uint32_t gx = clampi(int64_t(x) * chunk_size + i - apron, v.dims[0]);
        if (i > 0 && gx == clampi(int64_t(x) * chunk_size + i - 1 - apron, v.dims[0])) continue;
        const double val = v.value_at(gx, gy, gz);
        lo = std::min(lo, val);
        hi = std::max(hi, val);
      }
    }
  }
  return {lo, hi};
}

}  // namespace

Result<std::shared_ptr<DenseChunkSource>> DenseChunkSource::create_series(
    std::vector<std::vector<DenseVolume>> timepoints, uint32_t chunk_size, uint32_t apron) {
  if (timepoints.empty() || timepoints[0].empty()) return invalid_argument("in-memory volume: no channels");
  if (chunk_size == 0) return invalid_argument("in-memory volume: chunk size must be at least 1");
  const DenseVolume& first = timepoints[0][0];
  VXR_RETURN_IF_ERROR(check_renderable(first));
  for (const auto& channels : timepoints) {
    if (channels.size() != timepoints[0].size())
      return invalid_argument("in-memory volume: timepoints differ in their number of channels");
    for (const DenseVolume& c : channels)
      if (c.dims != first.dims || c.dtype != first.dtype)
        return invalid_argument("in-memory volume: channels or timepoints differ in size or data type");
  }
  std::shared_ptr<DenseChunkSource> s(new DenseChunkSource());
  s->cs_ = chunk_size;
  s->apron_ = apron;
  s->info_.dims = {first.dims[0], first.dims[1], first.dims[2]};
  s->info_.dtype = first.dtype;
  s->info_.channels = static_cast<uint32_t>(timepoints[0].size());
  s->info_.timepoints = static_cast<uint32_t>(timepoints.size());
  s->info_.voxel_size = first.voxel_size;
  s->info_.unit = first.unit;
  // Levels: 2x means until one chunk covers the top (the same dims for every timepoint).
  for (auto& channels : timepoints) {
    std::vector<std::vector<DenseVolume>> levels;
    levels.push_back(std::move(channels));
    while (true) {
      const DenseVolume& v = levels.back()[0];
      if (v.dims[0] <= chunk_size && v.dims[1] <= chunk_size && v.dims[2] <= chunk_size) break;
      std::vector<DenseVolume> next;
      for (const DenseVolume& c : levels.back()) next.push_back(shrink_by_two(c));
      levels.push_back(std::move(next));
    }
    s->data_.push_back(std::move(levels));
  }
  std::array<uint32_t, 3> ds{1, 1, 1};
  for (const auto& level : s->data_[0]) {
    const DenseVolume& v = level[0];
    LevelInfo li;
    for (int a = 0; a < 3; ++a) {
      li.dims[a] = v.dims[a];
      li.chunk_counts[a] = (v.dims[a] + chunk_size - 1) / chunk_size;
      li.downsample[a] = ds[a];
    }
    s->levels_.push_back(li);
    for (int a = 0; a < 3; ++a)
      if (v.dims[a] > 1) ds[a] *= 2;
  }
  size_t total = 0;
  for (const LevelInfo& li : s->levels_) {
    s->first_chunk_.push_back(total);
    total += size_t(li.chunk_counts[0]) * li.chunk_counts[1] * li.chunk_counts[2];
  }
  // Min/max of every payload, for the traversal's empty-space test.
  s->stats_.assign(s->info_.timepoints,
                   std::vector<std::vector<ChunkStats>>(s->info_.channels, std::vector<ChunkStats>(total)));
  for (uint32_t t = 0; t < s->info_.timepoints; ++t)
    for (uint32_t c = 0; c < s->info_.channels; ++c)
      for (uint32_t l = 0; l < s->levels_.size(); ++l) {
        const LevelInfo& li = s->levels_[l];
        for (uint32_t z = 0; z < li.chunk_counts[2]; ++z)
          for (uint32_t y = 0; y < li.chunk_counts[1]; ++y)
            for (uint32_t x = 0; x < li.chunk_counts[0]; ++x)
              s->stats_[t][c][s->chunk_index({l, x, y, z, c, t})] =
                  payload_range(s->data_[t][l][c], x, y, z, chunk_size, apron);
      }
  return s;
}

Status DenseChunkSource::check_key(const ChunkKey& k) const {
  if (k.level >= levels_.size() || k.channel >= info_.channels || k.timepoint >= info_.timepoints)
    return not_found("in-memory volume: no chunk at level " + std::to_string(k.level) + " channel " +
                     std::to_string(k.channel) + " timepoint " + std::to_string(k.timepoint));
  const LevelInfo& li = levels_[k.level];
  if (k.x >= li.chunk_counts[0] || k.y >= li.chunk_counts[1] || k.z >= li.chunk_counts[2])
    return not_found("in-memory volume: chunk (" + std::to_string(k.x) + ", " + std::to_string(k.y) + ", " +
                     std::to_string(k.z) + ") lies outside level " + std::to_string(k.level));
  return Status::ok();
}

size_t DenseChunkSource::chunk_index(const ChunkKey& k) const {
  const LevelInfo& li = levels_[k.level];
  return first_chunk_[k.level] + (size_t(k.z) * li.chunk_counts[1] + k.y) * li.chunk_counts[0] + k.x;
}

Result<ChunkStats> DenseChunkSource::stats(const ChunkKey& key) const {
  VXR_RETURN_IF_ERROR(check_key(key));
  return stats_[key.timepoint][key.channel][chunk_index(key)];
}

void DenseChunkSource::cut(const ChunkKey& k, Chunk& c) const {
  const DenseVolume& v = data_[k.timepoint][k.level][k.channel];
  c.key = k;
  c.edge = cs_ + 2 * apron_;
  c.dtype = info_.dtype;
  const uint32_t b = dtype_bytes(info_.dtype), e = c.edge;
  c.data.resize(uint64_t(e) * e * e * b);
  auto clampi = [](int64_t a, uint32_t n) { return uint64_t(std::clamp<int64_t>(a, 0, int64_t(n) - 1)); };
  for (uint32_t z = 0; z < e; ++z)
    for (uint32_t y = 0; y < e; ++y) {
      const uint64_t gz = clampi(int64_t(k.z) * cs_ + z - apron_, v.dims[2]);
      const uint64_t gy = clampi(int64_t(k.y) * cs_ + y - apron_, v.dims[1]);
      const uint8_t* row = &v.data[(gz * v.dims[1] + gy) * v.dims[0] * b];
      uint8_t* dst = &c.data[(uint64_t(z) * e + y) * e * b];
      for (uint32_t x = 0; x < e; ++x) {
        const uint64_t gx = clampi(int64_t(k.x) * cs_ + x - apron_, v.dims[0]);
        std::memcpy(dst + uint64_t(x) * b, row + gx * b, b);
      }
    }
}

Result<std::shared_ptr<const Chunk>> DenseChunkSource::read(const ChunkKey& key) const {
  VXR_RETURN_IF_ERROR(check_key(key));
  auto c = std::make_shared<Chunk>();
  cut(key, *c);
  c->stats = stats_[key.timepoint][key.channel][chunk_index(key)];
  return std::shared_ptr<const Chunk>(std::move(c));
}

Status DenseChunkSource::set_channel_display(std::vector<ChannelDisplay> display) {
  if (!display.empty() && display.size() != info_.channels)
    return invalid_argument("channel display metadata for " + std::to_string(display.size()) + " channels, but the volume has " +
                            std::to_string(info_.channels));
  info_.channel_display = std::move(display);
  return Status::ok();
}

}  // namespace vxr
