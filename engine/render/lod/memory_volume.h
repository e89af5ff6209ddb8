// Volumes already in memory drawn by the one renderer: a DenseChunkSource
// under a BrickRenderer with every brick resident, always at full resolution
// (LOD level 0). A small volume is the one-brick case of the out-of-core
// renderer; this is what tests, benchmarks and the CPU-reference comparisons
// draw DenseVolumes with (there is no separate dense ray caster).
#pragma once

#include <memory>
#include <vector>

#include "core/image.h"
#include "core/status.h"
#include "gpu/context.h"
#include "render/lod/brick_renderer.h"
#include "volume/dense_chunk_source.h"

namespace vxr {

class MemoryVolumeRenderer {
 public:
  // 1-4 channels of the same dims and dtype. `chunk_size`: brick edge in
  // voxels (64: one brick for volumes up to 64 per side). `pipelines`:
  // compiled shader variants shared with other renderers on `ctx` (many
  // small volumes in a row), or null.
  static Result<std::unique_ptr<MemoryVolumeRenderer>> create(gpu::Context& ctx, std::vector<DenseVolume> channels,
                                                              uint32_t chunk_size = 64,
                                                              std::shared_ptr<BrickPipelines> pipelines = nullptr);

  // One converged frame (every brick of level 0 drawn). `frame`'s LOD level
  // is forced to 0; its clip, pass mode and skipping are used as given.
  // `camera` is in world units; the volumes' origin (their box centre) places
  // them there, as render_reference does: the camera moves by it in double.
  Result<ImageRgba8> render(const Camera& camera, const RenderSettings& settings, uint32_t width, uint32_t height,
                            BrickFrameSettings frame = {}, BrickFrameStats* stats = nullptr);
  Result<ImageRgbaF> render_float(const Camera& camera, const RenderSettings& settings, uint32_t width,
                                  uint32_t height, BrickFrameSettings frame = {}, BrickFrameStats* stats = nullptr);

  BrickRenderer& bricks() { return *renderer_; }
  VolumePlacement placement() const { return renderer_->placement(); }

 private:
  MemoryVolumeRenderer() = default;
  Camera in_volume_frame(const Camera& world) const;
  glm::dvec3 origin_{0.0};
  std::shared_ptr<DenseChunkSource> source_;  // outlives renderer_ (declared first)
  std::unique_ptr<BrickRenderer> renderer_;
};

}  // namespace vxr
