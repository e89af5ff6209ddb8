// Timepoint playback: the frame clock (driven by a fake clock) never shows a
// timepoint out of order or twice, counts drops and stalls; the prefetcher
// queues the next timepoints' chunks in a ChunkCache within its budget.
#include <doctest/doctest.h>

#include <set>

#include "volume/dense_chunk_source.h"
#include "volume/chunk_cache.h"
#include "volume/playback.h"

using namespace vxr;

namespace {

const auto always_ready = [](uint32_t) { return true; };

// Runs the clock with frames every `frame_s` seconds of fake time; returns the
// timepoints shown (is_new) in order.
std::vector<uint32_t> run(PlaybackClock& clock, double start, double frame_s, int frames,
                          const std::function<bool(uint32_t)>& ready = always_ready) {
  std::vector<uint32_t> shown;
  for (int i = 0; i < frames; ++i) {
    auto f = clock.tick(start + i * frame_s, ready);
    if (f.is_new) shown.push_back(f.timepoint);
  }
  return shown;
}

// 8 timepoints; chunks of 1000 bytes, 2x1x1 chunks per timepoint.
class TimeSource final : public ChunkSource {
 public:
  TimeSource() {
    info_.dims = {20, 10, 10};
    info_.timepoints = 8;
    LevelInfo li;
    li.dims = info_.dims;
    li.chunk_counts = {2, 1, 1};
    levels_.push_back(li);
  }
  const VolumeInfo& info() const override { return info_; }
  const std::vector<LevelInfo>& levels() const override { return levels_; }
  uint32_t chunk_size() const override { return 10; }
  uint32_t apron() const override { return 0; }
  Result<ChunkStats> stats(const ChunkKey&) const override { return ChunkStats{}; }
  Result<std::shared_ptr<const Chunk>> read(const ChunkKey& key) const override {
    auto c = std::make_shared<Chunk>();
    c->key = key;
    c->edge = 10;
    c->data.assign(1000, static_cast<uint8_t>(key.timepoint));
    return std::shared_ptr<const Chunk>(c);
  }

 private:
  VolumeInfo info_;
  std::vector<LevelInfo> levels_;
};

}  // namespace

TEST_CASE("playback clock: real-time frames show every timepoint once, in order, then stop") {
  PlaybackClock clock(5, {.fps = 10});
  clock.play(100.0);
  // 60 Hz display, 10 timepoints/s: 5 timepoints in 0.4 s, then it pauses at the last.
  auto shown = run(clock, 100.0, 1.0 / 60, 60);
  CHECK(shown == std::vector<uint32_t>{0, 1, 2, 3, 4});
  CHECK_FALSE(clock.playing());
  CHECK(clock.counters().dropped == 0);
  CHECK(clock.counters().shown == 5);
}

TEST_CASE("playback clock: a slow renderer drops timepoints, never repeats or reorders") {
  PlaybackClock clock(20, {.fps = 10});
  clock.play(0.0);
  // 0.25 s per frame at 10 timepoints/s: 2.5 timepoints due per frame.
  auto shown = run(clock, 0.0, 0.25, 9);
  CHECK(shown == std::vector<uint32_t>{0, 2, 5, 7, 10, 12, 15, 17, 19});
  for (size_t i = 1; i < shown.size(); ++i) CHECK(shown[i] > shown[i - 1]);
  CHECK(clock.counters().dropped == 20 - shown.size());
}

TEST_CASE("playback clock: looping wraps to 0 and counts loops, order increases within a loop") {
  PlaybackClock clock(4, {.fps = 10, .loop = true});
  clock.play(0.0);
  auto shown = run(clock, 0.0, 0.1, 10);
  CHECK(shown == std::vector<uint32_t>{0, 1, 2, 3, 0, 1, 2, 3, 0, 1});
  CHECK(clock.counters().loops == 2);
  CHECK(clock.playing());
}

TEST_CASE("playback clock: data not loaded yet stalls on the current picture, then resumes without drops") {
  PlaybackClock clock(6, {.fps = 10});
  clock.play(0.0);
  bool three_loaded = false;
  auto ready = [&](uint32_t t) { return t != 3 || three_loaded; };
  std::vector<uint32_t> shown;
  for (int i = 0; i < 30; ++i) {
    if (i == 20) three_loaded = true;  // arrives 1.7 s late
    auto f = clock.tick(i * 0.1, ready);
    if (f.is_new) {
      shown.push_back(f.timepoint);
      if (f.timepoint == 3) CHECK(i == 20);
    }
  }
  CHECK(shown == std::vector<uint32_t>{0, 1, 2, 3, 4, 5});
  CHECK(clock.counters().dropped == 0);
  CHECK(clock.counters().stalls == 17);
}

TEST_CASE("playback clock: pause, step, speed") {
  PlaybackClock clock(10, {.fps = 10});
  clock.play(0.0);
  CHECK(run(clock, 0.0, 0.1, 3) == std::vector<uint32_t>{0, 1, 2});
  clock.pause(0.25);
  CHECK(run(clock, 0.3, 0.1, 10).empty());  // paused: nothing new
  CHECK(clock.timepoint() == 2);

  clock.step(+1, 1.3);
  CHECK(clock.tick(1.3, always_ready).timepoint == 3);
  clock.step(-2, 1.4);
  auto f = clock.tick(1.4, always_ready);
  CHECK(f.is_new);
  CHECK(f.timepoint == 1);
  clock.step(-5, 1.5);  // not looping: clamps at 0
  CHECK(clock.tick(1.5, always_ready).timepoint == 0);
  CHECK_FALSE(clock.playing());

  clock.set_speed(2.0, 2.0);
  clock.play(2.0);
  // 20 timepoints/s now: one every 0.05 s.
  CHECK(run(clock, 2.05, 0.05, 3) == std::vector<uint32_t>{1, 2, 3});
  clock.set_speed(0.5, 2.15);  // 5 timepoints/s: next one 0.2 s later
  CHECK_FALSE(clock.tick(2.3, always_ready).is_new);
  CHECK(clock.tick(2.35, always_ready).timepoint == 4);
}

TEST_CASE("playback clock: upcoming lists the next timepoints in play order") {
  PlaybackClock looping(5, {.fps = 10, .loop = true});
  CHECK(looping.upcoming(3) == std::vector<uint32_t>{0, 1, 2});
  looping.play(0.0);
  looping.tick(0.0, always_ready);
  looping.tick(0.35, always_ready);  // shows 3
  CHECK(looping.upcoming(3) == std::vector<uint32_t>{4, 0, 1});
  CHECK(looping.upcoming(10) == std::vector<uint32_t>{4, 0, 1, 2});

  PlaybackClock once(5, {.fps = 10});
  once.play(0.0);
  once.tick(0.0, always_ready);
  once.tick(0.35, always_ready);
  CHECK(once.upcoming(3) == std::vector<uint32_t>{4});
}

TEST_CASE("playback clock: while waiting on a due timepoint past the prefetch window, upcoming starts there") {
  // A late first frame makes timepoint 7 due at once; if upcoming kept listing
  // from the shown one (1, 2, 3), timepoint 7 would never be loaded.
  PlaybackClock clock(10, {.fps = 10});
  clock.play(0.0);
  clock.tick(0.0, always_ready);  // shows 0
  const auto only = [](uint32_t ok) { return [ok](uint32_t t) { return t == ok; }; };
  CHECK_FALSE(clock.tick(0.75, only(0)).is_new);  // 7 is due, not loaded: wait
  CHECK(clock.upcoming(3) == std::vector<uint32_t>{7, 8, 9});
  const auto f = clock.tick(0.8, only(7));
  CHECK(f.is_new);
  CHECK(f.timepoint == 7);
  CHECK(f.dropped == 6);
}

TEST_CASE("timepoint prefetcher: queues the nearest timepoints within its budget share, cancels stale ones") {
  auto source = std::make_shared<TimeSource>();
  const uint64_t chunk_bytes = 1000 + sizeof(Chunk) + 64;
  // Budget for 8 chunks; share 0.5 -> 4 chunks -> 2 timepoints ahead.
  ChunkCache cache(source, {.budget_bytes = 8 * chunk_bytes, .loader_threads = 0});
  TimepointPrefetcher prefetch(cache, *source, 0, 0, 0.5);
  CHECK(prefetch.bytes_per_timepoint() == 2 * chunk_bytes);
  CHECK(prefetch.keys(5).size() == 2);

  CHECK(prefetch.update({3, 4, 5, 6}) == 2);
  CHECK(cache.queued() == 4);
  CHECK_FALSE(prefetch.ready(3));
  // Moving on cancels timepoint 3's requests and queues 5.
  CHECK(prefetch.update({4, 5, 6}) == 2);
  CHECK(cache.queued() == 4);
  CHECK(cache.counters().cancelled == 2);

  auto chunks = prefetch.chunks(4);
  REQUIRE(chunks);
  REQUIRE(chunks.value().size() == 2);
  CHECK(chunks.value()[0]->data[0] == 4);
  CHECK(prefetch.ready(4));
  CHECK_FALSE(prefetch.ready(5));
}

TEST_CASE("timepoint prefetcher: loader threads make the upcoming timepoints ready in order") {
  auto source = std::make_shared<TimeSource>();
  ChunkCache cache(source, {.budget_bytes = 1 << 20, .loader_threads = 2});
  TimepointPrefetcher prefetch(cache, *source, 0);
  PlaybackClock clock(8, {.fps = 10});
  clock.play(0.0);
  std::vector<uint32_t> shown;
  for (int i = 0; i < 40 && clock.playing(); ++i) {
    prefetch.update(clock.upcoming(4));
    cache.wait_idle();
    auto f = clock.tick(i * 0.1, [&](uint32_t t) { return prefetch.ready(t); });
    if (f.is_new) {
      REQUIRE(prefetch.chunks(f.timepoint));
      CHECK(prefetch.chunks(f.timepoint).value()[1]->data[0] == f.timepoint);
      shown.push_back(f.timepoint);
    }
  }
  CHECK(shown == std::vector<uint32_t>{0, 1, 2, 3, 4, 5, 6, 7});
  CHECK(cache.counters().load_errors == 0);
}

// `vxr play --headless` with a forced slow renderer: the log shows every
// timepoint at most once, in increasing order within each loop, and counts
// what it skipped.
#include <fstream>
#include <nlohmann/json.hpp>

#include "cli_runner.h"

namespace {

nlohmann::json play(const std::string& input, const std::string& name, const std::string& flags) {
  const std::filesystem::path dir = vxr::test::scratch_dir("playback", name);
  const auto run = vxr::test::run_vxr("play " + vxr::test::shell_quote(input) + " --headless --size 64 --out " +
                                          vxr::test::shell_quote(dir.string()) + " " + flags,
                                      dir, 300);
  REQUIRE_MESSAGE(run.rc == 0, run.err);
  std::ifstream f(dir / "play.json");
  return nlohmann::json::parse(f);
}

// The 7-timepoint OME-TIFF as a container (what vxr play streams per timepoint).
std::string imported_time_series(const std::string& name) {
  const std::filesystem::path dir = vxr::test::scratch_dir("playback", name + "_input");
  const std::string tif = std::string(VXR_TESTDATA_DIR) + "/ome-tiff/multi-channel-time-series.ome.tif";
  const auto out = (dir / "ts.vxc").string();
  const auto run = vxr::test::run_vxr("import " + vxr::test::shell_quote(tif) + " -o " + vxr::test::shell_quote(out), dir, 300);
  REQUIRE_MESSAGE(run.rc == 0, run.err);
  return out;
}

// The shown timepoints split into loops; each strictly increasing.
std::vector<std::vector<uint32_t>> loops_of(const nlohmann::json& doc) {
  std::vector<std::vector<uint32_t>> loops(1);
  for (const auto& fr : doc["frames"]) {
    if (!fr["new"].get<bool>()) continue;
    if (fr["wrapped"].get<bool>()) loops.emplace_back();
    loops.back().push_back(fr["timepoint"].get<uint32_t>());
  }
  return loops;
}

}  // namespace

TEST_CASE("play headless: a slow renderer drops timepoints, never repeats or reorders (OME-TIFF, 7 timepoints)") {
  const auto doc = play(imported_time_series("slow"), "slow", "--fps 20 --frame-delay-ms 120");
  REQUIRE(doc["timepoints"].get<uint32_t>() == 7);
  const auto loops = loops_of(doc);
  REQUIRE(loops.size() == 1);
  const auto& shown = loops[0];
  REQUIRE(!shown.empty());
  CHECK(shown.front() == 0);
  CHECK(shown.back() == 6);
  for (size_t i = 1; i < shown.size(); ++i) CHECK(shown[i] > shown[i - 1]);
  // Every timepoint was either shown once or counted as dropped.
  CHECK(doc["shown"].get<uint64_t>() == shown.size());
  CHECK(doc["dropped"].get<uint64_t>() + shown.size() == 7);
  CHECK(doc["dropped"].get<uint64_t>() > 0);
}

TEST_CASE("play headless: looping plays in order within every loop") {
  const auto doc = play(imported_time_series("loop"), "loop", "--fps 50 --loop --frames 40 --frame-delay-ms 30");
  const auto loops = loops_of(doc);
  CHECK(loops.size() >= 2);
  CHECK(doc["loops"].get<uint64_t>() >= loops.size() - 1);  // a very slow frame may skip a whole loop
  for (const auto& l : loops)
    for (size_t i = 1; i < l.size(); ++i) CHECK(l[i] > l[i - 1]);
}

TEST_CASE("bench movie: a movie longer than the cache is read again every loop, and the render run counts every timepoint") {
  // 12 one-chunk timepoints, prefetch 1: the cache holds 2 x 2 volumes and the
  // brick pool 8 bricks, so the second loop reads, decodes and uploads all 12
  // again; the played run shows or drops each timepoint exactly once.
  const std::filesystem::path dir = vxr::test::scratch_dir("playback", "bench_movie");
  const auto run = vxr::test::run_vxr("bench movie --dims 48 40 36 --timepoints 12 --prefetch 1 --loops 2 --size 32 "
                                      "--fps 1000 --out " + vxr::test::shell_quote(dir.string()),
                                      dir, 300);
  REQUIRE_MESSAGE(run.rc == 0, run.err);
  std::ifstream f(dir / "movie.json");
  const auto doc = nlohmann::json::parse(f);
  CHECK(doc["timepoints"].get<uint32_t>() == 12);
  CHECK(doc["data_path_volumes_per_s"].get<double>() > 0);
  CHECK(doc["lz4_decode_bound_volumes_per_s"].get<double>() > 0);
  CHECK(doc["per_volume_ms"].size() == 24);
  const auto chunks = doc["level0_chunks_per_volume"].get<uint64_t>();
  CHECK(doc["cache"]["loads"].get<uint64_t>() >= 2 * 12 * chunks);
  CHECK(doc["cache"]["evictions"].get<uint64_t>() > 0);
  CHECK(doc["uploaded_bytes"].get<uint64_t>() > 0);
  CHECK(doc["render_volumes_per_s"].get<double>() > 0);
  CHECK(doc["shown"].get<uint64_t>() >= 1);
  CHECK(doc["shown"].get<uint64_t>() + doc["dropped"].get<uint64_t>() == 12);
}

TEST_CASE("dense chunk source: a time series serves each timepoint's own voxels and ranges") {
  std::vector<std::vector<vxr::DenseVolume>> series;
  for (uint8_t t = 0; t < 3; ++t) {
    vxr::DenseVolume v;
    v.dims = {70, 9, 5};  // two chunks along x at chunk size 64
    v.dtype = vxr::DType::kU8;
    v.data.assign(v.byte_size(), uint8_t(10 * (t + 1)));
    v.data[0] = uint8_t(200 + t);  // one voxel marks the timepoint in chunk (0,0,0)
    series.push_back({v});
  }
  auto src = vxr::DenseChunkSource::create_series(std::move(series));
  REQUIRE(src);
  CHECK((*src)->info().timepoints == 3);
  for (uint32_t t = 0; t < 3; ++t) {
    auto c = (*src)->read({0, 0, 0, 0, 0, t});
    REQUIRE(c);
    const uint32_t a = (*src)->apron(), e = (*c)->edge;
    CHECK((*c)->data[(size_t(a) * e + a) * e + a] == 200 + t);  // voxel (0,0,0) of the interior
    auto far = (*src)->stats({0, 1, 0, 0, 0, t});
    REQUIRE(far);
    CHECK(far->min == 10 * (t + 1));
    CHECK(far->max == 10 * (t + 1));
  }
  CHECK_FALSE((*src)->read({0, 0, 0, 0, 0, 3}));  // past the last timepoint
}

TEST_CASE("play headless: an OME-TIFF time series plays without import, every timepoint shown or dropped once") {
  const std::string tif = std::string(VXR_TESTDATA_DIR) + "/ome-tiff/multi-channel-time-series.ome.tif";
  const auto doc = play(tif, "ome_tiff_direct", "--fps 4");
  REQUIRE(doc["timepoints"].get<uint32_t>() == 7);
  const auto loops = loops_of(doc);
  REQUIRE(loops.size() == 1);
  const auto& shown = loops[0];
  REQUIRE(shown.size() >= 2);
  CHECK(shown.front() == 0);
  CHECK(shown.back() == 6);
  for (size_t i = 1; i < shown.size(); ++i) CHECK(shown[i] > shown[i - 1]);
  CHECK(doc["dropped"].get<uint64_t>() + shown.size() == 7);
}

TEST_CASE("view --timepoint: the viewer opens at that timepoint, the same picture every run, a clear error past the last") {
  namespace fs = std::filesystem;
  const fs::path dir = vxr::test::scratch_dir("playback", "view_timepoint");
  const auto q = [](const fs::path& p) { return vxr::test::shell_quote(p.string()); };
  const auto made = vxr::test::run_vxr("bench movie --dims 48 40 36 --timepoints 6 --loops 1 --size 32 --fps 1000 --out " +
                                           q(dir),
                                       dir, 300);
  REQUIRE_MESSAGE(made.rc == 0, made.err);
  const fs::path movie = dir / "movie.vxc";
  const auto view = [&](uint32_t t, const std::string& name) {
    const auto r = vxr::test::run_vxr("view " + q(movie) + " --headless --frames 20 --width 64 --height 64 --timepoint " +
                                          std::to_string(t) + " --png-dir " + q(dir / name),
                                      dir, 300);
    REQUIRE_MESSAGE(r.rc == 0, r.err);
    return vxr::test::read_bytes(dir / name / "last_left.png");
  };
  const std::string t0 = view(0, "t0"), t4 = view(4, "t4"), t4_again = view(4, "t4_again");
  CHECK(t0 != t4);  // the movie's blobs move between timepoints
  CHECK(t4 == t4_again);

  const auto past = vxr::test::run_vxr("view " + q(movie) + " --headless --frames 1 --timepoint 6", dir, 300);
  CHECK(past.rc == 2);
  CHECK(past.err.find("--timepoint: 6, but " + movie.string() + " has 6 timepoint(s) (0..5)") != std::string::npos);
}

TEST_CASE("play headless: the session flags of render and view (--timepoint, --channel, --model) choose what plays") {
  const std::string tif = std::string(VXR_TESTDATA_DIR) + "/ome-tiff/multi-channel-time-series.ome.tif";
  const auto from3 = play(tif, "flags_from3", "--fps 4 --timepoint 3 --channel 1 --model mip");
  const auto loops = loops_of(from3);
  REQUIRE(loops.size() == 1);
  REQUIRE(!loops[0].empty());
  CHECK(loops[0].front() == 3);
  CHECK(loops[0].back() == 6);
  CHECK(from3["dropped"].get<uint64_t>() + loops[0].size() == 4);

  const std::filesystem::path dir = vxr::test::scratch_dir("playback", "flags_bad");
  const auto bad = vxr::test::run_vxr("play " + vxr::test::shell_quote(tif) + " --headless --out " +
                                          vxr::test::shell_quote(dir.string()) + " --channel 5",
                                      dir, 300);
  CHECK(bad.rc == 2);
  CHECK(bad.err.find("--channel: '5', but " + tif + " has 3 channel(s)") != std::string::npos);
  const auto late = vxr::test::run_vxr("play " + vxr::test::shell_quote(tif) + " --headless --out " +
                                           vxr::test::shell_quote(dir.string()) + " --timepoint 7",
                                       dir, 300);
  CHECK(late.rc == 2);
  CHECK(late.err.find("--timepoint: 7, but " + tif + " has 7 timepoint(s) (0..6)") != std::string::npos);
}
