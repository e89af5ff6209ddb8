#include "render/movie_player.h"

#include <chrono>
#include <cmath>

namespace vxr {
namespace {

double ms_since(std::chrono::steady_clock::time_point t0) {
  return std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
}

uint64_t chunks_in_level(const ChunkSource& source, uint32_t level) {
  const auto& c = source.levels()[level].chunk_counts;
  return uint64_t(c[0]) * c[1] * c[2];
}

}  // namespace

uint32_t finest_level_within(const ChunkSource& source, uint64_t budget_bytes) {
  const uint64_t edge = source.chunk_size() + 2ull * source.apron();
  const uint64_t chunk_bytes = edge * edge * edge * dtype_bytes(source.info().dtype);
  const uint32_t levels = uint32_t(source.levels().size());
  for (uint32_t l = 0; l < levels; ++l)
    if (chunks_in_level(source, l) * chunk_bytes <= budget_bytes) return l;
  return levels - 1;
}

MoviePlayer::MoviePlayer(std::shared_ptr<const ChunkSource> source, const MoviePlayerOptions& o, uint32_t level)
    : source_(std::move(source)), options_(o), level_(level),
      clock_(source_->info().timepoints, o.playback) {}

Result<std::unique_ptr<MoviePlayer>> MoviePlayer::create(gpu::Context& ctx, std::shared_ptr<const ChunkSource> source,
                                                         const MoviePlayerOptions& o) {
  if (!source) return invalid_argument("movie player: no source");
  const uint32_t levels = uint32_t(source->levels().size());
  if (o.level >= int(levels))
    return invalid_argument("movie player: level " + std::to_string(o.level) + " does not exist (the volume has " +
                            std::to_string(levels) + ")");
  // Prefetch gets half the cache; the shown timepoint and `prefetch` more must fit in it, every drawn channel.
  const uint32_t channels = o.pool.channels.empty() ? std::min(source->info().channels, 4u)
                                                    : uint32_t(o.pool.channels.size());
  const uint64_t per_timepoint = o.cache_bytes / 2 / (uint64_t(o.prefetch) + 1) / std::max(1u, channels);
  const uint32_t level = o.level >= 0 ? uint32_t(o.level) : finest_level_within(*source, per_timepoint);

  std::unique_ptr<MoviePlayer> p(new MoviePlayer(source, o, level));
  p->cache_ = std::make_unique<ChunkCache>(source, ChunkCacheOptions{.budget_bytes = o.cache_bytes,
                                                                     .loader_threads = o.loader_threads});
  p->cached_ = std::make_unique<CachedChunkSource>(*source, *p->cache_);
  std::vector<uint32_t> drawn = o.pool.channels;
  for (uint32_t c = 0; drawn.size() < channels; ++c) drawn.push_back(c);
  for (uint32_t c : drawn)
    p->prefetch_.push_back(std::make_unique<TimepointPrefetcher>(*p->cache_, *source, level, c, 0.5 / drawn.size()));

  BrickRendererOptions ro;
  ro.pool = o.pool;
  if (ro.pool.slots == glm::uvec3(0)) {
    // Two timepoints of the level: the one drawn and the next, so uploading
    // the next never evicts a brick the current frame draws.
    const uint32_t side = std::max(2u, uint32_t(std::ceil(std::cbrt(2.0 * double(chunks_in_level(*source, level))))));
    ro.pool.slots = {side, side, side};
  }
  VXR_ASSIGN_OR_RETURN(p->renderer_, BrickRenderer::create(ctx, *p->cached_, ro));
  return p;
}

Result<PlaybackFrame> MoviePlayer::frame(double now, const Camera& camera, const RenderSettings& settings,
                                         uint32_t width, uint32_t height, ImageRgba8* image, MovieFrameStats* stats) {
  MovieFrameStats st;
  for (auto& [key, status] : cache_->take_errors())
    if (!status) return status;  // the source names the file and the chunk
  const std::vector<uint32_t> upcoming = clock_.upcoming(options_.prefetch + 1);
  for (auto& p : prefetch_) p->update(upcoming);
  const PlaybackFrame f = clock_.tick(now, [this](uint32_t t) {
    for (const auto& p : prefetch_)
      if (!p->ready(t)) return false;
    return true;
  });
  if (f.is_new) {
    VXR_RETURN_IF_ERROR(renderer_->prepare(settings));
    BrickFrameSettings frame;
    frame.lod.timepoint = f.timepoint;
    frame.lod.force_level = int(level_);
    // Upload the whole timepoint first (decoded already, so this is a copy
    // into the atlas), then one render pass draws it complete.
    const auto t0 = std::chrono::steady_clock::now();
    BrickPool& pool = renderer_->pool();
    pool.begin_frame();
    std::vector<ChunkKey> keys = prefetch_.front()->keys(f.timepoint);  // a brick key names every channel
    std::erase_if(keys, [&pool](const ChunkKey& k) { return pool.resident(k); });  // shown before (looping)
    while (!keys.empty()) {
      VXR_ASSIGN_OR_RETURN(UploadStats up, pool.upload(keys, UINT64_MAX));
      if (up.bricks == 0) return internal_error("movie player: the brick pool accepted no brick");
      keys.erase(keys.begin(), keys.begin() + up.bricks);
    }
    st.upload_ms = ms_since(t0);
    const auto t1 = std::chrono::steady_clock::now();
    BrickFrameStats bs;
    do {
      VXR_RETURN_IF_ERROR(renderer_->render_into(*image, camera, settings, frame, width, height, &bs));
      ++st.passes;
    } while (bs.lod.missing > 0 && st.passes < 16);
    if (bs.lod.missing > 0)
      return internal_error("movie player: timepoint " + std::to_string(f.timepoint) + " still misses " +
                            std::to_string(bs.lod.missing) + " bricks after 16 passes (brick pool too small)");
    st.render_ms = ms_since(t1);
  }
  if (stats) *stats = st;
  return f;
}

}  // namespace vxr
