// `vxr view --desktop --ui-script FILE`: a scripted desktop session, for tests
// and demos. FILE is a JSON array of steps (or {"steps": [...]}), each a string,
// run one frame apart, in order; the window closes after the last one.
//
//   any viewer command        "colormap 0 viridis", "window 0 10 200", "visible 1 off",
//                             "model mip", "step 0.5", "iso 120" (the isosurface's value, data
//                             units), "time 2", "orbit 40 0", "zoom 2",
//                             "reset", "view 3", "play", "pause", "speed 0.5", "loop on",
//                             "opacity 0 0:0,0.5:0.2,1:1" (the opacity curve over the window,
//                             x:opacity pairs, x rising in 0..1), "opacity 0 ramp" (no points),
//                             "cut z 0.5" (keep z >= half the volume; -x/-y/-z keep the other
//                             side), "cut 1 1 0 -0.8" (keep dot(n/|n|, f) - 0.8 >= 0), "cut off",
//                             "cut on", "clip 0.1 0.1 0 0.9 0.9 1" (keep that box, volume
//                             fractions), "clip off", "fly 0.2 0 0" (the orbit centre travels
//                             forward/right/up by volume lengths)
//                             (ViewerState::apply_command)
//   ui on|off                 show or hide the panels
//   wait N                    render N more frames first
//   resize W H                the window to W x H pixels (the viewer follows it and remembers it)
//   screenshot PATH           this frame's swapchain image, panels included, as a PNG
//   count X Y Z [CLASS]       a count marker at voxel (X, Y, Z)      } through the ToolPalette,
//   measure X Y Z X2 Y2 Z2    a measurement between two voxels       } into --annotations STORE
//   card TITLE...             a card: the current scene + the last screenshot
//   tool navigate|count [CLASS]|measure|trace|track [CLASS]|roi
//                             the tools panel's tool (as if picked there)
//   click X Y                 a left click at window pixel (X, Y), as the mouse would
//                             (count: a marker; measure: an end point; trace: a node below
//                             the current one, or on a traced node: continue from it;
//                             track: the track's marker at the current timepoint)
//   drag X Y X2 Y2            a left drag from (X, Y) to (X2, Y2): press, move, release
//                             (roi: a box over that rectangle, through the whole volume
//                             along the axis nearest the view direction)
//   finish                    the tools panel's "finish" (Enter): trace: the next node
//                             starts a new root; track: the next marker a new track
//   remove KIND ID            the annotation list's "remove": KIND marker|measurement|
//                             skeleton|track|roi (a track goes with its markers)
//   panel-card TITLE...       the tools panel's "save card": this frame's picture and scene
//   restore-card ID           the tools panel's "restore" of card ID
//   open PATH                 the Open panel: the window closes and vxr view opens PATH
//                             (any input it takes; the last step, PATH must exist)
//   keyframe                  the movie panel's "add keyframe": the window's camera now
//   export-movie OUT FRAMES [FPS]
//                             the movie panel's "export": FRAMES frames along the smooth
//                             path through the keyframes so far (2 or more), drawn by the
//                             window; OUT a folder (frame-00000.png ...) or NAME.mp4
//                             (ffmpeg, FPS default 30); the next step runs when it is written
//
// The whole script is checked before the window opens: a bad step is one line
// naming the file, the step number and the problem.
#pragma once

#include <array>
#include <functional>
#include <optional>
#include <string>
#include <vector>

#include "core/status.h"
#include "xr/desktop/viewer_movie.h"
#include "xr/desktop/viewer_state.h"
#include "xr/desktop/viewer_tools.h"

namespace vxr::xr {

enum class UiStepKind { kViewer, kUi, kWait, kResize, kScreenshot, kCount, kMeasure, kCard, kTool, kClick, kPanelCard,
                        kRestoreCard, kDrag, kFinish, kRemove, kKeyframe, kExportMovie, kOpen };

struct UiStep {
  UiStepKind kind = UiStepKind::kViewer;
  std::string text;                 // as written (viewer commands are applied from it)
  std::string arg;                  // screenshot path, count class, card title, tool ("count CLASS"),
                                    // remove's kind, export-movie's output
  std::array<double, 6> xyz{};      // count: 3, measure: 6 voxel coordinates; resize, click: x, y;
                                    // drag: x, y, x2, y2; remove: id; export-movie: fps
  uint64_t frames = 0;              // wait, export-movie
  bool on = true;                   // ui
};

struct UiScript {
  std::string path;
  std::vector<UiStep> steps;
  // "FILE: step N ('TEXT'): WHY": every error about a step reads the same.
  Status step_error(size_t index, const std::string& why) const;
};

// Parses FILE and checks every step against a copy of `state` (channels,
// colour maps, ranges), the screenshot paths against `inputs`
// (core/output_file.h), and that tools and cards have a store.
Result<UiScript> load_ui_script(const std::string& path, const ViewerState& state,
                                const std::vector<std::string>& inputs, bool have_store);

// Runs a script one frame at a time over the viewer's state and the store.
class UiScriptRunner {
 public:
  // `tools`: the store's tools (null without a store); `card_scene`: the
  // Scene a card stores for the viewer's current state (the window knows the
  // volume's size and its own).
  UiScriptRunner(UiScript script, ViewerTools* tools, std::function<Scene(const ViewerState&)> card_scene);

  // What the frame about to be drawn must do besides drawing.
  struct FrameWork {
    std::string screenshot;           // read this frame back into this PNG
    std::array<int, 2> resize{0, 0};  // > 0: resize the window to this
    bool done = false;                // every step ran: close the window
    std::string tool;                 // non-empty: the tools panel switches to it ("navigate", "count CLASS", "measure",
                                      // "trace", "track CLASS", "roi")
    std::optional<std::array<double, 2>> click;  // a left click at this window pixel (as the mouse would)
    std::optional<std::array<double, 4>> drag;   // a left drag between these window pixels
    bool finish = false;                         // the tools panel's "finish"
    std::optional<std::pair<AnnotationKind, annotate::Id>> remove;  // the annotation list's "remove"
    bool keyframe = false;                       // the movie panel's "add keyframe"
    std::optional<MovieRequest> export_movie;    // the movie panel's "export" (the next step waits for it)
    std::optional<std::string> panel_card;       // "save card" in the tools panel, with this title
    std::optional<std::string> open;             // the Open panel's "open" of this input
    std::optional<uint64_t> restore_card;        // "restore" of this card in the tools panel
  };
  // Applies the steps due before this frame (state edits, tool events).
  Result<FrameWork> before_frame(ViewerState& state);
  // After the frame's screenshot was written (cards take the latest).
  void screenshot_written(const std::string& path) { last_screenshot_ = path; }

 private:
  Status run_step(const UiStep& step, ViewerState& state);

  UiScript script_;
  ViewerTools* tools_;
  std::function<Scene(const ViewerState&)> card_scene_;
  size_t next_ = 0;
  uint64_t wait_ = 0;
  std::string last_screenshot_;
};

}  // namespace vxr::xr
