// `vxr bench movie`: how many volumes per second the playback data path
// delivers for a time series: read + LZ4 decode (cache loader threads, ahead
// of need via TimepointPrefetcher) + upload into the GPU brick pool, against
// the bare LZ4 decode bound of the same chunks in the same run.
#include <lz4.h>
#include <sys/resource.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <thread>

#include "bench.h"
#include "core/image.h"
#include "core/progress.h"
#include "plot.h"
#include "render/camera.h"
#include "render/lod/brick_pool.h"
#include "render/movie_player.h"
#include "render/volume_session.h"
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
  uint32_t loops = 3;        // plays of the whole movie; the first (cold start) is reported apart
  uint64_t cache_mb = 0;     // 0: room for 2 x (prefetch + 1) volumes, less than the movie, so
                             //    every loop reads and decodes every volume again (a long movie)
  double fps = 25.0;         // playback rate of the render run (the paper's 25 volumes/s)
  uint32_t size = 256;       // render run image side
};

// CPU seconds of every thread of this process so far (user + system).
double process_cpu_s() {
  rusage u{};
  getrusage(RUSAGE_SELF, &u);
  return double(u.ru_utime.tv_sec + u.ru_stime.tv_sec) + 1e-6 * double(u.ru_utime.tv_usec + u.ru_stime.tv_usec);
}

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

struct RenderRun {
  uint64_t shown = 0, dropped = 0, stalls = 0;
  double wall_s = 0;
  double upload_ms = 0, render_ms = 0;  // means per shown volume
  uint32_t level = 0;
};

Status run_render(gpu::Context& ctx, std::shared_ptr<const ChunkSource> source, const MovieOptions& o, RenderRun& out) {
  MoviePlayerOptions mo;
  mo.playback = {.fps = o.fps};
  mo.prefetch = o.prefetch;
  mo.level = 0;  // the full-resolution volumes the data path measured
  VXR_ASSIGN_OR_RETURN(auto player, MoviePlayer::create(ctx, source, mo));
  const Camera camera = orbit_camera(player->renderer().placement(), 30.0, 20.0);
  const RenderSettings settings = default_view_settings();
  ImageRgba8 image;
  // Warm-up: shaders and the first timepoint, outside the timed run.
  player->clock().step(0, 0.0);
  while (true) {
    VXR_ASSIGN_OR_RETURN(PlaybackFrame f, player->frame(0.0, camera, settings, o.size, o.size, &image));
    if (f.is_new) break;
    std::this_thread::sleep_for(std::chrono::milliseconds(1));
  }
  PlaybackClock& clock = player->clock();
  clock.step(-int(clock.timepoint_count()), 0.0);  // back to timepoint 0, not shown
  const auto t0 = std::chrono::steady_clock::now();
  Progress progress("movie: render", clock.timepoint_count(), false);
  clock.play(0.0);
  double upload_ms = 0, render_ms = 0;
  while (clock.playing()) {
    MovieFrameStats st;
    VXR_ASSIGN_OR_RETURN(PlaybackFrame f, player->frame(seconds_since(t0), camera, settings, o.size, o.size, &image, &st));
    if (f.is_new) {
      upload_ms += st.upload_ms;
      render_ms += st.render_ms;
      progress.advance(1 + f.dropped);
    } else {
      std::this_thread::sleep_for(std::chrono::milliseconds(1));
    }
  }
  progress.finish();
  out.wall_s = seconds_since(t0);
  const PlaybackCounters& c = clock.counters();
  out.shown = c.shown;
  out.dropped = c.dropped;
  out.stalls = c.stalls;
  out.upload_ms = c.shown ? upload_ms / double(c.shown) : 0;
  out.render_ms = c.shown ? render_ms / double(c.shown) : 0;
  out.level = player->level();
  return Status::ok();
}

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

  // Data path: the next `prefetch` timepoints decode on 2 loader threads
  // while each timepoint's level 0 is uploaded, `loops` times round the movie.
  const uint64_t edge = source->chunk_size() + 2ull * source->apron();
  const auto& counts = source->levels()[0].chunk_counts;
  const uint64_t volume_bytes =
      (edge * edge * edge * dtype_bytes(info.dtype) + sizeof(Chunk) + 64) * counts[0] * counts[1] * counts[2];
  const uint64_t cache_bytes = o.cache_mb ? o.cache_mb << 20 : 2 * (uint64_t(o.prefetch) + 1) * volume_bytes;
  ChunkCache cache(source, {.budget_bytes = cache_bytes, .loader_threads = 2});
  CachedChunkSource cached(*source, cache);
  TimepointPrefetcher prefetch(cache, *source, 0);
  const uint32_t bricks = uint32_t(prefetch.keys(0).size());
  BrickPoolOptions po;
  po.staging_bytes = 64ull << 20;
  const uint32_t side = uint32_t(std::ceil(std::cbrt(double(bricks) * 2)));
  po.slots = {side, side, side};
  auto pool = BrickPool::create(ctx, cached, po);
  if (!pool) return cli::fail(pool.status());

  Progress progress("movie: data path", uint64_t(T) * o.loops, false);
  uint64_t uploaded_bytes = 0;
  std::vector<double> per_volume_ms, loop_s;
  double warm_cpu_s = 0;
  for (uint32_t loop = 0; loop < o.loops; ++loop) {
    const auto tl = std::chrono::steady_clock::now();
    const double cpu0 = process_cpu_s();
    for (uint32_t t = 0; t < T; ++t) {
      std::vector<uint32_t> next;
      for (uint32_t k = 0; k < o.prefetch && k < T; ++k) next.push_back((t + k) % T);
      prefetch.update(next);
      const auto tv = std::chrono::steady_clock::now();
      (*pool)->begin_frame();
      std::vector<ChunkKey> keys = prefetch.keys(t);
      // Still resident only when the pool (2+ volumes) holds the whole movie.
      std::erase_if(keys, [&](const ChunkKey& k) { return (*pool)->resident(k); });
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
    loop_s.push_back(seconds_since(tl));
    if (loop > 0) warm_cpu_s += process_cpu_s() - cpu0;
  }
  progress.finish();
  if (auto errors = cache.take_errors(); !errors.empty()) return cli::fail(errors.front().second);
  const double first_rate = T / loop_s.front();
  double warm_s = 0;
  for (size_t i = 1; i < loop_s.size(); ++i) warm_s += loop_s[i];
  const double data_rate = loop_s.size() > 1 ? T * double(loop_s.size() - 1) / warm_s : first_rate;
  const auto cache_counters = cache.counters();

  // Render: the movie played once at --fps through MoviePlayer (what `vxr play`
  // runs): shown volumes per second of wall time, and what the clock dropped.
  RenderRun rr;
  if (auto r = run_render(ctx, source, o, rr); !r) return cli::fail(r);

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

  const double lz4_rate = T / lz4_s;
  const double render_rate = rr.wall_s > 0 ? double(rr.shown) / rr.wall_s : 0;
  nlohmann::json doc = {
      {"input", path},
      {"dims", {info.dims[0], info.dims[1], info.dims[2]}},
      {"dtype_bytes", dtype_bytes(info.dtype)},
      {"timepoints", T},
      {"level0_chunks_per_volume", bricks},
      {"loops", o.loops},
      {"cache_budget_mb", double(cache_bytes) / double(1 << 20)},
      {"data_path_volumes_per_s", data_rate},
      {"data_path_first_loop_volumes_per_s", first_rate},
      {"data_path_cpu_ms_per_volume", o.loops > 1 ? 1e3 * warm_cpu_s / (double(T) * (o.loops - 1)) : 0.0},
      {"data_path_cpu_note", "CPU time of all threads per volume after the first loop: 1000 x cores / this is the rate"
                             " the machine could sustain when nothing else runs"},
      {"data_path_note", "read + LZ4 decode on 2 cache loader threads (prefetch " + std::to_string(o.prefetch) +
                             " timepoints ahead) + BrickPool::upload of level 0; the cache holds fewer volumes than"
                             " the movie, so every loop reads and decodes every volume again; sustained = loops after"
                             " the first (cold start)"},
      {"per_volume_ms", per_volume_ms},
      {"uploaded_bytes", uploaded_bytes},
      {"lz4_decode_bound_volumes_per_s", lz4_rate},
      {"lz4_note", "one thread, LZ4_decompress_safe of the same level-0 chunks (payload incl. apron)"},
      {"lz4_ratio", double(raw_bytes) / double(std::max<uint64_t>(1, packed_bytes))},
      {"cache", {{"loads", cache_counters.loads}, {"hits", cache_counters.hits}, {"misses", cache_counters.misses},
                 {"evictions", cache_counters.evictions}}},
      {"render_volumes_per_s", render_rate},
      {"render_note", "the movie played once at --fps through MoviePlayer (vxr play): volumes shown per second of"
                      " wall time, level 0, " + std::to_string(o.size) + "^2 pixels"},
      {"render_fps_target", o.fps},
      {"shown", rr.shown},
      {"dropped", rr.dropped},
      {"stalls", rr.stalls},
      {"render_upload_ms_mean", rr.upload_ms},
      {"render_ms_mean", rr.render_ms},
  };
  PlotSpec plot;
  plot.title = "vxr bench movie: ms per volume (data path)";
  plot.x_label = "volume (timepoint + loop x timepoints)";
  plot.y_label = "ms";
  PlotSeries s;
  s.label = "read+decode+upload";
  s.line = true;
  for (size_t i = 0; i < per_volume_ms.size(); ++i) {
    s.x.push_back(double(i));
    s.y.push_back(per_volume_ms[i]);
  }
  plot.series.push_back(s);
  auto png = write_plot(o.common, "movie", plot);
  if (!png) return cli::fail(png.status());
  const std::string& png_path = *png;
  doc["plot"] = png_path;
  std::fprintf(stderr,
               "movie: %u x %llux%llux%llu volumes, %u loops: data path %.1f volumes/s sustained (first loop %.1f), bare "
               "LZ4 decode %.1f volumes/s (ratio %.2f); render %.1f volumes/s at %ux%u, %llu shown, %llu dropped at %.0f fps\n",
               T, (unsigned long long)info.dims[0], (unsigned long long)info.dims[1], (unsigned long long)info.dims[2],
               o.loops, data_rate, first_rate, lz4_rate, doc["lz4_ratio"].get<double>(), render_rate, o.size, o.size,
               (unsigned long long)rr.shown, (unsigned long long)rr.dropped, o.fps);
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
  cmd->add_option("--loops", o->loops, "plays of the whole movie through the data path")->check(CLI::Range(1u, 100u));
  cmd->add_option("--cache-mb", o->cache_mb, "decoded-chunk cache (default: 2 x (prefetch + 1) volumes)")
      ->check(CLI::Range(uint64_t(16), uint64_t(1) << 20));
  cmd->add_option("--fps", o->fps, "playback rate of the render run")->check(CLI::Range(0.1, 1000.0));
  cmd->add_option("--size", o->size, "render run image side, pixels")->check(CLI::Range(16u, 4096u));
  cmd->callback([&inv, o] { inv.run = [o] { return run_movie(*o); }; });
}

}  // namespace vxr::bench
