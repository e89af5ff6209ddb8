// The frame loop every target shares, inside an outer restart loop
// (hello_xr's shape):
//
//   for each (re)start: make the target -> Vulkan context (target's hooks)
//     -> attach -> chunk cache (loader threads) + eye renderer
//     frame loop: wait_frame -> interaction -> ONE command buffer: brick
//                 uploads that arrived, then every view (lens warp
//                 included) recorded into the target's images, then what
//                 the target draws itself (record_after_views: the desktop
//                 viewer's blit and panels) -> one submit -> end_frame
//   a target with its own controls (FrameState::settings) changes the
//   settings and timepoint the next views are drawn with
//   a lost session/instance (wants_restart) tears everything down in order
//   and starts again; any other error ends the run with its message.
//
// No frame reads anything back or waits for I/O: missing bricks are asked of
// the ChunkCache's loader threads and their resident ancestors drawn until
// they arrive. With a frame budget the LOD bias follows the frame time.
//
// The volume transform and frame count live outside the restart loop, so a
// recovered session continues where the lost one stopped.
#pragma once

#include <functional>
#include <memory>
#include <nlohmann/json_fwd.hpp>
#include <optional>
#include <string>
#include <vector>

#include "render/annotation_renderer.h"
#include "render/lod/brick_renderer.h"
#include "render/volume_session.h"
#include "xr/cut_plane_tool.h"
#include "xr/frame_target.h"
#include "xr/hand_tools.h"
#include "xr/interaction.h"
#include "xr/lens_warp.h"
#include "xr/teleport.h"
#include "xr/volume_transform.h"

namespace vxr::xr {

struct ViewOptions {
  uint64_t frames = 0;  // rendered frames before an orderly exit; 0: until the target ends
  RenderSettings settings = default_view_settings();
  LensWarp warp;
  // LOD settings and per-frame upload budget. frame.lod.cut is where the
  // cut plane starts (a card's, cut_plane_of(Scene::cut)); the hands' cut
  // tool moves or clears it from there.
  BrickFrameSettings frame;
  double frame_budget_ms = 0.0;  // > 0: the LOD bias follows the frame time towards this
  uint64_t cache_bytes = uint64_t(1) << 30;  // decoded chunks kept on the CPU
  uint32_t loader_threads = 2;
  int max_restarts = 3;
  std::vector<uint32_t> channels;  // source channels drawn; empty: the first up to 4
  // Drawn with every view (world units, volume frame; load_annotation_scene). Empty: none.
  AnnotationScene annotations;
  // Called after each rendered frame (its command buffer has completed).
  std::function<void(uint64_t frame)> on_frame;
  // The store the hands' tools edit (xr/hand_tools.h); the session holds it
  // and draws it (then `annotations` is not used). Null: no hand tools.
  std::shared_ptr<annotate::AnnotationStore> tool_store;
  HandToolSettings hand_tools;
  // Told one line when the tool changes or an edit is stored (null: log_info).
  std::function<void(const std::string& line)> on_tool_report;
  // A ray caster camera (volume frame), e.g. a restored card's: the first
  // rendered frame places the volume so that the head sees what it sees
  // (transform_placing_camera, at the initial transform's scale). Targets that
  // draw ViewSpec::camera themselves (headless --card) leave it empty.
  std::optional<Camera> place_for_camera;
  TeleportSettings teleport;
  CutPlaneSettings cut;
};

struct ViewStats {
  std::string target;          // describe() of the last target
  std::string device_fingerprint;  // of the Vulkan device the frames were rendered on
  uint64_t frames_rendered = 0;
  uint64_t frames_submitted = 0;  // including frames the runtime said not to render
  uint64_t frames_complete = 0;   // rendered with every view drawn into its image
  uint64_t frames_full_detail = 0;  // ... and no wanted brick missing (nothing drawn from an ancestor)
  int restarts = 0;
  double mean_frame_ms = 0.0;  // per rendered frame: record + submit + GPU, wall clock
  double max_frame_ms = 0.0;
  std::vector<double> frame_ms;  // every rendered frame's time, in order
  std::vector<double> lod_bias;  // the LOD bias each rendered frame used
  std::vector<uint64_t> frame_missing;  // bricks each rendered frame drew from an ancestor (still streaming)
  uint64_t rays = 0;
  uint64_t bricks_skipped_empty = 0;  // over every drawn view: bricks the traversal dropped as empty (none with skipping off)
  uint64_t pipelines_first_frame = 0;        // pipelines built up to the end of frame 1
  uint64_t pipelines_after_first_frame = 0;  // built after it (poses must build none)
  uint64_t readbacks = 0;                    // image readbacks during the frames (PNG output only)
  uint64_t bricks_uploaded = 0;
  VolumeTransform transform;   // where the interaction left the volume
  uint64_t teleports = 0;      // jumps the teleport made
  CutPlane cut;                // where the cut tool left the plane (voxel coordinates; disabled: none)
};

// p50/p99 frame ms, frames complete, pipelines after frame 1, readbacks per
// frame: the figures `vxr view --json` writes.
nlohmann::json view_stats_json(const ViewStats& stats, const ViewOptions& options);

using TargetFactory = std::function<Result<std::unique_ptr<FrameTarget>>()>;

Result<ViewStats> run_view(const TargetFactory& make_target, std::shared_ptr<const ChunkSource> source,
                           const ViewOptions& options, const VolumeTransform& initial);

}  // namespace vxr::xr
