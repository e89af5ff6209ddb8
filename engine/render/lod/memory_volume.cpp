#include "render/lod/memory_volume.h"

#include <algorithm>

namespace vxr {

Result<std::unique_ptr<MemoryVolumeRenderer>> MemoryVolumeRenderer::create(gpu::Context& ctx,
                                                                           std::vector<DenseVolume> channels,
                                                                           uint32_t chunk_size,
                                                                           std::shared_ptr<BrickPipelines> pipelines) {
  if (channels.empty() || channels.size() > 4) return invalid_argument("a volume in memory has 1 to 4 channels");
  std::unique_ptr<MemoryVolumeRenderer> r(new MemoryVolumeRenderer());
  r->origin_ = {channels[0].origin[0], channels[0].origin[1], channels[0].origin[2]};
  VXR_ASSIGN_OR_RETURN(r->source_, DenseChunkSource::create(std::move(channels), chunk_size));
  BrickRendererOptions o;
  o.preload_if_fits = true;  // every brick resident from the first frame: deterministic
  o.pipelines = std::move(pipelines);
  // Atlases sized to the volume (every chunk of every level, twice over, at
  // 4 bytes a texel), not the streaming default of 1 GiB.
  uint64_t chunks = 0;
  for (const LevelInfo& l : r->source_->levels())
    chunks += uint64_t(l.chunk_counts[0]) * l.chunk_counts[1] * l.chunk_counts[2];
  const uint64_t edge = r->source_->chunk_size() + 2 * r->source_->apron();
  o.pool.auto_atlas_bytes =
      std::min(o.pool.auto_atlas_bytes, 8 * chunks * edge * edge * edge * 4 * r->source_->info().channels);
  VXR_ASSIGN_OR_RETURN(r->renderer_, BrickRenderer::create(ctx, *r->source_, o));
  return r;
}

Camera MemoryVolumeRenderer::in_volume_frame(const Camera& world) const {
  Camera c = world;
  c.eye -= origin_;
  c.target -= origin_;
  return c;
}

namespace {
// Frames until none misses a brick (with preload: the first).
template <typename Image, typename Draw>
Result<Image> converge(Draw draw, BrickFrameStats* stats_out) {
  BrickFrameStats st;
  for (int i = 0; i < 64; ++i) {
    VXR_ASSIGN_OR_RETURN(Image img, draw(&st));
    if (st.lod.missing == 0) {
      if (stats_out) *stats_out = st;
      return img;
    }
  }
  return internal_error("a volume in memory still missed bricks after 64 frames (the brick pool is too small)");
}
}  // namespace

Result<ImageRgba8> MemoryVolumeRenderer::render(const Camera& camera, const RenderSettings& settings, uint32_t width,
                                                uint32_t height, BrickFrameSettings frame, BrickFrameStats* stats) {
  frame.lod.force_level = 0;
  return converge<ImageRgba8>(
      [&](BrickFrameStats* st) { return renderer_->render(in_volume_frame(camera), settings, frame, width, height, st); }, stats);
}

Result<ImageRgbaF> MemoryVolumeRenderer::render_float(const Camera& camera, const RenderSettings& settings,
                                                      uint32_t width, uint32_t height, BrickFrameSettings frame,
                                                      BrickFrameStats* stats) {
  frame.lod.force_level = 0;
  return converge<ImageRgbaF>(
      [&](BrickFrameStats* st) { return renderer_->render_float(in_volume_frame(camera), settings, frame, width, height, st); }, stats);
}

}  // namespace vxr
