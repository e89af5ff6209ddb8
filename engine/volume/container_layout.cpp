#include "volume/container_layout.h"

#include <algorithm>
#include <cmath>
#include <cstring>
#include <limits>

#include "core/checked_math.h"
#include "volume/channel_display.h"

namespace vxr {

uint64_t ContainerLayout::chunks_in_level(uint32_t level) const {
  const auto& c = levels.at(level).chunk_counts;
  return checked_product({c[0], c[1], c[2]}).value_or(std::numeric_limits<uint64_t>::max());
}

uint64_t ContainerLayout::total_chunks() const {
  // Saturates instead of wrapping: a count no index can match (parse_header
  // refuses such headers; this keeps a layout built some other way honest).
  constexpr uint64_t kMax = std::numeric_limits<uint64_t>::max();
  uint64_t n = 0;
  for (uint32_t l = 0; l < levels.size(); ++l) n = checked_sum({n, chunks_in_level(l)}).value_or(kMax);
  return checked_product({n, info.channels, info.timepoints}).value_or(kMax);
}

bool ContainerLayout::contains(const ChunkKey& k) const {
  if (k.level >= levels.size() || k.channel >= info.channels || k.timepoint >= info.timepoints) return false;
  const auto& c = levels[k.level].chunk_counts;
  return k.x < c[0] && k.y < c[1] && k.z < c[2];
}

uint64_t ContainerLayout::index_position(const ChunkKey& k) const {
  uint64_t base = 0;
  for (uint32_t l = 0; l < k.level; ++l) base += chunks_in_level(l);
  base *= uint64_t(info.channels) * info.timepoints;
  const auto& c = levels[k.level].chunk_counts;
  return base + (((uint64_t(k.timepoint) * info.channels + k.channel) * c[2] + k.z) * c[1] + k.y) * c[0] + k.x;
}

ChunkKey ContainerLayout::key_at(uint64_t position) const {
  ChunkKey k;
  const uint64_t per = uint64_t(info.channels) * info.timepoints;
  while (k.level + 1 < levels.size() && position >= chunks_in_level(k.level) * per) position -= chunks_in_level(k.level++) * per;
  const auto& c = levels[k.level].chunk_counts;
  k.x = uint32_t(position % c[0]);
  position /= c[0];
  k.y = uint32_t(position % c[1]);
  position /= c[1];
  k.z = uint32_t(position % c[2]);
  position /= c[2];
  k.channel = uint32_t(position % info.channels);
  k.timepoint = uint32_t(position / info.channels);
  return k;
}

std::vector<LevelInfo> plan_pyramid(const std::array<uint64_t, 3>& dims, const std::array<double, 3>& voxel_size,
                                    uint32_t chunk_size) {
  std::vector<LevelInfo> levels;
  LevelInfo cur;
  cur.dims = dims;
  std::array<double, 3> vs = voxel_size;
  for (;;) {
    for (int a = 0; a < 3; ++a) cur.chunk_counts[a] = static_cast<uint32_t>((cur.dims[a] + chunk_size - 1) / chunk_size);
    levels.push_back(cur);
    if (cur.chunk_counts[0] == 1 && cur.chunk_counts[1] == 1 && cur.chunk_counts[2] == 1) break;
    if (levels.size() >= vxc::kMaxLevels) break;
    const double coarsest = std::max({vs[0], vs[1], vs[2]});
    LevelInfo next = cur;
    bool any = false;
    // Fine axes are halved (all of them once roughly isotropic); an axis down to one voxel stays.
    bool fine[3];
    for (int a = 0; a < 3; ++a) fine[a] = vs[a] * std::sqrt(2.0) < coarsest;
    const bool all_iso = !fine[0] && !fine[1] && !fine[2];
    for (int a = 0; a < 3; ++a) {
      if ((fine[a] || all_iso) && cur.dims[a] > 1) {
        next.dims[a] = (cur.dims[a] + 1) / 2;
        next.downsample[a] = cur.downsample[a] * 2;
        vs[a] *= 2;
        any = true;
      }
    }
    if (!any) break;
    cur = next;
  }
  return levels;
}

Result<ContainerLayout> make_layout(const VolumeInfo& info, uint32_t chunk_size, uint32_t apron,
                                    vxc::Downsample downsample, vxc::Codec codec) {
  if (chunk_size < 8 || chunk_size > 512) return invalid_argument("--chunk must be between 8 and 512 voxels");
  if (apron > 4) return invalid_argument("apron must be between 0 and 4 voxels");
  for (int a = 0; a < 3; ++a) {
    if (info.dims[a] == 0 || info.dims[a] > (uint64_t(1) << 40)) return invalid_argument("volume dims must be 1..2^40");
    if (!(info.voxel_size[a] > 0) || !std::isfinite(info.voxel_size[a]))
      return invalid_argument("voxel size must be three positive numbers");
  }
  if (info.channels == 0 || info.timepoints == 0) return invalid_argument("channels and timepoints must be >= 1");
  if (info.unit.size() > 15) return invalid_argument("unit '" + info.unit + "' is longer than 15 bytes");
  if (!info.channel_display.empty() && info.channel_display.size() != info.channels)
    return invalid_argument("channel display metadata for " + std::to_string(info.channel_display.size()) +
                            " channels, but the volume has " + std::to_string(info.channels));
  ContainerLayout layout;
  layout.info = info;
  layout.chunk_size = chunk_size;
  layout.apron = apron;
  layout.downsample = downsample;
  layout.codec = codec;
  layout.levels = plan_pyramid(info.dims, info.voxel_size, chunk_size);
  return layout;
}

namespace {

// Channel records a version-2 header holds for `info`: up to the last channel
// with display metadata, at most kMaxChannelRecords.
uint32_t channel_records(const VolumeInfo& info) {
  uint32_t n = 0;
  for (uint32_t c = 0; c < std::min<uint32_t>(info.channels, vxc::kMaxChannelRecords); ++c)
    if (!info.display(c).empty()) n = c + 1;
  return n;
}

uint64_t header_size(uint32_t version, uint32_t levels, uint32_t records) {
  const uint64_t base = sizeof(vxc::FileHeader) + uint64_t(levels) * sizeof(vxc::LevelRecord) + 8;
  return version < vxc::kVersionChannels ? base : base + sizeof(vxc::ChannelBlock) + uint64_t(records) * sizeof(vxc::ChannelRecord);
}

vxc::ChannelRecord channel_record(const ChannelDisplay& d) {
  vxc::ChannelRecord r;
  std::memset(&r, 0, sizeof r);
  std::memcpy(r.name, d.name.data(), std::min<size_t>(d.name.size(), sizeof r.name - 1));
  if (d.color) {
    r.flags |= vxc::kHasColor;
    for (int i = 0; i < 3; ++i) r.color[i] = (*d.color)[i];
  }
  if (d.window) {
    r.flags |= vxc::kHasWindow;
    r.window[0] = (*d.window)[0];
    r.window[1] = (*d.window)[1];
  }
  return r;
}

// A record back into display metadata; kCorrupt naming `what` and the channel when a field is impossible.
Result<ChannelDisplay> channel_display(const vxc::ChannelRecord& r, uint32_t channel, const std::string& what) {
  const std::string at = what + ": header channel record " + std::to_string(channel);
  if (r.flags & ~(vxc::kHasColor | vxc::kHasWindow)) return corrupt(at + " has unknown flags; the file is damaged");
  if (strnlen(r.name, sizeof r.name) == sizeof r.name) return corrupt(at + " has an unterminated name; the file is damaged");
  ChannelDisplay d;
  d.name = r.name;
  if (r.flags & vxc::kHasColor) d.color = Rgb8{r.color[0], r.color[1], r.color[2]};
  if (r.flags & vxc::kHasWindow) {
    if (!std::isfinite(r.window[0]) || !std::isfinite(r.window[1]) || !(r.window[1] > r.window[0]))
      return corrupt(at + " has a window that is not lo < hi; the file is damaged");
    d.window = std::array<double, 2>{r.window[0], r.window[1]};
  }
  return d;
}

}  // namespace

std::vector<uint8_t> serialize_header(const ContainerLayout& layout) {
  vxc::FileHeader h;
  std::memset(&h, 0, sizeof h);
  std::memcpy(h.magic, vxc::kFileMagic, 8);
  const uint32_t records = channel_records(layout.info);
  // Version 1 when there is nothing for the channel block: such files stay readable by older vxr.
  h.version = records ? vxc::kVersionChannels : 1;
  const uint32_t nlev = static_cast<uint32_t>(layout.levels.size());
  h.header_bytes = static_cast<uint32_t>(header_size(h.version, nlev, records));
  for (int a = 0; a < 3; ++a) {
    h.dims[a] = layout.info.dims[a];
    h.voxel_size[a] = layout.info.voxel_size[a];
    h.origin[a] = layout.info.origin[a];
  }
  h.channels = layout.info.channels;
  h.timepoints = layout.info.timepoints;
  std::memcpy(h.unit, layout.info.unit.data(), std::min<size_t>(layout.info.unit.size(), 15));
  h.chunk_size = layout.chunk_size;
  h.apron = layout.apron;
  h.levels = nlev;
  h.dtype = static_cast<uint8_t>(layout.info.dtype);
  h.downsample = static_cast<uint8_t>(layout.downsample);
  h.codec = static_cast<uint8_t>(layout.codec);
  std::vector<uint8_t> out(h.header_bytes);
  std::memcpy(out.data(), &h, sizeof h);
  for (uint32_t l = 0; l < nlev; ++l) {
    vxc::LevelRecord r;
    for (int a = 0; a < 3; ++a) {
      r.dims[a] = layout.levels[l].dims[a];
      r.chunk_counts[a] = layout.levels[l].chunk_counts[a];
      r.downsample[a] = layout.levels[l].downsample[a];
    }
    std::memcpy(out.data() + sizeof h + l * sizeof r, &r, sizeof r);
  }
  if (records) {
    uint8_t* at = out.data() + sizeof h + nlev * sizeof(vxc::LevelRecord);
    const vxc::ChannelBlock block{records, uint32_t(sizeof(vxc::ChannelRecord))};
    std::memcpy(at, &block, sizeof block);
    for (uint32_t c = 0; c < records; ++c) {
      const vxc::ChannelRecord r = channel_record(layout.info.display(c));
      std::memcpy(at + sizeof block + c * sizeof r, &r, sizeof r);
    }
  }
  const uint64_t sum = vxc::checksum(out.data(), out.size() - 8);
  std::memcpy(out.data() + out.size() - 8, &sum, 8);
  return out;
}

namespace {
constexpr uint64_t kMaxDim = uint64_t(1) << 40;     // make_layout's limit
constexpr uint64_t kMaxChunks = uint64_t(1) << 48;  // 80 bytes each: a 22 PB index
}  // namespace

Result<ContainerLayout> parse_header(std::span<const uint8_t> bytes, const std::string& what, uint64_t* header_bytes) {
  vxc::FileHeader h;
  if (bytes.size() < sizeof h) return corrupt(what + ": too short to be a .vxc container");
  std::memcpy(&h, bytes.data(), sizeof h);
  if (std::memcmp(h.magic, vxc::kFileMagic, 8) != 0) return corrupt(what + ": not a .vxc container (bad magic)");
  if (h.version == 0 || h.version > vxc::kVersion)
    return unsupported(what + ": container version " + std::to_string(h.version) +
                       " is newer than this vxr reads (" + std::to_string(vxc::kVersion) + "); update vxr");
  if (h.levels == 0 || h.levels > vxc::kMaxLevels)
    return corrupt(what + ": header is damaged (level count / header size)");
  // Version 2: the channel block after the level records says how many records follow.
  const uint64_t block_at = sizeof h + uint64_t(h.levels) * sizeof(vxc::LevelRecord);
  vxc::ChannelBlock block{0, uint32_t(sizeof(vxc::ChannelRecord))};
  if (h.version >= vxc::kVersionChannels) {
    if (bytes.size() < block_at + sizeof block) return corrupt(what + ": header is truncated");
    std::memcpy(&block, bytes.data() + block_at, sizeof block);
    if (block.record_bytes != sizeof(vxc::ChannelRecord) || block.count > vxc::kMaxChannelRecords ||
        block.count > h.channels)
      return corrupt(what + ": header is damaged (channel block)");
  }
  if (h.header_bytes != header_size(h.version, h.levels, block.count))
    return corrupt(what + ": header is damaged (level count / header size)");
  if (bytes.size() < h.header_bytes) return corrupt(what + ": header is truncated");
  uint64_t stored;
  std::memcpy(&stored, bytes.data() + h.header_bytes - 8, 8);
  if (stored != vxc::checksum(bytes.data(), h.header_bytes - 8))
    return corrupt(what + ": header checksum mismatch (the file is damaged)");
  if (h.dtype > static_cast<uint8_t>(DType::kF32) || h.downsample > 1 || h.codec > 3)
    return corrupt(what + ": header names an unknown dtype, downsample mode or codec");
  ContainerLayout L;
  for (int a = 0; a < 3; ++a) {
    L.info.dims[a] = h.dims[a];
    L.info.voxel_size[a] = h.voxel_size[a];
    L.info.origin[a] = h.origin[a];
  }
  L.info.dtype = static_cast<DType>(h.dtype);
  L.info.channels = h.channels;
  L.info.timepoints = h.timepoints;
  L.info.unit = std::string(h.unit, strnlen(h.unit, 15));
  L.chunk_size = h.chunk_size;
  L.apron = h.apron;
  L.downsample = static_cast<vxc::Downsample>(h.downsample);
  L.codec = static_cast<vxc::Codec>(h.codec);
  if (L.chunk_size < 8 || L.chunk_size > 512 || L.apron > 4 || !L.info.channels || !L.info.timepoints)
    return corrupt(what + ": header holds impossible chunk size, apron, channels or timepoints");
  // The writer's limits (make_layout): anything beyond them is damage, and
  // refusing it here keeps every count derived below far from overflow.
  for (int a = 0; a < 3; ++a) {
    if (h.dims[a] == 0 || h.dims[a] > kMaxDim)
      return corrupt(what + ": header claims absurd dimensions (" + std::to_string(h.dims[0]) + " x " +
                     std::to_string(h.dims[1]) + " x " + std::to_string(h.dims[2]) + "); the file is damaged");
    if (!(h.voxel_size[a] > 0) || !std::isfinite(h.voxel_size[a]))
      return corrupt(what + ": header holds a voxel size that is not a positive number; the file is damaged");
    if (!std::isfinite(h.origin[a]))
      return corrupt(what + ": header holds an origin that is not a finite number; the file is damaged");
  }
  for (uint32_t l = 0; l < h.levels; ++l) {
    vxc::LevelRecord r;
    std::memcpy(&r, bytes.data() + sizeof h + l * sizeof r, sizeof r);
    LevelInfo li;
    for (int a = 0; a < 3; ++a) {
      li.dims[a] = r.dims[a];
      li.chunk_counts[a] = r.chunk_counts[a];
      li.downsample[a] = r.downsample[a];
      if (r.dims[a] == 0 || r.dims[a] > kMaxDim || (r.dims[a] + L.chunk_size - 1) / L.chunk_size != r.chunk_counts[a] ||
          r.downsample[a] == 0)
        return corrupt(what + ": level " + std::to_string(l) + " record is inconsistent");
    }
    L.levels.push_back(li);
  }
  for (int a = 0; a < 3; ++a)
    if (L.levels[0].dims[a] != L.info.dims[a]) return corrupt(what + ": level 0 dims differ from the volume dims");
  if (block.count) {
    L.info.channel_display.resize(L.info.channels);
    for (uint32_t c = 0; c < block.count; ++c) {
      vxc::ChannelRecord r;
      std::memcpy(&r, bytes.data() + block_at + sizeof block + c * sizeof r, sizeof r);
      VXR_ASSIGN_OR_RETURN(L.info.channel_display[c], channel_display(r, c, what));
    }
  }
  // Every count the reader and verifier derive (index size, positions) must
  // fit comfortably in 64 bits; a real index this large would not fit on disk.
  const auto chunks = checked_product({L.total_chunks(), uint64_t(sizeof(vxc::IndexEntry))});
  if (!chunks || L.total_chunks() > kMaxChunks)
    return corrupt(what + ": header claims absurd dimensions (" + std::to_string(h.dims[0]) + " x " +
                   std::to_string(h.dims[1]) + " x " + std::to_string(h.dims[2]) + ", " +
                   std::to_string(L.info.channels) + " channels, " + std::to_string(L.info.timepoints) +
                   " timepoints: too many chunks); the file is damaged");
  *header_bytes = h.header_bytes;
  return L;
}

}  // namespace vxr
