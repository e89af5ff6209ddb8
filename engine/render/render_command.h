// `vxr render`'s work behind its flags: one picture of a volume through the
// one renderer vxr view uses, for every input. The session (source,
// settings, channels, timepoint; the same as vxr view's) is
// render/volume_session.h, the frames render/still_render.h. For comparison
// `reference` draws the CPU reference (double precision) with the same
// resolved settings instead; with `json` it measures each GPU frame against it.
//
// Settings come from --settings (a RenderSettings JSON, or a Scene JSON with
// "render" and "camera"), then the flags override them. Cards: `save_card`
// stores the picture as a card whose Scene holds every resolved choice
// (input, timepoint, channels, windows, camera, size, LOD bias); `card`
// (STORE:ID) starts from that Scene, so the same build draws the same pixels
// again. Timing: `frames` + `json` print each frame's GPU ms (timestamp
// queries), wall ms and samples; `no_skip` marches empty space too (the same
// image; for A/B timing). tools/cmd_render.cpp parses flags into
// RenderCommandOptions and makes the one call.
#pragma once

#include <functional>
#include <memory>
#include <string>

#include "core/status.h"
#include "gpu/context.h"
#include "render/volume_session.h"

namespace vxr {

struct RenderCommandOptions {
  std::string input, output, camera, size = "512x512";
  double fov = 0.0, reference_step = 1.0 / 16.0;
  double lod_bias = 0.0, frame_budget_ms = 0.0;
  bool lod_bias_given = false;
  int frames = 0;  // 0: until converged
  bool reference = false, stats = false;
  bool no_skip = false;  // lod: no empty-space skipping (bricks or cells), for A/B timing
  bool json = false;     // lod: per-frame figures as JSON on stdout
  bool size_given = false;
  std::string card;       // STORE:ID to restore
  std::string save_card;  // STORE to add a card to
  std::string card_title, card_note;
  SessionFlags flags;  // the session's flags, shared with vxr view (--settings, --channel, --annotations, ...)
};

// Where the user hears from the command: `out` lines are its results (stdout:
// the picture written, statistics, the JSON), `note` lines its warnings
// (stderr). Without a trailing newline.
struct RenderReport {
  std::function<void(const std::string&)> out, note;
};

// Why run_render_command failed: the options or settings (a usage error) or the work.
enum class RenderFailure { kUsage, kWork };

using GpuOpener = Result<std::unique_ptr<gpu::Context>>();

// Runs `vxr render` with `options`; `open_gpu` is called only when a GPU is
// needed. On failure `failure` (when given) says which kind; the Status
// message is the one line to print.
Status run_render_command(const RenderCommandOptions& options, const std::function<GpuOpener>& open_gpu,
                          const RenderReport& report, RenderFailure* failure = nullptr);

}  // namespace vxr
