#include "volume/pyramid_builder.h"

#include <algorithm>
#include <atomic>
#include <chrono>
#include <cmath>
#include <cstring>
#include <filesystem>
#include <future>
#include <thread>

#include "core/trace.h"
#include "volume/chunk_codec.h"
#include "volume/container_writer.h"

namespace vxr {
namespace {

struct Tile {
  uint32_t level = 0, channel = 0, timepoint = 0;
  std::array<uint32_t, 3> c0{}, c1{};  // chunk range [c0, c1)
};

// A byte buffer that is not zero-filled on allocation (tiles are overwritten
// whole), recycled between tiles to avoid page-faulting fresh memory.
struct Buffer {
  std::unique_ptr<uint8_t[]> bytes;
  size_t size = 0, capacity = 0;
  uint8_t* data() { return bytes.get(); }
  const uint8_t* data() const { return bytes.get(); }
  std::span<uint8_t> span() { return {bytes.get(), size}; }
};

class BufferPool {
 public:
  Buffer acquire(size_t n) {
    {
      std::lock_guard<std::mutex> lock(m_);
      for (size_t i = 0; i < free_.size(); ++i)
        if (free_[i].capacity >= n) {
          Buffer b = std::move(free_[i]);
          free_.erase(free_.begin() + static_cast<std::ptrdiff_t>(i));
          b.size = n;
          return b;
        }
    }
    Buffer b;
    b.bytes.reset(new uint8_t[n]);
    b.size = b.capacity = n;
    return b;
  }
  void release(Buffer&& b) {
    if (!b.bytes) return;
    std::lock_guard<std::mutex> lock(m_);
    free_.push_back(std::move(b));
    // Keep the two largest: one tile being encoded, one being produced.
    std::sort(free_.begin(), free_.end(), [](const Buffer& a, const Buffer& c) { return a.capacity > c.capacity; });
    if (free_.size() > 2) free_.resize(2);
  }

 private:
  std::mutex m_;
  std::vector<Buffer> free_;
};

// Voxels of one level inside `box`, x fastest; or, when `uniform`, no data
// and every voxel equals `value`.
struct Region {
  Box3 box;
  Buffer data;
  bool uniform = false;
  double value = 0;
};

// True when all `n` voxels of `bpv` bytes at `p` are bitwise equal.
bool all_equal(const uint8_t* p, size_t bytes, uint32_t bpv) {
  return bytes <= bpv || std::memcmp(p, p + bpv, bytes - bpv) == 0;
}

// Runs fn(i) for i in [0, n) on `threads` threads; returns the first error.
template <typename F>
Status parallel_for(uint32_t threads, size_t n, F&& fn) {
  std::atomic<size_t> next{0};
  std::atomic<bool> failed{false};
  Status first;
  std::mutex m;
  auto work = [&] {
    for (;;) {
      const size_t i = next++;
      if (i >= n || failed) return;
      Status s = fn(i);
      if (!s) {
        std::lock_guard<std::mutex> lock(m);
        if (!failed) first = s;
        failed = true;
      }
    }
  };
  const uint32_t t = static_cast<uint32_t>(std::min<size_t>(std::max(1u, threads), n));
  std::vector<std::thread> pool;
  for (uint32_t k = 1; k < t; ++k) pool.emplace_back(work);
  work();
  for (auto& th : pool) th.join();
  return first;
}

Box3 region_box(const ContainerLayout& L, const Tile& t) {
  Box3 b;
  const auto& dims = L.levels[t.level].dims;
  for (int a = 0; a < 3; ++a) {
    const int64_t lo = int64_t(t.c0[a]) * L.chunk_size - L.apron;
    const uint64_t hi = uint64_t(t.c1[a]) * L.chunk_size + L.apron;
    b.origin[a] = uint64_t(std::max<int64_t>(lo, 0));
    b.size[a] = std::min(hi, dims[a]) - b.origin[a];
  }
  return b;
}

uint64_t interior_bytes(const ContainerLayout& L, const ChunkKey& k) {
  const auto& dims = L.levels[k.level].dims;
  const uint32_t c[3] = {k.x, k.y, k.z};
  uint64_t v = dtype_bytes(L.info.dtype);
  for (int a = 0; a < 3; ++a) v *= std::min<uint64_t>(L.chunk_size, dims[a] - uint64_t(c[a]) * L.chunk_size);
  return v;
}

std::vector<Tile> plan_tiles(const ContainerLayout& L, uint32_t level, uint32_t channel, uint32_t timepoint,
                             uint64_t limit_bytes, uint64_t multiplier) {
  const auto& counts = L.levels[level].chunk_counts;
  const uint64_t bpv = dtype_bytes(L.info.dtype);
  const uint64_t ext_z = L.chunk_size + 2 * L.apron;
  auto bytes = [&](uint32_t tx, uint32_t ty) {
    return (uint64_t(tx) * L.chunk_size + 2 * L.apron) * (uint64_t(ty) * L.chunk_size + 2 * L.apron) * ext_z * bpv *
           multiplier;
  };
  uint32_t tx = counts[0], ty = counts[1];
  while (bytes(tx, ty) > limit_bytes && ty > 1) ty = (ty + 1) / 2;
  while (bytes(tx, ty) > limit_bytes && tx > 1) tx = (tx + 1) / 2;
  std::vector<Tile> tiles;
  for (uint32_t z = 0; z < counts[2]; ++z)
    for (uint32_t y = 0; y < counts[1]; y += ty)
      for (uint32_t x = 0; x < counts[0]; x += tx) {
        Tile t;
        t.level = level;
        t.channel = channel;
        t.timepoint = timepoint;
        t.c0 = {x, y, z};
        t.c1 = {std::min(x + tx, counts[0]), std::min(y + ty, counts[1]), z + 1};
        tiles.push_back(t);
      }
  return tiles;
}

template <typename T>
void downsample_typed(const uint8_t* in, const Box3& I, uint8_t* out, const Box3& O, const std::array<uint32_t, 3>& f,
                      const std::array<uint64_t, 3>& prev_dims, vxc::Downsample mode) {
  const uint64_t ix = I.size[0], iy = I.size[1];
  std::vector<uint64_t> xs0(O.size[0]), xs1(O.size[0]);
  for (uint64_t x = 0; x < O.size[0]; ++x) {
    const uint64_t g = (O.origin[0] + x) * f[0];
    xs0[x] = g - I.origin[0];
    xs1[x] = (f[0] == 2 ? std::min(g + 1, prev_dims[0] - 1) : g) - I.origin[0];
  }
  const double n = double(f[0] * f[1] * f[2]);
  for (uint64_t z = 0; z < O.size[2]; ++z) {
    const uint64_t gz = (O.origin[2] + z) * f[2];
    const uint64_t zs[2] = {gz - I.origin[2], (f[2] == 2 ? std::min(gz + 1, prev_dims[2] - 1) : gz) - I.origin[2]};
    for (uint64_t y = 0; y < O.size[1]; ++y) {
      const uint64_t gy = (O.origin[1] + y) * f[1];
      const uint64_t ys[2] = {gy - I.origin[1], (f[1] == 2 ? std::min(gy + 1, prev_dims[1] - 1) : gy) - I.origin[1]};
      T* dst = reinterpret_cast<T*>(out) + (z * O.size[1] + y) * O.size[0];
      for (uint64_t x = 0; x < O.size[0]; ++x) {
        const uint64_t xx[2] = {xs0[x], xs1[x]};
        double sum = 0;
        T best = std::numeric_limits<T>::lowest();
        bool nan = false;
        for (uint32_t dz = 0; dz < f[2]; ++dz)
          for (uint32_t dy = 0; dy < f[1]; ++dy)
            for (uint32_t dx = 0; dx < f[0]; ++dx) {
              T v;
              std::memcpy(&v, in + ((zs[dz] * iy + ys[dy]) * ix + xx[dx]) * sizeof(T), sizeof(T));
              sum += double(v);
              if constexpr (std::is_floating_point_v<T>) nan |= std::isnan(v);
              best = v > best ? v : best;
            }
        if (mode == vxc::Downsample::kMax) {
          dst[x] = best;
        } else if constexpr (std::is_floating_point_v<T>) {
          dst[x] = static_cast<T>(sum / n);
        } else {
          dst[x] = static_cast<T>(std::floor(sum / n + 0.5));
        }
        (void)nan;
      }
    }
  }
}

void downsample(DType dtype, const uint8_t* in, const Box3& I, uint8_t* out, const Box3& O,
                const std::array<uint32_t, 3>& f, const std::array<uint64_t, 3>& prev_dims, vxc::Downsample mode) {
  switch (dtype) {
    case DType::kU8: return downsample_typed<uint8_t>(in, I, out, O, f, prev_dims, mode);
    case DType::kI8: return downsample_typed<int8_t>(in, I, out, O, f, prev_dims, mode);
    case DType::kU16: return downsample_typed<uint16_t>(in, I, out, O, f, prev_dims, mode);
    case DType::kI16: return downsample_typed<int16_t>(in, I, out, O, f, prev_dims, mode);
    case DType::kU32: return downsample_typed<uint32_t>(in, I, out, O, f, prev_dims, mode);
    case DType::kI32: return downsample_typed<int32_t>(in, I, out, O, f, prev_dims, mode);
    case DType::kF32: return downsample_typed<float>(in, I, out, O, f, prev_dims, mode);
  }
}

class Builder {
 public:
  Builder(SlabSource& src, ContainerWriter& w, const ImportOptions& o, Progress* p)
      : src_(src), w_(w), L_(w.layout()), opt_(o), progress_(p) {}

  Status run() {
    const uint64_t scratch = uint64_t(std::max(1u, opt_.threads)) * L_.payload_bytes() * 5;
    const uint64_t avail = opt_.memory_bytes > scratch ? opt_.memory_bytes - scratch : 0;
    for (uint32_t t = 0; t < L_.info.timepoints; ++t)
      for (uint32_t c = 0; c < L_.info.channels; ++c)
        for (uint32_t l = 0; l < L_.levels.size(); ++l) {
          // Tiles alive at once: one encoding, one being produced, one recycled in the
          // pool; above level 0 also the gathered input (up to 8x the tile).
          uint64_t mult = 3;
          if (l > 0) {
            uint64_t fprod = 1;
            for (int a = 0; a < 3; ++a) fprod *= L_.levels[l].downsample[a] / L_.levels[l - 1].downsample[a];
            mult = 3 + fprod;
          }
          std::vector<Tile> todo;
          for (const Tile& tile : plan_tiles(L_, l, c, t, avail, mult))
            if (!missing_keys(tile).empty()) todo.push_back(tile);
          VXR_RETURN_IF_ERROR(run_tiles(todo));
        }
    return Status::ok();
  }

 private:
  std::vector<ChunkKey> missing_keys(const Tile& t) const {
    std::vector<ChunkKey> keys;
    for (uint32_t z = t.c0[2]; z < t.c1[2]; ++z)
      for (uint32_t y = t.c0[1]; y < t.c1[1]; ++y)
        for (uint32_t x = t.c0[0]; x < t.c1[0]; ++x) {
          ChunkKey k{t.level, x, y, z, t.channel, t.timepoint};
          if (!w_.has(k)) keys.push_back(k);
        }
    return keys;
  }

  Status run_tiles(const std::vector<Tile>& tiles) {
    if (tiles.empty()) return Status::ok();
    auto produce = [this](const Tile& t) { return produce_region(t); };
    std::future<Result<Region>> next = std::async(std::launch::async, produce, tiles[0]);
    for (size_t i = 0; i < tiles.size(); ++i) {
      Result<Region> region = next.get();
      if (i + 1 < tiles.size()) next = std::async(std::launch::async, produce, tiles[i + 1]);
      if (!region) return region.status();  // `next` joins in its destructor
      Status s = encode_tile(tiles[i], *region);
      pool_.release(std::move(region->data));
      VXR_RETURN_IF_ERROR(s);
    }
    return Status::ok();
  }

  Result<Region> produce_region(const Tile& t) {
    VXR_TRACE_SCOPE("pyramid.produce_region");
    Region r;
    r.box = region_box(L_, t);
    const uint32_t bpv = dtype_bytes(L_.info.dtype);
    if (t.level == 0) {
      r.data = pool_.acquire(r.box.voxels() * bpv);
      if (Status s = src_.read_region(t.channel, t.timepoint, r.box, r.data.span()); !s) {
        pool_.release(std::move(r.data));
        return s;
      }
      mark_uniform(r);
      return r;
    }
    // Level l from level l-1's chunks, read back from the file being written.
    const uint32_t pl = t.level - 1;
    const LevelInfo& prev = L_.levels[pl];
    std::array<uint32_t, 3> f;
    Box3 in;
    std::array<uint32_t, 3> k0, k1;
    for (int a = 0; a < 3; ++a) {
      f[a] = L_.levels[t.level].downsample[a] / prev.downsample[a];
      in.origin[a] = r.box.origin[a] * f[a];
      in.size[a] = std::min((r.box.origin[a] + r.box.size[a]) * f[a], prev.dims[a]) - in.origin[a];
      k0[a] = static_cast<uint32_t>(in.origin[a] / L_.chunk_size);
      k1[a] = static_cast<uint32_t>((in.origin[a] + in.size[a] - 1) / L_.chunk_size) + 1;
    }
    // Fast path: every contributing chunk is uniform with one value, so is the result.
    bool uniform = true;
    double value = 0;
    bool first = true;
    for (uint32_t z = k0[2]; z < k1[2] && uniform; ++z)
      for (uint32_t y = k0[1]; y < k1[1] && uniform; ++y)
        for (uint32_t x = k0[0]; x < k1[0] && uniform; ++x) {
          VXR_ASSIGN_OR_RETURN(ChunkStats s, w_.stats({pl, x, y, z, t.channel, t.timepoint}));
          if (!(s.min == s.max) || (!first && std::memcmp(&s.min, &value, sizeof value) != 0)) uniform = false;
          value = s.min;
          first = false;
        }
    if (uniform) {
      r.uniform = true;
      r.value = value;
      return r;
    }
    Buffer input = pool_.acquire(in.voxels() * bpv);
    const uint64_t C = L_.chunk_size, A = L_.apron;
    for (uint32_t z = k0[2]; z < k1[2]; ++z)
      for (uint32_t y = k0[1]; y < k1[1]; ++y)
        for (uint32_t x = k0[0]; x < k1[0]; ++x) {
          auto chunk_r = w_.read({pl, x, y, z, t.channel, t.timepoint});
          if (!chunk_r) {
            pool_.release(std::move(input));
            return chunk_r.status();
          }
          const auto& chunk = *chunk_r;
          const uint64_t E = chunk->edge;
          const uint64_t cc[3] = {x, y, z};
          uint64_t lo[3], hi[3];
          for (int a = 0; a < 3; ++a) {
            lo[a] = std::max(cc[a] * C, in.origin[a]);
            hi[a] = std::min({(cc[a] + 1) * C, in.origin[a] + in.size[a], prev.dims[a]});
          }
          for (uint64_t gz = lo[2]; gz < hi[2]; ++gz)
            for (uint64_t gy = lo[1]; gy < hi[1]; ++gy) {
              const uint8_t* s =
                  chunk->data.data() + (((gz - cc[2] * C + A) * E + (gy - cc[1] * C + A)) * E + (lo[0] - cc[0] * C + A)) * bpv;
              uint8_t* d = input.data() +
                           (((gz - in.origin[2]) * in.size[1] + (gy - in.origin[1])) * in.size[0] + (lo[0] - in.origin[0])) * bpv;
              std::memcpy(d, s, (hi[0] - lo[0]) * bpv);
            }
        }
    r.data = pool_.acquire(r.box.voxels() * bpv);
    downsample(L_.info.dtype, input.data(), in, r.data.data(), r.box, f, prev.dims, L_.downsample);
    pool_.release(std::move(input));
    mark_uniform(r);
    return r;
  }

  // A region whose voxels are all one value needs no per-chunk work: every
  // chunk cut from it is uniform (apron included, as edges repeat inside it).
  void mark_uniform(Region& r) {
    const uint32_t bpv = dtype_bytes(L_.info.dtype);
    if (r.data.size < bpv || !all_equal(r.data.data(), r.data.size, bpv)) return;
    const ChunkStats st = payload_stats(L_.info.dtype, {r.data.data(), bpv});
    if (std::isnan(st.min)) return;
    r.uniform = true;
    r.value = st.min;
    pool_.release(std::move(r.data));
    r.data = Buffer();
  }

  // Copies chunk `k`'s payload (interior + apron, clamped at the level's edges) out of `r`.
  void extract(const Region& r, const ChunkKey& k, std::vector<uint8_t>& out) const {
    const uint32_t bpv = dtype_bytes(L_.info.dtype);
    const uint64_t E = L_.edge();
    out.resize(E * E * E * bpv);
    const auto& dims = L_.levels[k.level].dims;
    const uint32_t kc[3] = {k.x, k.y, k.z};
    std::vector<uint64_t> idx[3];
    for (int a = 0; a < 3; ++a) {
      idx[a].resize(E);
      for (uint64_t i = 0; i < E; ++i) {
        const int64_t g = int64_t(kc[a]) * L_.chunk_size - L_.apron + int64_t(i);
        const uint64_t cl = uint64_t(std::clamp<int64_t>(g, 0, int64_t(dims[a]) - 1));
        idx[a][i] = cl - r.box.origin[a];
      }
    }
    // Longest run of consecutive x indices: copy it with memcpy, the clamped ends voxel by voxel.
    uint64_t run0 = 0, run1 = E;
    while (run0 + 1 < E && idx[0][run0 + 1] == idx[0][run0]) ++run0;
    while (run1 - 1 > run0 && idx[0][run1 - 2] == idx[0][run1 - 1]) --run1;
    for (uint64_t z = 0; z < E; ++z)
      for (uint64_t y = 0; y < E; ++y) {
        const uint8_t* src = r.data.data() + ((idx[2][z] * r.box.size[1] + idx[1][y]) * r.box.size[0]) * bpv;
        uint8_t* dst = out.data() + ((z * E + y) * E) * bpv;
        std::memcpy(dst + run0 * bpv, src + idx[0][run0] * bpv, (run1 - run0) * bpv);
        for (uint64_t x = 0; x < run0; ++x) std::memcpy(dst + x * bpv, src + idx[0][x] * bpv, bpv);
        for (uint64_t x = run1; x < E; ++x) std::memcpy(dst + x * bpv, src + idx[0][x] * bpv, bpv);
      }
  }

  Status encode_tile(const Tile& t, const Region& r) {
    VXR_TRACE_SCOPE("pyramid.encode_tile");
    const std::vector<ChunkKey> keys = missing_keys(t);
    const vxc::Codec codec = L_.codec;
    return parallel_for(opt_.threads, keys.size(), [&](size_t i) -> Status {
      const ChunkKey& k = keys[i];
      EncodedChunk enc;
      if (r.uniform) {
        enc.key = k;
        enc.codec = vxc::Codec::kUniform;
        enc.stats = {r.value, r.value};
        enc.raw_size = L_.payload_bytes();
      } else {
        thread_local std::vector<uint8_t> payload;
        extract(r, k, payload);
        enc = encode_chunk(k, L_.info.dtype, payload, codec);
      }
      VXR_RETURN_IF_ERROR(w_.append(enc));
      if (progress_) progress_->advance(interior_bytes(L_, k));
      return Status::ok();
    });
  }

  SlabSource& src_;
  ContainerWriter& w_;
  const ContainerLayout& L_;
  ImportOptions opt_;
  Progress* progress_;
  BufferPool pool_;
};

}  // namespace

Result<ContainerLayout> import_layout(const VolumeInfo& info, const ImportOptions& options) {
  const vxc::Codec codec = options.codec.value_or(default_codec(info.dtype));
  return make_layout(info, options.chunk_size, options.apron, options.downsample, codec);
}

uint64_t pyramid_work_bytes(const ContainerLayout& L) {
  uint64_t total = 0;
  for (const auto& li : L.levels) total += li.dims[0] * li.dims[1] * li.dims[2];
  return total * dtype_bytes(L.info.dtype) * L.info.channels * L.info.timepoints;
}

std::optional<uint64_t> parse_byte_size(const std::string& text) {
  if (text.empty()) return std::nullopt;
  size_t pos = 0;
  double v = 0;
  try {
    v = std::stod(text, &pos);
  } catch (...) {
    return std::nullopt;
  }
  std::string suffix = text.substr(pos);
  for (char& ch : suffix) ch = static_cast<char>(std::toupper(static_cast<unsigned char>(ch)));
  if (!suffix.empty() && suffix.back() == 'B') suffix.pop_back();
  if (suffix.size() == 2 && suffix[1] == 'I') suffix.pop_back();  // "MiB"
  double mult = 1;
  if (suffix == "K") mult = 1024.0;
  else if (suffix == "M") mult = 1024.0 * 1024;
  else if (suffix == "G") mult = 1024.0 * 1024 * 1024;
  else if (suffix == "T") mult = 1024.0 * 1024 * 1024 * 1024;
  else if (!suffix.empty()) return std::nullopt;
  if (!(v > 0) || !std::isfinite(v)) return std::nullopt;
  return static_cast<uint64_t>(v * mult);
}

Result<ImportSummary> build_container(SlabSource& source, const std::string& path, const ImportOptions& options,
                                      Progress* progress) {
  const auto start = std::chrono::steady_clock::now();
  const VolumeInfo& info = source.info();
  VXR_ASSIGN_OR_RETURN(ContainerLayout layout, import_layout(info, options));
  VXR_ASSIGN_OR_RETURN(auto writer, ContainerWriter::create(path, layout, options.resume));
  if (progress) {
    uint64_t done = 0;
    for (uint32_t t = 0; t < info.timepoints; ++t)
      for (uint32_t c = 0; c < info.channels; ++c)
        for (uint32_t l = 0; l < layout.levels.size(); ++l) {
          const auto& n = layout.levels[l].chunk_counts;
          for (uint32_t z = 0; z < n[2]; ++z)
            for (uint32_t y = 0; y < n[1]; ++y)
              for (uint32_t x = 0; x < n[0]; ++x) {
                ChunkKey k{l, x, y, z, c, t};
                if (writer->has(k)) done += interior_bytes(layout, k);
              }
        }
    if (done) progress->set_done(done);
  }
  Builder builder(source, *writer, options, progress);
  VXR_RETURN_IF_ERROR(builder.run());
  VXR_RETURN_IF_ERROR(writer->finish());
  ImportSummary s;
  s.layout = layout;
  s.chunks = writer->chunk_count();
  s.chunks_resumed = writer->resumed_chunks();
  s.input_bytes = info.voxels_per_volume() * dtype_bytes(info.dtype) * info.channels * info.timepoints;
  std::error_code ec;
  s.file_bytes = std::filesystem::file_size(path, ec);
  s.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  if (progress) progress->finish();
  return s;
}

}  // namespace vxr
