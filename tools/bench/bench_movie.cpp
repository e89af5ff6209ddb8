// `vxr bench movie`: how many volumes per second the playback data path
// delivers for a time series: read + LZ4 decode (cache loader threads, ahead
// of need via TimepointPrefetcher) + upload into the GPU brick pool, against
// the bare LZ4 decode bound of the same chunks in the same run.
#include <lz4.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <filesystem>

#include "bench.h"
#include "core/image.h"
#include "core/progress.h"
#include "plot.h"
#include "render/lod/brick_pool.h"
#include "volume/chunk_cache.h"
#include "volume/memory_slab_source.h"
#include "volume/open_chunk_source.h"
#include "volume/playback.h"
#include "volume/pyramid_builder.h"
#include "volume/synthetic_microscopy.h"

namespace vxr::bench {
namespace {

struct MovieOptions {
  BenchOptions common;
  std::string input;  // existing container; empty: build one
  uint32_t timepoints = 12;
  std::vector<uint64_t> dims{272, 272, 272};
  uint32_t prefetch = 4;
};

double seconds_since(std::chrono::steady_clock::time_point t0) {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
}

// T timepoints of noisy fluorescence-like u8 content (camera noise, blobs),
// each shifted along x so every timepoint differs.
Result<std::string> build_movie(const MovieOptions& o) {
  const std::array<uint64_t, 3> dims{o.dims[0], o.dims[1], o.dims[2]};
  SyntheticMicroscopySource synth(dims);
  const uint64_t n = dims[0] * dims[1] * dims[2];
  std::vector<uint8_t> u16(n * 2);
  if (Status s = synth.read_region(0, 0, Box3{{0, 0, 0}, dims}, u16); !s) return s;
  VolumeInfo info;
  info.dims = dims;
  info.timepoints = o.timepoints;
  std::vector<std::vector<uint8_t>> volumes(o.timepoints, std::vector<uint8_t>(n));
  for (uint32_t t = 0; t < o.timepoints; ++t) {
    const uint64_t shift = (uint64_t(t) * 5) % dims[0];
    for (uint64_t i = 0; i < n; ++i) {
      const uint64_t x = i % dims[0];
      const uint64_t src = i - x + (x + shift) % dims[0];
      const uint16_t v = reinterpret_cast<const uint16_t*>(u16.data())[src];
      volumes[t][i] = static_cast<uint8_t>(std::min<int>(255, std::max<int>(0, int(v) - 100) / 2));
    }
  }
  MemorySlabSource source(info, std::move(volumes));
  std::error_code ec;
  std::filesystem::create_directories(o.common.out_dir, ec);
  const std::string path = (std::filesystem::path(o.common.out_dir) / "movie.vxc").string();
  std::filesystem::remove(path, ec);
  Progress progress("movie: building container", n * o.timepoints);
  ImportOptions io;
  auto summary = build_container(source, path, io, &progress);
  progress.finish();
  if (!summary) return summary.status();
  return path;
}

// Reads through the cache, so BrickPool::upload finds what the loader threads decoded.
class CachedSource final : public ChunkSource {
 public:
  CachedSource(const ChunkSource& inner, ChunkCache& cache) : inner_(inner), cache_(cache) {}
  const VolumeInfo& info() const override { return inner_.info(); }
  const std::vector<LevelInfo>& levels() const override { return inner_.levels(); }
  uint32_t chunk_size() const override { return inner_.chunk_size(); }
  uint32_t apron() const override { return inner_.apron(); }
  Result<ChunkStats> stats(const ChunkKey& key) const override { return inner_.stats(key); }
  Result<std::shared_ptr<const Chunk>> read(const ChunkKey& key) const override { return cache_.get_or_load(key); }

 private:
  const ChunkSource& inner_;
  ChunkCache& cache_;
};

int run_movie(const MovieOptions& o) {
  std::string path = o.input;
  if (path.empty()) {
    auto built = build_movie(o);
    if (!built) return cli::fail(built.status());
    path = *built;
  }
  auto opened = open_chunk_source(path);
  if (!opened) return cli::fail(opened.status());
  std::shared_ptr<const ChunkSource> source(std::move(opened->source));
  const VolumeInfo& info = source->info();
  if (info.timepoints < 2) return cli::fail(invalid_argument(path + ": needs at least 2 timepoints"));
  const uint32_t T = info.timepoints;

  auto gpu = cli::open_gpu();
  if (!gpu) return cli::fail(gpu.status());
  gpu::Context& ctx = **gpu;

  // Data path: prefetch T+prefetch ahead on 2 loader threads, upload each timepoint's level 0.
  ChunkCache cache(source, {.budget_bytes = 1ull << 30, .loader_threads = 2});
  CachedSource cached(*source, cache);
  TimepointPrefetcher prefetch(cache, *source, 0);
  const uint32_t bricks = uint32_t(prefetch.keys(0).size());
  BrickPoolOptions po;
  po.staging_bytes = 64ull << 20;
  const uint32_t side = uint32_t(std::ceil(std::cbrt(double(bricks) * 2)));
  po.slots = {side, side, side};
  auto pool = BrickPool::create(ctx, cached, po);
  if (!pool) return cli::fail(pool.status());

  Progress progress("movie: data path", T, false);
  const auto t0 = std::chrono::steady_clock::now();
  uint64_t uploaded_bytes = 0;
  std::vector<double> per_volume_ms;
  for (uint32_t t = 0; t < T; ++t) {
    std::vector<uint32_t> next;
    for (uint32_t k = t; k < std::min(T, t + o.prefetch); ++k) next.push_back(k);
    prefetch.update(next);
    const auto tv = std::chrono::steady_clock::now();
    (*pool)->begin_frame();
    std::vector<ChunkKey> keys = prefetch.keys(t);
    while (!keys.empty()) {
      auto up = (*pool)->upload(keys, 1ull << 40);
      if (!up) return cli::fail(up.status());
      uploaded_bytes += up->bytes;
      keys.erase(keys.begin(), keys.begin() + up->bricks);
      if (up->bricks == 0) return cli::fail(internal_error("brick pool accepted no brick"));
    }
    per_volume_ms.push_back(seconds_since(tv) * 1e3);
    progress.advance(1);
  }
  const double data_s = seconds_since(t0);
  progress.finish();
  if (auto errors = cache.take_errors(); !errors.empty()) return cli::fail(errors.front().second);

  // Bare LZ4 bound: the same level-0 chunks of every timepoint, compressed
  // here once, then only LZ4_decompress_safe timed.
  std::vector<std::vector<char>> packed;
  std::vector<int> raw_sizes;
  uint64_t raw_bytes = 0, packed_bytes = 0;
  for (uint32_t t = 0; t < T; ++t)
    for (const ChunkKey& k : prefetch.keys(t)) {
      auto c = source->read(k);
      if (!c) return cli::fail(c.status());
      const auto& d = (*c)->data;
      std::vector<char> buf(LZ4_compressBound(int(d.size())));
      const int m = LZ4_compress_default(reinterpret_cast<const char*>(d.data()), buf.data(), int(d.size()), int(buf.size()));
      buf.resize(m);
      packed_bytes += m;
      raw_bytes += d.size();
      packed.push_back(std::move(buf));
      raw_sizes.push_back(int(d.size()));
    }
  std::vector<char> out(*std::max_element(raw_sizes.begin(), raw_sizes.end()));
  const auto t1 = std::chrono::steady_clock::now();
  for (size_t i = 0; i < packed.size(); ++i)
    if (LZ4_decompress_safe(packed[i].data(), out.data(), int(packed[i].size()), int(out.size())) != raw_sizes[i])
      return cli::fail(internal_error("LZ4 round trip failed"));
  const double lz4_s = seconds_since(t1);

  const double data_rate = T / data_s, lz4_rate = T / lz4_s;
  nlohmann::json doc = {
      {"input", path},
      {"dims", {info.dims[0], info.dims[1], info.dims[2]}},
      {"dtype_bytes", dtype_bytes(info.dtype)},
      {"timepoints", T},
      {"level0_chunks_per_volume", bricks},
      {"data_path_volumes_per_s", data_rate},
      {"data_path_note", "read + LZ4 decode on 2 cache loader threads (prefetch " + std::to_string(o.prefetch) +
                             " timepoints ahead) + BrickPool::upload of level 0, first timepoint cold"},
      {"per_volume_ms", per_volume_ms},
      {"uploaded_bytes", uploaded_bytes},
      {"lz4_decode_bound_volumes_per_s", lz4_rate},
      {"lz4_note", "one thread, LZ4_decompress_safe of the same level-0 chunks (payload incl. apron)"},
      {"lz4_ratio", double(raw_bytes) / double(std::max<uint64_t>(1, packed_bytes))},
      {"cache", {{"loads", cache.counters().loads}, {"hits", cache.counters().hits}, {"misses", cache.counters().misses}}},
  };
  PlotSpec plot;
  plot.title = "vxr bench movie: ms per volume (data path)";
  plot.x_label = "timepoint";
  plot.y_label = "ms";
  PlotSeries s;
  s.label = "read+decode+upload";
  s.line = true;
  for (uint32_t t = 0; t < T; ++t) {
    s.x.push_back(t);
    s.y.push_back(per_volume_ms[t]);
  }
  plot.series.push_back(s);
  std::error_code ec;
  std::filesystem::create_directories(o.common.out_dir, ec);
  const std::string png_path = (std::filesystem::path(o.common.out_dir) / "movie.png").string();
  if (Status st = write_png(png_path, render_plot(plot)); !st) return cli::fail(st);
  doc["plot"] = png_path;
  std::fprintf(stderr, "movie: %u x %llu^3-ish volumes: data path %.1f volumes/s, bare LZ4 decode %.1f volumes/s (ratio %.2f)\n",
               T, (unsigned long long)info.dims[0], data_rate, lz4_rate, doc["lz4_ratio"].get<double>());
  auto report = write_report(o.common, "movie", doc, &ctx);
  if (!report) return cli::fail(report.status());
  std::printf("%s\n", png_path.c_str());
  return cli::kExitOk;
}

}  // namespace

void add_movie_bench(CLI::App& bench, cli::Invocation& inv) {
  auto* cmd = bench.add_subcommand("movie", "volumes per second of the timepoint playback data path vs bare LZ4 decode");
  auto o = std::make_shared<MovieOptions>();
  add_common_options(cmd, o->common);
  cmd->add_option("--input", o->input, "multi-timepoint container or OME-Zarr (default: build one)");
  cmd->add_option("--timepoints", o->timepoints, "timepoints to build")->check(CLI::Range(2u, 1000u));
  cmd->add_option("--dims", o->dims, "volume size to build, x y z")->expected(3);
  cmd->add_option("--prefetch", o->prefetch, "timepoints decoded ahead")->check(CLI::Range(1u, 64u));
  cmd->callback([&inv, o] { inv.run = [o] { return run_movie(*o); }; });
}

}  // namespace vxr::bench
