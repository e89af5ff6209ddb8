#include "xr/view_session.h"

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <nlohmann/json.hpp>
#include <optional>

#include "core/log.h"
#include "core/trace.h"
#include "gpu/resources.h"
#include "gpu/vk_check.h"
#include "xr/eye_renderer.h"

namespace vxr::xr {
namespace {

enum class Outcome { kDone, kRestart };

// The frame's one command buffer and the fence its submission signals.
struct FrameCommands {
  gpu::Handle<VkCommandPool> pool;
  gpu::Handle<VkFence> fence;
  VkCommandBuffer cmd = VK_NULL_HANDLE;

  Status create(gpu::Context& ctx) {
    VkCommandPoolCreateInfo pci{VK_STRUCTURE_TYPE_COMMAND_POOL_CREATE_INFO};
    pci.flags = VK_COMMAND_POOL_CREATE_RESET_COMMAND_BUFFER_BIT;
    pci.queueFamilyIndex = ctx.queue_family();
    VkCommandPool p = VK_NULL_HANDLE;
    VXR_VK_TRY(vkCreateCommandPool(ctx.device(), &pci, nullptr, &p));
    pool = gpu::Handle<VkCommandPool>(ctx.device(), p);
    VkCommandBufferAllocateInfo ai{VK_STRUCTURE_TYPE_COMMAND_BUFFER_ALLOCATE_INFO};
    ai.commandPool = pool;
    ai.level = VK_COMMAND_BUFFER_LEVEL_PRIMARY;
    ai.commandBufferCount = 1;
    VXR_VK_TRY(vkAllocateCommandBuffers(ctx.device(), &ai, &cmd));
    VkFenceCreateInfo fci{VK_STRUCTURE_TYPE_FENCE_CREATE_INFO};
    VkFence f = VK_NULL_HANDLE;
    VXR_VK_TRY(vkCreateFence(ctx.device(), &fci, nullptr, &f));
    fence = gpu::Handle<VkFence>(ctx.device(), f);
    return Status::ok();
  }
  Status begin() {
    VXR_VK_TRY(vkResetCommandBuffer(cmd, 0));
    VkCommandBufferBeginInfo bi{VK_STRUCTURE_TYPE_COMMAND_BUFFER_BEGIN_INFO};
    bi.flags = VK_COMMAND_BUFFER_USAGE_ONE_TIME_SUBMIT_BIT;
    VXR_VK_TRY(vkBeginCommandBuffer(cmd, &bi));
    return Status::ok();
  }
  // Submits and waits: the swapchain images are released (and the next frame
  // reuses the renderer's per-frame buffers) only after the rays have run.
  Status submit_and_wait(gpu::Context& ctx, const FrameSubmit& sync) {
    VXR_VK_TRY(vkEndCommandBuffer(cmd));
    VkFence f = fence;
    VXR_VK_TRY(vkResetFences(ctx.device(), 1, &f));
    const std::vector<VkPipelineStageFlags> stages(sync.wait.size(), VK_PIPELINE_STAGE_ALL_COMMANDS_BIT);
    VkSubmitInfo si{VK_STRUCTURE_TYPE_SUBMIT_INFO};
    si.waitSemaphoreCount = uint32_t(sync.wait.size());
    si.pWaitSemaphores = sync.wait.data();
    si.pWaitDstStageMask = stages.data();
    si.signalSemaphoreCount = uint32_t(sync.signal.size());
    si.pSignalSemaphores = sync.signal.data();
    si.commandBufferCount = 1;
    si.pCommandBuffers = &cmd;
    VXR_VK_TRY(vkQueueSubmit(ctx.queue(), 1, &si, f));
    VXR_VK_TRY(vkWaitForFences(ctx.device(), 1, &f, VK_TRUE, UINT64_MAX));
    return Status::ok();
  }
};

// The hands' tools over the store the session holds, and the scene drawn from it.
struct SessionTools {
  HandTools& hands;
  const ViewOptions& options;
  uint64_t drawn_revision = UINT64_MAX;  // of the store scene below (per run: the eyes are new)
  uint32_t drawn_timepoint = 0;
  annotate::Tool drawn_tool = annotate::Tool::kCount;
  AnnotationScene stored;

  void report(const std::string& line) const {
    if (options.on_tool_report) options.on_tool_report(line);
    else log_info("view: " + line);
  }
  // Applies this frame's input; the eyes get the store's scene (re-read after
  // an edit) and what is live over it.
  Status frame(const FrameState& f, const VolumeTransform& t, uint32_t timepoint, FrameTarget& target,
               EyeRenderer& eyes, const std::optional<AnnotationSphere>& marker) {
    const HandToolFrame r = hands.update(f.input, t, timepoint);
    if (r.stored || r.picked) target.haptic_pulse(r.hand, 0.3, 0.01);
    if (!r.error.empty()) report(std::string("tool ") + annotate::tool_name(hands.tool()) + ": " + r.error);
    if (r.stored || r.tool_changed || r.picked) report(hands.report());
    if (hands.tools().revision() != drawn_revision || timepoint != drawn_timepoint || hands.tool() != drawn_tool) {
      // A store unreadable from the start ends the run; later, the last picture stays and says why.
      auto scene = hands.stored_scene(timepoint);
      if (!scene && drawn_revision == UINT64_MAX) return scene.status();
      if (scene) stored = std::move(scene).value();
      else log_warn("view: " + hands.tools().store().path() + ": " + scene.status().message());
      drawn_revision = hands.tools().revision();
      drawn_timepoint = timepoint;
      drawn_tool = hands.tool();
    }
    AnnotationScene scene = stored;
    hands.add_live(f.input, t, scene);
    if (marker) scene.spheres.push_back(*marker);
    return eyes.set_annotations(std::move(scene), /*make_pass=*/true);
  }
};

// The teleport's target as a ball 2 cm across whatever the zoom, in the volume frame.
std::optional<AnnotationSphere> teleport_marker(const Teleport& teleport, const VolumeTransform& t) {
  if (!teleport.target()) return std::nullopt;
  return AnnotationSphere{*teleport.target(), 0.01 / t.scale, glm::vec4(0.3f, 0.6f, 1.0f, 1.0f)};
}

// What moves the volume (and the cut plane) before a frame is drawn, kept across restarts.
struct Motion {
  GrabInteraction grab;
  Teleport teleport;
  CutPlaneTool cut;
  bool placed = false;  // ViewOptions::place_for_camera applied
  // Without a store (no HandTools) the menu's cycle is off -> cut: the
  // triggers do nothing until the menu turns the cut plane on.
  bool storeless_cut = false;
  bool menu_down = false;
};

// "cut plane: normal (x, y, z), offset d (voxels)" or "cut plane: cleared".
std::string describe_cut(const CutPlane& c) {
  if (!c.enabled) return "cut plane: cleared";
  char line[160];
  std::snprintf(line, sizeof line, "cut plane: normal (%.6f, %.6f, %.6f), offset %.6f (voxels)", c.normal.x,
                c.normal.y, c.normal.z, c.offset);
  return line;
}

void report_line(const ViewOptions& options, const std::string& line) {
  if (options.on_tool_report) options.on_tool_report(line);
  else log_info("view: " + line);
}

// The cut tool's frame: it holds the triggers while the cycle is on "cut"
// (HandTools' cycle, or without a store the menu's off -> cut).
void update_cut(const FrameState& f, const VolumeTransform& t, const HandTools* hands, const ViewOptions& options,
                FrameTarget& target, Motion& motion) {
  if (!hands) {
    const bool menu = f.input.hands[kLeft].menu || f.input.hands[kRight].menu;
    if (menu && !motion.menu_down) {
      motion.storeless_cut = !motion.storeless_cut;
      report_line(options, motion.storeless_cut ? "tool cut" : "tool none");
    }
    motion.menu_down = menu;
  }
  const bool active = hands ? hands->cutting() : motion.storeless_cut;
  const CutPlaneFrame r = motion.cut.update(f.input, t, active);
  if (!r.placed && !r.cleared) return;
  target.haptic_pulse(r.placed ? kRight : kLeft, 0.3, 0.01);
  report_line(options, describe_cut(motion.cut.plane()));
}

// One run of a target: returns kRestart when the target lost its session.
Result<Outcome> run_once(FrameTarget& target, const std::shared_ptr<const ChunkSource>& source,
                         const ViewOptions& options, Motion& motion, FrameBudget& budget, HandTools* hands,
                         ViewStats& stats) {
  gpu::ContextOptions copts = gpu::ContextOptions::from_env();
  VXR_RETURN_IF_ERROR(target.prepare_context(copts));
  VXR_ASSIGN_OR_RETURN(std::unique_ptr<gpu::Context> ctx, gpu::Context::create(copts));
  stats.device_fingerprint = ctx->info().fingerprint();
  // Everything tied to the device goes before it: renderer and cache, then the target's objects.
  struct Detach {
    FrameTarget& t;
    ~Detach() { t.detach(); }
  };
  FrameCommands commands;
  std::unique_ptr<EyeRenderer> eyes;
  Detach detach{target};
  ChunkCache cache(source, {options.cache_bytes, options.loader_threads});
  struct CacheHook {  // the target lets go of the cache before it dies
    FrameTarget& t;
    ~CacheHook() { t.use_chunk_cache(nullptr, nullptr); }
  };
  CacheHook cache_hook{target};
  VXR_RETURN_IF_ERROR(target.attach(*ctx));
  target.use_chunk_cache(&cache, source.get());
  VXR_ASSIGN_OR_RETURN(eyes, EyeRenderer::create(*ctx, source, &cache, options.channels));
  std::optional<SessionTools> tools;
  // The annotation pass is made up front (the teleport's marker needs it too), so no frame builds it.
  if (hands) tools.emplace(SessionTools{*hands, options});
  VXR_RETURN_IF_ERROR(eyes->set_annotations(hands ? AnnotationScene{} : options.annotations, /*make_pass=*/true));
  bool marker_drawn = false;  // without hand tools: the teleport's marker is over options.annotations
  // Pool changes the settings need (apron 2 for gradients) before any frame records.
  VXR_RETURN_IF_ERROR(eyes->renderer().prepare(options.settings));
  VXR_RETURN_IF_ERROR(commands.create(*ctx));
  stats.target = target.describe();

  bool exit_requested = false;
  // The settings the last frame drew: a target's edits are checked once, when they change.
  RenderSettings drawn_settings = options.settings;
  int64_t last_display_ns = 0;
  double total_ms = 0.0;
  Pose head;  // the last frame's with views (a frame without views keeps it)
  for (;;) {
    VXR_TRACE_SCOPE("xr.frame");
    auto frame = target.wait_frame();
    if (!frame) return target.wants_restart() ? Result<Outcome>(Outcome::kRestart) : frame.status();
    if (frame->exit) {
      stats.target = target.describe();
      return Outcome::kDone;
    }
    const auto t0 = std::chrono::steady_clock::now();
    const uint64_t readbacks_before = gpu::readback_count();

    // Seconds since the last frame's display time, for thumbstick flight (capped: a stall is not a jump).
    const double dt = last_display_ns > 0 && frame->display_time_ns > last_display_ns
                          ? std::min(0.1, double(frame->display_time_ns - last_display_ns) * 1e-9)
                          : 0.0;
    last_display_ns = frame->display_time_ns;
    if (!frame->views.empty()) head = head_of_views(frame->views);
    if (options.place_for_camera && !motion.placed && frame->should_render && !frame->views.empty()) {
      stats.transform = transform_placing_camera(*options.place_for_camera, head, stats.transform.scale);
      motion.placed = true;
    }
    const auto started = motion.grab.update(frame->input, stats.transform, dt);
    for (int h = 0; h < 2; ++h)
      if (started[h]) target.haptic_pulse(Hand(h), 0.5, 0.02);
    const TeleportFrame jump = motion.teleport.update(frame->input, head, stats.transform);
    if (jump.moved) {
      target.haptic_pulse(jump.hand, 0.5, 0.02);
      ++stats.teleports;
    }
    const std::optional<AnnotationSphere> marker = teleport_marker(motion.teleport, stats.transform);

    BrickFrameSettings fs = options.frame;
    if (options.frame_budget_ms > 0.0) fs.lod.lod_bias = budget.bias;
    fs.lod.lod_bias += frame->lod_bias_offset;
    if (frame->settings) fs.lod.timepoint = std::min(frame->timepoint, source->info().timepoints - 1);
    if (tools) {
      VXR_RETURN_IF_ERROR(tools->frame(*frame, stats.transform, fs.lod.timepoint, target, *eyes, marker));
    } else if (marker || marker_drawn) {
      AnnotationScene scene = options.annotations;
      if (marker) scene.spheres.push_back(*marker);
      VXR_RETURN_IF_ERROR(eyes->set_annotations(std::move(scene), /*make_pass=*/true));
      marker_drawn = marker.has_value();
    }
    update_cut(*frame, stats.transform, hands, options, target, motion);  // after the menu's cycle
    if (frame->settings && !(*frame->settings == drawn_settings)) {
      // An edit the brick renderer cannot draw keeps the last picture and says why.
      Status ok = check_brick_settings(*frame->settings, eyes->renderer().channels());
      if (ok) ok = eyes->renderer().prepare(*frame->settings);
      if (ok)
        drawn_settings = *frame->settings;
      else
        log_warn("view: settings not applied: " + ok.message());
    }
    const RenderSettings& settings = drawn_settings;
    apply_clip(settings.clip, source->info().dims, fs.lod);  // the settings' cut plane and box (panels, cards)
    if (motion.cut.owns_plane()) fs.lod.cut = motion.cut.plane();  // the hands' plane, once they set one
    stats.cut = fs.lod.cut;
    size_t views_drawn = 0;
    uint64_t missing = 0;
    if (frame->should_render) {
      VXR_RETURN_IF_ERROR(commands.begin());
      VXR_RETURN_IF_ERROR(eyes->begin_frame(commands.cmd, fs));
      for (size_t v = 0; v < frame->views.size(); ++v) {
        auto image = target.acquire(v);
        if (!image) return target.wants_restart() ? Result<Outcome>(Outcome::kRestart) : image.status();
        uint64_t rays = 0;
        BrickFrameStats st;
        VXR_RETURN_IF_ERROR(eyes->record(commands.cmd, v, frame->views[v], stats.transform, settings, fs,
                                         options.warp, *image, &rays, &st));
        stats.rays += rays;
        stats.bricks_skipped_empty += st.lod.skipped_empty;
        missing += st.lod.missing;
        if (v == 0) stats.bricks_uploaded += st.bricks_uploaded;
        ++views_drawn;
      }
      FrameSubmit sync;
      if (Status s = target.record_after_views(commands.cmd, sync); !s)
        return target.wants_restart() ? Result<Outcome>(Outcome::kRestart) : Result<Outcome>(s);
      VXR_RETURN_IF_ERROR(commands.submit_and_wait(*ctx, sync));
    }
    const double ms = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
    FrameContent content;
    content.focus_point = stats.transform.position;
    if (Status s = target.end_frame(*frame, content); !s)
      return target.wants_restart() ? Result<Outcome>(Outcome::kRestart) : Result<Outcome>(s);
    ++stats.frames_submitted;
    if (frame->should_render) {
      stats.readbacks += gpu::readback_count() - readbacks_before;
      total_ms += ms;
      stats.frame_ms.push_back(ms);
      stats.lod_bias.push_back(fs.lod.lod_bias);
      stats.frame_missing.push_back(missing);
      stats.max_frame_ms = std::max(stats.max_frame_ms, ms);
      stats.mean_frame_ms = total_ms / double(stats.frame_ms.size());
      if (views_drawn == frame->views.size() && views_drawn > 0) {
        ++stats.frames_complete;
        if (missing == 0) ++stats.frames_full_detail;
      }
      if (options.frame_budget_ms > 0.0) budget.update(ms);
      if (stats.frames_rendered == 0) stats.pipelines_first_frame = ctx->pipelines_built();
      stats.pipelines_after_first_frame = ctx->pipelines_built() - stats.pipelines_first_frame;
      if (options.on_frame) options.on_frame(stats.frames_rendered);
      ++stats.frames_rendered;
    }
    if (options.frames > 0 && stats.frames_rendered >= options.frames && !exit_requested) {
      target.request_exit();
      exit_requested = true;
    }
  }
}

double percentile(std::vector<double> v, double p) {
  if (v.empty()) return 0.0;
  std::sort(v.begin(), v.end());
  const size_t i = std::min(v.size() - 1, size_t(p * double(v.size() - 1) + 0.5));
  return v[i];
}

}  // namespace

nlohmann::json view_stats_json(const ViewStats& s, const ViewOptions& o) {
  nlohmann::json j;
  j["target"] = s.target;
  j["device"] = s.device_fingerprint;
  j["frames_rendered"] = s.frames_rendered;
  j["frames_complete"] = s.frames_complete;
  j["frames_full_detail"] = s.frames_full_detail;
  j["restarts"] = s.restarts;
  j["p50_frame_ms"] = percentile(s.frame_ms, 0.50);
  j["p99_frame_ms"] = percentile(s.frame_ms, 0.99);
  j["mean_frame_ms"] = s.mean_frame_ms;
  j["max_frame_ms"] = s.max_frame_ms;
  j["frame_budget_ms"] = o.frame_budget_ms;
  if (o.frame_budget_ms > 0.0) {
    // The controller needs a few frames to find the bias: judge the second half.
    std::vector<double> tail(s.frame_ms.begin() + std::ptrdiff_t(s.frame_ms.size() / 2), s.frame_ms.end());
    j["p50_frame_ms_second_half"] = percentile(tail, 0.50);
    size_t within = 0;
    for (double ms : tail) within += ms <= o.frame_budget_ms ? 1 : 0;
    j["second_half_within_budget"] = tail.empty() ? 0.0 : double(within) / double(tail.size());
    j["final_lod_bias"] = s.lod_bias.empty() ? 0.0 : s.lod_bias.back();
  }
  j["pipelines_first_frame"] = s.pipelines_first_frame;
  j["pipelines_after_first_frame"] = s.pipelines_after_first_frame;
  j["readbacks_per_frame"] = s.frames_rendered ? double(s.readbacks) / double(s.frames_rendered) : 0.0;
  j["submits_per_frame"] = 1;
  j["rays"] = s.rays;
  j["empty_space_skipping"] = o.frame.lod.skip_empty;
  j["bricks_skipped_empty"] = s.bricks_skipped_empty;
  j["bricks_uploaded"] = s.bricks_uploaded;
  j["lens_warp"] = o.warp.enabled;
  j["frame_ms"] = s.frame_ms;
  return j;
}

Result<ViewStats> run_view(const TargetFactory& make_target, std::shared_ptr<const ChunkSource> source,
                           const ViewOptions& options, const VolumeTransform& initial) {
  if (!source) return invalid_argument("view: no volume");
  VXR_RETURN_IF_ERROR(check_brick_settings(options.settings, uint32_t(std::max<size_t>(1, options.channels.size()))));
  ViewStats stats;
  stats.transform = initial;
  // Outside the restart loop: a recovered session keeps the tool and what it was drawing.
  std::unique_ptr<ViewerTools> viewer_tools;
  std::unique_ptr<HandTools> hands;
  const VolumeInfo& info = source->info();
  const VolumePlacement placement{{uint32_t(info.dims[0]), uint32_t(info.dims[1]), uint32_t(info.dims[2])},
                                  info.voxel_size};
  if (options.tool_store) {
    viewer_tools = std::make_unique<ViewerTools>(*options.tool_store);
    hands = std::make_unique<HandTools>(*viewer_tools, placement, options.hand_tools);
  }
  Motion motion{GrabInteraction(), Teleport(placement, options.teleport), CutPlaneTool(placement, options.cut)};
  // The hands start from the caller's plane if any, else the settings' (which keep deciding until the hands act).
  LodSettings start_clip;
  apply_clip(options.settings.clip, info.dims, start_clip);
  const bool given = options.frame.lod.cut.enabled;
  motion.cut.set_plane(given ? options.frame.lod.cut : start_clip.cut, given);
  stats.cut = motion.cut.plane();
  FrameBudget budget;
  budget.target_ms = options.frame_budget_ms;
  budget.bias = options.frame.lod.lod_bias;
  for (;;) {
    std::unique_ptr<FrameTarget> target;
    VXR_ASSIGN_OR_RETURN(target, make_target());
    auto outcome = run_once(*target, source, options, motion, budget, hands.get(), stats);
    if (!outcome) {
      if (!target->wants_restart()) return outcome.status();
      log_warn("XR: " + outcome.status().message());
    } else if (*outcome == Outcome::kDone) {
      return stats;
    }
    if (stats.restarts >= options.max_restarts)
      return Status(ErrorCode::kGpu, "the XR session was lost " + std::to_string(stats.restarts + 1) +
                                         " times; giving up (check the headset and its runtime)");
    ++stats.restarts;
    log_info("XR: session lost; restarting (" + std::to_string(stats.restarts) + "/" +
             std::to_string(options.max_restarts) + ")");
    if (options.frames > 0 && stats.frames_rendered >= options.frames) return stats;
  }
}

}  // namespace vxr::xr
