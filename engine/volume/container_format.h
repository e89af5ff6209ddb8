// On-disk layout of the .vxc container, versions 1 and 2 (spec: docs/container-format.md).
//
// All integers little-endian, all sizes and offsets 64-bit. The structs below
// are the exact byte layout (naturally aligned, no implicit padding; checked by
// static_assert), written and read with memcpy on little-endian hosts.
//
//   [FileHeader][LevelRecord x levels][u64 header checksum]                        version 1
//   [FileHeader][LevelRecord x levels][ChannelBlock][ChannelRecord x n][u64 header checksum]  version 2
//   [RecordHeader][payload] ... appended in any order, one per chunk
//   [IndexHeader][IndexEntry x count]
//   [Footer]
#pragma once

#include <bit>
#include <cstdint>
#include <cstring>

static_assert(std::endian::native == std::endian::little, "the .vxc reader/writer assumes a little-endian host");

namespace vxr::vxc {

// The newest version this code reads. The writer writes version 1 unless the
// volume has channel display metadata (names, colours, windows): version 2
// adds the channel block, so files without it stay readable by older vxr.
constexpr uint32_t kVersion = 2;
constexpr uint32_t kVersionChannels = 2;  // the first version with a channel block
// Channel records kept at most (channels past it have none): bounds the header.
constexpr uint32_t kMaxChannelRecords = 1024;
constexpr uint32_t kMaxLevels = 48;
inline constexpr char kFileMagic[8] = {'V', 'X', 'C', 'V', 'O', 'L', '\r', '\n'};
inline constexpr char kRecordMagic[8] = {'V', 'X', 'C', 'C', 'H', 'U', 'N', 'K'};
inline constexpr char kIndexMagic[8] = {'V', 'X', 'C', 'I', 'N', 'D', 'E', 'X'};
inline constexpr char kFooterMagic[8] = {'V', 'X', 'C', 'E', 'N', 'D', '\r', '\n'};

// How a chunk's payload is stored.
enum class Codec : uint8_t {
  kRaw = 0,         // payload is the voxels as they are
  kLz4 = 1,         // LZ4 block of the voxels
  kShuffleLz4 = 2,  // byte-shuffled (byte b of every voxel together), then LZ4
  kUniform = 3,     // no payload: every voxel equals `min` (== `max`)
};

enum class Downsample : uint8_t { kMean = 0, kMax = 1 };

struct FileHeader {
  char magic[8];
  uint32_t version;
  uint32_t header_bytes;  // FileHeader + levels * LevelRecord + 8 (checksum)
  uint64_t dims[3];
  uint32_t channels;
  uint32_t timepoints;
  double voxel_size[3];
  char unit[16];  // NUL-padded
  uint32_t chunk_size;
  uint32_t apron;
  uint32_t levels;
  uint8_t dtype;       // vxr::DType
  uint8_t downsample;  // Downsample
  uint8_t codec;       // the codec the writer preferred for data chunks (informational)
  uint8_t reserved0;
  double origin[3];  // physical position of voxel (0, 0, 0); files written before it hold zeros here
};
static_assert(sizeof(FileHeader) == 128);

struct LevelRecord {
  uint64_t dims[3];
  uint32_t chunk_counts[3];
  uint32_t downsample[3];
};
static_assert(sizeof(LevelRecord) == 48);

// Version 2, after the level records: how many ChannelRecords follow.
struct ChannelBlock {
  uint32_t count;         // records for channels 0..count-1; count <= min(channels, kMaxChannelRecords)
  uint32_t record_bytes;  // sizeof(ChannelRecord)
};
static_assert(sizeof(ChannelBlock) == 8);

// One channel's display metadata (VolumeInfo::channel_display).
enum ChannelFlags : uint8_t { kHasColor = 1, kHasWindow = 2 };
struct ChannelRecord {
  char name[64];      // UTF-8, NUL-padded; at most 63 bytes (empty: none)
  uint8_t color[3];   // RGB when flags has kHasColor, else zero
  uint8_t flags;      // ChannelFlags
  uint32_t reserved0;
  double window[2];   // display lo < hi in data units when flags has kHasWindow, else zero
  uint64_t reserved1;
};
static_assert(sizeof(ChannelRecord) == 96);

// The largest header any version holds: what a reader reads before parsing it.
constexpr uint64_t kMaxHeaderBytes =
    sizeof(FileHeader) + kMaxLevels * sizeof(LevelRecord) + sizeof(ChannelBlock) + kMaxChannelRecords * sizeof(ChannelRecord) + 8;

struct RecordHeader {
  char magic[8];
  uint32_t level, x, y, z, channel, timepoint;
  uint8_t codec;
  uint8_t dtype;
  uint16_t reserved0;
  uint32_t reserved1;
  uint64_t raw_size;     // decoded payload bytes: edge^3 * dtype bytes
  uint64_t stored_size;  // bytes that follow this header (0 for kUniform)
  double min, max;       // over the whole payload (interior and apron)
  uint64_t payload_checksum;  // XXH64(seed 0) of the stored bytes (0 for kUniform)
  uint64_t reserved2;
  uint64_t header_checksum;  // XXH64 of the 88 bytes before it
};
static_assert(sizeof(RecordHeader) == 96);

struct IndexHeader {
  char magic[8];
  uint64_t count;
};
static_assert(sizeof(IndexHeader) == 16);

struct IndexEntry {
  uint32_t level, x, y, z, channel, timepoint;
  uint8_t codec;
  uint8_t reserved[7];
  uint64_t offset;  // of the chunk's RecordHeader
  uint64_t raw_size;
  uint64_t stored_size;
  double min, max;
  uint64_t payload_checksum;
};
static_assert(sizeof(IndexEntry) == 80);

struct Footer {
  uint64_t index_offset;
  uint64_t index_bytes;  // IndexHeader + count * IndexEntry
  uint64_t chunk_count;
  uint64_t index_checksum;   // XXH64 of the index bytes
  uint64_t header_checksum;  // copy of the header's checksum
  uint64_t file_bytes;       // the whole file, footer included
  uint64_t footer_checksum;  // XXH64 of the 48 bytes before it
  char magic[8];
};
static_assert(sizeof(Footer) == 64);

// XXH64 with seed 0.
uint64_t checksum(const void* data, size_t bytes);

}  // namespace vxr::vxc
