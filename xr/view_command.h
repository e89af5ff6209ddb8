// `vxr view`'s work behind its flags: the card or --settings start, the
// session (render/volume_session.h), the target (target_factory.h), the
// desktop viewer's setup (slider range, histograms, the annotation store, the
// UI script), the hands' tools, the frame loop (view_session.h), then the
// movie and --json figures. tools/cmd_view.cpp parses flags into
// ViewCommandOptions and makes the one call.
#pragma once

#include <cstdint>
#include <functional>
#include <string>

#include "core/status.h"
#include "render/volume_session.h"
#include "xr/target_factory.h"

namespace vxr::xr {

struct ViewCommandOptions {
  std::string input;      // a file, folder, project or procedural:...; empty (or `sample`): the bundled sample
  bool sample = false;
  TargetKind target = TargetKind::kAuto;  // --xr / --desktop / --headless force one
  uint64_t frames = 0;                    // 0: until the target ends
  std::string script;                     // headless pose script
  std::string png_dir;
  bool png_every_frame = false;
  bool lens_warp = false;
  bool stereo = false;      // desktop side-by-side
  std::string screenshot;   // desktop/mirror: the window at exit
  bool mirror = false;
  uint32_t width = 0, height = 0;  // eye size; 0: the target's (window: as last time)
  double frame_budget_ms = 0.0;
  double lod_bias = 0.0;
  bool lod_bias_given = false;  // false: a card's lod bias
  bool no_skip = false;         // march empty space too (same images; to time what skipping buys)
  std::string json;             // frame figures written here
  std::string movie;            // headless MP4 of the pose script's path
  double fps = 30.0;
  bool no_ui = false;
  std::string ui_script;        // desktop scripted session
  SessionFlags flags;           // shared with vxr render; its timepoint is shown first
  std::string card;             // STORE:ID or ID
  std::string tool = "count", tool_class = "cell";  // the hands' starting tool and count class
  bool tool_given = false;
};

// Where the user hears from the viewer: `info` lines go to stdout (the target
// chosen, figures), `note` lines to stderr (warnings, what is shown). Both
// without the "vxr view: " prefix, which the caller adds.
struct ViewReport {
  std::function<void(const std::string&)> info, note;
};

// Why run_view_command failed: the options or input (a usage error) or the work.
enum class ViewFailure { kUsage, kWork };

// Runs `vxr view` with `options`. On failure `failure` (when given) says
// which kind; the Status message is the one line to print.
Status run_view_command(const ViewCommandOptions& options, const ViewReport& report, ViewFailure* failure = nullptr);

}  // namespace vxr::xr
