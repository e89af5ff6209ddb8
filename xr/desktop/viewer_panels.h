// The desktop viewer's Dear ImGui panels: widgets over a ViewerState (channels,
// model and step, time, help). Only ImGui calls: the Vulkan/GLFW backends that
// put the draw lists into the swapchain image live with the window.
#pragma once

#include <map>
#include <optional>
#include <string>
#include <vector>

#include "xr/desktop/viewer_state.h"
#include "xr/desktop/viewer_tools.h"

namespace vxr::xr {

struct PanelInputs {
  std::string dataset;                              // shown in the channel panel's title
  std::vector<std::vector<float>> histograms;       // per channel, bins over data_range (may be empty)
  double frame_ms = 0.0;
};

// Channel `channel`'s opacity curve editor at the cursor (the channel panel
// draws one per channel): the curve over the window (x 0..1 = window lo..hi,
// opacity 0..1 bottom to top) over `histogram` (may be null); drag a point to
// move it, click elsewhere to add one, right-click a point to remove it,
// "ramp" to drop every point. The canvas is the full width available, 72 px tall.
void draw_opacity_editor(ViewerState& state, size_t channel, const std::vector<float>* histogram);

// The rendering panel's clipping controls at the cursor: "cut plane" on/off,
// the side kept along an axis and the plane's position on it (or, for an
// oblique plane, its normal and offset), "clip box" on/off and a range per
// axis, all in fractions of the volume. Editing a plane or range turns it on.
void draw_clip_controls(ViewerState& state);

// Draws the panels into the current ImGui frame (between NewFrame and Render)
// and applies the user's edits to `state`. Hidden panels (Tab) draw nothing.
void draw_viewer_panels(ViewerState& state, const PanelInputs& in);

// The tool palette and cards panel's own state (text fields, what the user
// asked for this frame). The window acts on save_card, restore, finish and remove.
struct ToolPanel {
  enum class Mode { kNavigate, kCount, kMeasure, kTrace, kTrack, kRoi };
  Mode mode = Mode::kNavigate;
  char cls[64] = "default";
  char card_title[128] = "";
  char card_note[1024] = "";
  bool save_card = false;                  // set for one frame: save a card with this frame's picture
  std::optional<annotate::Id> restore;     // set for one frame: show this card's scene
  bool finish = false;                     // set for one frame: "finish" (trace: new root; track: new track)
  std::optional<std::pair<AnnotationKind, annotate::Id>> remove;  // set for one frame: remove this annotation
  std::string message;                     // the last action's result or error
  // The store as last read (again after each edit).
  uint64_t read_revision = UINT64_MAX;
  uint32_t read_timepoint = UINT32_MAX;
  uint64_t read_events = UINT64_MAX;
  std::map<std::string, size_t> counts;
  std::vector<std::pair<std::string, double>> lengths;  // measurement label, length
  std::vector<annotate::Card> cards;                    // without media
  ToolStatus status;                                    // the live tool
  std::vector<AnnotationRow> rows;                      // the annotation list
};

// The movie panel's state: keyframes added, the export's output and progress.
struct MoviePanel {
  char output[512] = "movie.mp4";
  int frames = 90;
  float fps = 30.0f;               // an .mp4's frame rate
  size_t keyframes = 0;            // the window keeps them
  bool add_keyframe = false;       // set for one frame
  bool clear_keyframes = false;    // set for one frame
  bool start_export = false;       // set for one frame
  std::optional<double> progress;  // 0..1 while an export runs
  std::string message;
};

// Tools (navigate / count / measure / trace / track / roi, the class), the
// live tool's state (nodes and traced length, the active track, the box and
// the markers in it), the annotation list with remove, cards (title, note,
// save, list, restore). `timepoint`: the one shown (ROI counts are at it).
void draw_tools_panel(ViewerTools& tools, ToolPanel& panel, uint32_t timepoint);

// Keyframes of the camera and the movie export along them, with its progress.
void draw_movie_panel(MoviePanel& panel);

// Open another input (a .vxc, a project folder, any importable file): the
// window closes and the viewer opens it.
struct OpenPanel {
  char path[1024] = "";
  bool open = false;  // set for one frame
  std::string message;
};
void draw_open_panel(OpenPanel& panel);

// "vxr - DATASET - 12.3 ms" for the window title.
std::string viewer_window_title(const std::string& dataset, double frame_ms);

}  // namespace vxr::xr
