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

// Draws the panels into the current ImGui frame (between NewFrame and Render)
// and applies the user's edits to `state`. Hidden panels (Tab) draw nothing.
void draw_viewer_panels(ViewerState& state, const PanelInputs& in);

// The tool palette and cards panel's own state (text fields, what the user
// asked for this frame). The window acts on save_card and restore.
struct ToolPanel {
  enum class Mode { kNavigate, kCount, kMeasure };
  Mode mode = Mode::kNavigate;
  char cls[64] = "default";
  char card_title[128] = "";
  char card_note[1024] = "";
  bool save_card = false;                  // set for one frame: save a card with this frame's picture
  std::optional<annotate::Id> restore;     // set for one frame: show this card's scene
  std::string message;                     // the last action's result or error
  // The store as last read (again after each edit).
  uint64_t read_revision = UINT64_MAX;
  std::map<std::string, size_t> counts;
  std::vector<std::pair<std::string, double>> lengths;  // measurement label, length
  std::vector<annotate::Card> cards;                    // without media
};

// Tools (navigate / count / measure, the count class), live counts and
// lengths, cards (title, note, save, list, restore).
void draw_tools_panel(ViewerTools& tools, ToolPanel& panel);

// "vxr - DATASET - 12.3 ms" for the window title.
std::string viewer_window_title(const std::string& dataset, double frame_ms);

}  // namespace vxr::xr
