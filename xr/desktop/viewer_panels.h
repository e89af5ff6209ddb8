// The desktop viewer's Dear ImGui panels: widgets over a ViewerState (channels,
// model and step, time, help). Only ImGui calls: the Vulkan/GLFW backends that
// put the draw lists into the swapchain image live with the window.
#pragma once

#include <string>
#include <vector>

#include "xr/desktop/viewer_state.h"

namespace vxr::xr {

struct PanelInputs {
  std::string dataset;                              // shown in the channel panel's title
  std::vector<std::vector<float>> histograms;       // per channel, bins over data_range (may be empty)
  double frame_ms = 0.0;
};

// Draws the panels into the current ImGui frame (between NewFrame and Render)
// and applies the user's edits to `state`. Hidden panels (Tab) draw nothing.
void draw_viewer_panels(ViewerState& state, const PanelInputs& in);

// "vxr - DATASET - 12.3 ms" for the window title.
std::string viewer_window_title(const std::string& dataset, double frame_ms);

}  // namespace vxr::xr
