// Plays a time series (3D movie) through the one brick renderer.
//
//   auto player = MoviePlayer::create(ctx, source, {.playback = {.fps = 25}});
//   (*player)->clock().play(now);
//   each display frame: auto f = (*player)->frame(now, camera, settings, w, h, &image);
//                       if (f->is_new) show(image);
//
// The PlaybackClock picks the timepoint; the TimepointPrefetcher keeps the
// next ones decoding on the cache's loader threads while the current one is
// drawn; a due timepoint is shown only once all its chunks are decoded, then
// uploaded and drawn complete in one pass. A slow data path or renderer
// therefore drops timepoints (never shows one out of order, twice, or half
// loaded). One level of the pyramid is played (the finest whose timepoint
// fits the prefetch budget, or the one asked for), so what is prefetched is
// what is drawn.
#pragma once

#include <memory>
#include <vector>

#include "core/image.h"
#include "core/status.h"
#include "gpu/context.h"
#include "render/camera.h"
#include "render/lod/brick_renderer.h"
#include "scene/render_settings.h"
#include "volume/chunk_cache.h"
#include "volume/playback.h"

namespace vxr {

struct MoviePlayerOptions {
  PlaybackOptions playback;
  uint32_t prefetch = 4;               // timepoints decoded ahead of the one shown
  uint64_t cache_bytes = 1ull << 30;   // decoded chunks kept (prefetch uses half)
  uint32_t loader_threads = 2;
  int level = -1;                      // level played; -1: the finest that fits (see above)
  BrickPoolOptions pool;               // slots {0,0,0}: two timepoints of the level played
};

struct MovieFrameStats {
  double upload_ms = 0;  // this frame's brick uploads (0 when no new timepoint)
  double render_ms = 0;  // ray casting and readback
  uint32_t passes = 0;   // render passes until complete (1 unless bricks were evicted)
};

class MoviePlayer {
 public:
  static Result<std::unique_ptr<MoviePlayer>> create(gpu::Context& ctx, std::shared_ptr<const ChunkSource> source,
                                                     const MoviePlayerOptions& options = {});

  // One display frame at `now` (seconds, the clock's time base): ticks the
  // clock and, when it shows a new timepoint, draws it into *image (w x h,
  // premultiplied RGBA). Otherwise *image is left alone.
  Result<PlaybackFrame> frame(double now, const Camera& camera, const RenderSettings& settings, uint32_t width,
                              uint32_t height, ImageRgba8* image, MovieFrameStats* stats = nullptr);

  PlaybackClock& clock() { return clock_; }
  BrickRenderer& renderer() { return *renderer_; }
  const ChunkCache& cache() const { return *cache_; }
  uint32_t level() const { return level_; }

 private:
  MoviePlayer(std::shared_ptr<const ChunkSource> source, const MoviePlayerOptions& o, uint32_t level);

  std::shared_ptr<const ChunkSource> source_;
  MoviePlayerOptions options_;
  uint32_t level_;
  std::unique_ptr<ChunkCache> cache_;
  std::unique_ptr<CachedChunkSource> cached_;
  std::vector<std::unique_ptr<TimepointPrefetcher>> prefetch_;  // one per drawn channel
  std::unique_ptr<BrickRenderer> renderer_;
  PlaybackClock clock_;
};

// The finest level of `source` whose chunks of one timepoint (one channel)
// take at most `budget_bytes` decoded; the coarsest when none does.
uint32_t finest_level_within(const ChunkSource& source, uint64_t budget_bytes);

}  // namespace vxr
