// `vxr play X --headless --out DIR`: plays the timepoints of a time series
// through the session and brick renderer of `vxr view`, paced by the playback
// clock (volume/playback.h), and logs which timepoint every frame showed to
// DIR/play.json (what the ordering/drop test reads).
#include <chrono>
#include <cstdio>
#include <filesystem>
#include <nlohmann/json.hpp>
#include <thread>

#include "command.h"
#include "volume_flags.h"
#include "core/image.h"
#include "core/output_file.h"
#include "render/camera.h"
#include "render/movie_player.h"
#include "render/volume_session.h"
#include "volume/playback.h"

namespace vxr::cli {
namespace {

struct PlayOptions {
  std::string input;
  double fps = 10.0;
  double speed = 1.0;
  bool loop = false;
  bool headless = false;
  std::string out_dir;
  int frames = 0;             // display frames (stalls included); 0: until the end (looping: one loop and a bit)
  double frame_delay_ms = 0;  // extra time per frame: a forced slow renderer
  uint32_t size = 256;
  uint32_t prefetch = 4;      // timepoints decoded ahead
  int level = -1;             // pyramid level played (-1: the finest that fits the prefetch budget)
  SessionFlags session;  // shared with render and view; its timepoint is the first one played
};

int run_play(const PlayOptions& o) {
  if (!o.headless) return fail(invalid_argument("vxr play: only --headless playback is available; use vxr view to look"), kExitUsage);
  std::error_code dir_error;
  std::filesystem::create_directories(o.out_dir, dir_error);  // --out names a folder: made if missing
  if (Status s = check_output((std::filesystem::path(o.out_dir) / "play.json").string(), {}); !s) return fail(s, kExitUsage);
  SessionStep failed_at = SessionStep::kSettings;
  auto session = open_volume_session(o.input, o.session, &failed_at);
  if (!session) return fail(session.status(), failed_at == SessionStep::kSource ? kExitFailure : kExitUsage);
  const ChunkSource& src = *session->source;
  const uint32_t T = src.info().timepoints;
  auto gpu = open_gpu();
  if (!gpu) return fail(gpu.status());
  MoviePlayerOptions mo;
  mo.playback = {.fps = o.fps, .speed = o.speed, .loop = o.loop};
  mo.prefetch = o.prefetch;
  mo.level = o.level;
  mo.pool.channels = session->channels;
  auto player = MoviePlayer::create(**gpu, session->source, mo);
  if (!player) return fail(player.status());
  MoviePlayer& p = **player;
  PlaybackClock& clock = p.clock();
  const Camera camera = orbit_camera(p.renderer().placement(), 30.0, 20.0);

  clock.step(int(session->timepoint), 0.0);
  const auto t0 = std::chrono::steady_clock::now();
  auto now = [&] { return std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count(); };
  clock.play(now());
  // The log holds the frames that showed a new timepoint (a stall, waiting
  // for data, is counted, not logged).
  nlohmann::json frames = nlohmann::json::array();
  ImageRgba8 last;
  double last_new = now();
  for (int i = 0; o.frames <= 0 || i < o.frames; ++i) {
    // A due timepoint is drawn once decoded; until then the clock holds the
    // current one (a stall) or, when late, drops: never a repeat or a reorder.
    auto f = p.frame(now(), camera, session->settings, o.size, o.size, &last);
    if (!f) return fail(f.status());
    if (f->is_new) {
      frames.push_back({{"frame", i}, {"timepoint", f->timepoint}, {"new", true}, {"dropped", f->dropped},
                        {"wrapped", f->wrapped}});
      last_new = now();
    } else if (now() - last_new > 60.0) {
      return fail(internal_error(o.input + ": timepoint " + std::to_string(f->timepoint) +
                                 "'s successor did not load within 60 s"));
    }
    if (o.frame_delay_ms > 0) std::this_thread::sleep_for(std::chrono::duration<double, std::milli>(o.frame_delay_ms));
    else if (!f->is_new) std::this_thread::sleep_for(std::chrono::milliseconds(1));  // waiting for data: do not spin
    if (!clock.playing()) break;
    // Looping without --frames: one loop and a bit.
    if (o.frames <= 0 && clock.counters().loops >= 1 && clock.timepoint() >= T / 2) break;
  }
  const auto& c = clock.counters();
  nlohmann::json doc = {{"input", o.input}, {"timepoints", T}, {"fps", o.fps}, {"speed", o.speed}, {"loop", o.loop},
                        {"shown", c.shown}, {"dropped", c.dropped}, {"stalls", c.stalls}, {"loops", c.loops}, {"level", p.level()},
                        {"frames", frames}};
  const std::string json_path = (std::filesystem::path(o.out_dir) / "play.json").string();
  if (Status s = write_file_atomically(json_path, doc.dump(1)); !s) return fail(s);
  const std::string png_path = (std::filesystem::path(o.out_dir) / "last.png").string();
  if (Status s = write_png(png_path, last); !s) return fail(s);
  std::printf("%s: %llu timepoints shown, %llu dropped, %llu loops\n", json_path.c_str(), (unsigned long long)c.shown,
              (unsigned long long)c.dropped, (unsigned long long)c.loops);
  return kExitOk;
}

}  // namespace

void add_play_command(CLI::App& app, Invocation& inv) {
  auto* cmd = app.add_subcommand("play", "play the timepoints of a time series (3D movie)");
  auto o = std::make_shared<PlayOptions>();
  cmd->add_option("input", o->input, "volume: .vxc, OME-Zarr, OME-TIFF, ...")->required();
  cmd->add_option("--fps", o->fps, "timepoints per second")->check(CLI::Range(0.01, 1000.0));
  cmd->add_option("--speed", o->speed, "speed multiplier")->check(CLI::Range(0.01, 100.0));
  cmd->add_flag("--loop", o->loop, "start over after the last timepoint");
  cmd->add_flag("--headless", o->headless, "no window: render offscreen, log the shown timepoints");
  cmd->add_option("--out", o->out_dir, "headless: directory for play.json and last.png")->default_val("out/play");
  cmd->add_option("--frames", o->frames, "stop after this many display frames (default: the end; looping: one loop and a half)");
  cmd->add_option("--frame-delay-ms", o->frame_delay_ms, "add this much time to every frame (a slow renderer)");
  cmd->add_option("--prefetch", o->prefetch, "timepoints decoded ahead")->check(CLI::Range(1u, 64u));
  cmd->add_option("--level", o->level, "pyramid level to play (default: the finest whose timepoint fits the prefetch budget)")
      ->check(CLI::Range(0, 64));
  cmd->add_option("--size", o->size, "headless image side, pixels")->check(CLI::Range(16u, 4096u));
  add_session_flags(cmd, &o->session);
  cmd->callback([&inv, o, cmd] {
    note_session_flags(cmd, &o->session);
    inv.run = [o] { return run_play(*o); };
  });
}

}  // namespace vxr::cli
