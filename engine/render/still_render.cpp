#include "render/still_render.h"

#include <chrono>
#include <cmath>
#include <memory>

#include "render/annotation_renderer.h"
#include "render/reference_renderer.h"
#include "volume/container_reader.h"
#include "volume/load_dense.h"

namespace vxr {
namespace {

double ms_since(std::chrono::steady_clock::time_point t0) {
  return std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
}

// The reference's options for `step` with the settings' cut plane and box,
// clipped as the bricks are.
ReferenceOptions clipped_reference(const RenderSettings& s, const std::array<uint64_t, 3>& dims, double step) {
  ReferenceOptions ro{step, 0};
  LodSettings clip;
  apply_clip(s.clip, dims, clip);
  if (clip.cut.enabled) ro.plane = glm::dvec4(clip.cut.normal, clip.cut.offset);
  if (clip.roi.enabled) {
    ro.clip_lo = clip.roi.lo;
    ro.clip_hi = clip.roi.hi;
  }
  return ro;
}

// The CPU reference of the finest level of the drawn channels, over black.
Result<std::vector<uint8_t>> reference_pixels(const VolumeSession& session, const Camera& camera, const StillOptions& o,
                                              double* cpu_ms) {
  std::vector<DenseVolume> level0;
  for (uint32_t c : session.channels) {
    VXR_ASSIGN_OR_RETURN(DenseVolume dense, read_level_dense(*session.source, 0, c, session.timepoint, uint64_t(1) << 30));
    level0.push_back(std::move(dense));
  }
  const auto t0 = std::chrono::steady_clock::now();
  const ReferenceOptions ro = clipped_reference(session.settings, session.source->info().dims, o.reference_step);
  VXR_ASSIGN_OR_RETURN(ImageRgbaF ref, render_reference(level0, camera, session.settings, o.width, o.height, ro));
  *cpu_ms = ms_since(t0);
  return over_black(to_rgba8(ref)).pixels;
}

}  // namespace

Result<StillResult> render_still(gpu::Context& gpu, const VolumeSession& session, const Camera& camera,
                                 const StillOptions& o) {
  const RenderSettings& s = session.settings;
  VXR_RETURN_IF_ERROR(check_brick_settings(s, static_cast<uint32_t>(session.channels.size())));
  BrickRendererOptions ro;
  ro.pool.channels = session.channels;
  ro.preload_if_fits = true;  // small volumes: every brick in the slots vxr view gives them (same pixels)
  VXR_ASSIGN_OR_RETURN(std::unique_ptr<BrickRenderer> renderer, BrickRenderer::create(gpu, *session.source, ro));
  BrickRenderer& r = *renderer;
  // Annotations: drawn first in each frame's command buffer; rays end at them.
  std::unique_ptr<AnnotationRenderer> annotation_renderer;
  AnnotationScene annotations;
  BrickRenderer::UnderlayRecorder underlay;
  if (!session.annotation_store.empty()) {
    VXR_ASSIGN_OR_RETURN(annotations, load_annotation_scene(session.annotation_store, r.placement(), session.timepoint));
    VXR_ASSIGN_OR_RETURN(annotation_renderer, AnnotationRenderer::create(gpu));
    underlay = [&](VkCommandBuffer cmd) {
      return annotation_renderer->record(cmd, 0, camera, annotations, o.width, o.height);
    };
  }

  StillResult out;
  std::vector<uint8_t> reference;
  if (o.compare_to_reference) {
    VXR_ASSIGN_OR_RETURN(reference, reference_pixels(session, camera, o, &out.reference_cpu_ms));
  }
  BrickFrameSettings frame;
  frame.lod.lod_bias = o.lod_bias;
  frame.lod.timepoint = session.timepoint;
  frame.lod.skip_empty = o.skip_empty;
  apply_clip(s.clip, session.source->info().dims, frame.lod);
  const bool budget = o.frame_budget_ms > 0.0;
  FrameBudget controller;
  controller.target_ms = o.frame_budget_ms;
  controller.bias = o.lod_bias;
  const int max_frames = o.frames > 0 ? o.frames : budget ? 30 : 1000;
  // create() uploaded the pinned bricks (top level; every brick of a volume that fits).
  out.bricks_uploaded = r.pool().used();
  out.bytes_uploaded = out.bricks_uploaded * r.pool().brick_bytes();
  const auto t0 = std::chrono::steady_clock::now();
  while (int(out.frames.size()) < max_frames) {
    if (budget) frame.lod.lod_bias = controller.bias;
    const auto f0 = std::chrono::steady_clock::now();
    VXR_RETURN_IF_ERROR(r.render_into(out.image, camera, s, frame, o.width, o.height, &out.last, underlay));
    StillFrame f;
    f.wall_ms = ms_since(f0);
    f.frame = int(out.frames.size()) + 1;
    f.gpu_ms = out.last.gpu_ms;
    f.lod_bias = frame.lod.lod_bias;
    f.samples = out.last.samples;
    f.bricks_drawn = out.last.lod.drawn;
    f.bricks_missing = out.last.lod.missing;
    f.bricks_uploaded = out.last.bricks_uploaded;
    if (!reference.empty()) f.rmse_vs_reference = compare_pixels(over_black(out.image).pixels, reference).rmse;
    out.frames.push_back(f);
    out.bytes_uploaded += out.last.bytes_uploaded;
    out.bricks_uploaded += out.last.bricks_uploaded;
    if (o.on_frame) o.on_frame(f);
    if (budget) {
      controller.update(f.wall_ms);
      continue;
    }
    out.converged = out.last.lod.missing == 0;
    if (out.converged && o.frames == 0) break;
  }
  out.total_ms = ms_since(t0);
  out.pool_used = r.pool().used();
  out.pool_capacity = r.pool().capacity();
  if (!budget && o.frames == 0 && !out.converged)
    return internal_error("the view still missed bricks after " + std::to_string(out.frames.size()) +
                          " frames; raise --lod-bias or render fewer pixels");
  return out;
}

Result<ReferenceStill> render_still_reference(const std::string& input, const SessionFlags& given_flags,
                                              const CameraChooser& camera_for, const ReferenceStillOptions& o,
                                              SessionStep* failed_at) {
  SessionStep step_unused;
  SessionStep& step = failed_at ? *failed_at : step_unused;
  step = SessionStep::kSettings;
  VXR_ASSIGN_OR_RETURN(const SessionFlags flags, complete_session_flags(given_flags));
  VXR_ASSIGN_OR_RETURN(SettingsChoice choice, choose_settings(flags));
  step = SessionStep::kSource;
  VXR_ASSIGN_OR_RETURN(LoadedVolume loaded, load_for_render(input, o.max_dim, uint64_t(1) << 30));
  ReferenceStill out;
  out.notes = loaded.notes;
  out.shrink = loaded.shrink;
  step = SessionStep::kChannels;
  std::vector<DenseVolume>& channels = loaded.channels;
  VXR_RETURN_IF_ERROR(apply_voxel_size_flag(flags, loaded.shrink, channels));
  VXR_ASSIGN_OR_RETURN(DrawnSettings drawn,
                       resolve_drawn_settings(std::move(choice), flags, input, static_cast<uint32_t>(channels.size()), 1,
                                              [&](uint32_t c) -> Result<std::pair<double, double>> {
                                                return percentile_window(channels[c]);
                                              },
                                              loaded.channel_display));
  for (std::string& n : drawn.notes) out.notes.push_back(std::move(n));
  std::vector<DenseVolume> picked;
  for (uint32_t c : drawn.channels) picked.push_back(std::move(channels[c]));
  out.settings = std::move(drawn.settings);
  out.channels = std::move(drawn.channels);
  const VolumePlacement placement{picked[0].dims, picked[0].voxel_size};
  VXR_ASSIGN_OR_RETURN(out.camera, camera_for(placement, picked[0].dims[2] == 1));

  const auto t0 = std::chrono::steady_clock::now();
  const std::array<uint64_t, 3> dims{picked[0].dims[0], picked[0].dims[1], picked[0].dims[2]};
  VXR_ASSIGN_OR_RETURN(ImageRgbaF image,
                       render_reference(picked, out.camera, out.settings, o.width, o.height,
                                        clipped_reference(out.settings, dims, o.reference_step)));
  out.ms = ms_since(t0);
  out.image = to_rgba8(image);
  // The reference keeps no counters: the samples are counted from the rays, before early termination.
  out.sample_bound = dense_sample_count(out.camera, placement, out.settings.step_voxels, o.width, o.height);
  return out;
}

}  // namespace vxr
