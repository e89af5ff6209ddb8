// What the desktop window needs to be the viewer (panels, keys and mouse
// editing a ViewerState that says what the renderer draws), built once by
// `vxr view` and shared by every (re)start of the window.
#pragma once

#include <array>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "annotate/annotation_store.h"
#include "render/camera.h"
#include "scene/render_settings.h"
#include "volume/chunk_source.h"
#include "xr/desktop/ui_script.h"
#include "xr/volume_transform.h"

namespace vxr::xr {

struct ViewerSetup {
  std::string dataset;  // window title and the panels
  Scene scene;          // volume (input path) and the starting settings
  uint32_t timepoints = 1;
  std::array<double, 2> data_range{0.0, 255.0};
  VolumePlacement placement;  // the orbit's scale (longest side = 1 orbit unit) and the marker overlay
  VolumeTransform transform;  // where the frame loop places the volume (its initial transform)
  std::optional<UiScript> script;                    // checked; run, then the window closes
  std::shared_ptr<annotate::AnnotationStore> store;  // tools, cards, the marker overlay (may be null)
  std::vector<std::vector<float>> histograms;        // per channel, bins over data_range (panels)
  std::optional<OrbitCamera> start_orbit;            // `--card`: the window starts at the card's camera
  // Per-dataset memory (viewer_state.h remembered_view_path(input)): the window
  // writes its Scene there when it closes. Empty (the default): nothing written.
  std::string view_memory;
  // Start from the Scene found at view_memory (settings, timepoint, camera).
  // `vxr view` sets it when no --settings, --card or look flags were given.
  bool restore_view = false;
  // The Open panel writes the input to open next here and closes the window;
  // the caller (xr/view_command) then opens it. Null: no Open panel.
  std::shared_ptr<std::string> open_request;
};

// The orbit that shows `scene`'s camera: the camera moved into the volume's
// frame through the scene's volume transform (the window draws the volume
// untransformed), in units of the volume's longest side. nullopt without a
// camera. An orbit has no roll: a camera rolled about its view keeps its eye
// and target, and its up becomes the orbit's.
std::optional<OrbitCamera> scene_orbit(const Scene& scene, const VolumePlacement& placement);

// Histogram of `channel` at `timepoint` over `range` in `bins` bins, from the
// finest level of at most `max_chunks` chunks (a coarse level: the data's
// shape, read at once), as log(1 + count) so the background does not flatten
// the rest. Interior voxels only.
Result<std::vector<float>> coarse_histogram(const ChunkSource& source, uint32_t channel, uint32_t timepoint,
                                            std::array<double, 2> range, size_t bins = 128,
                                            uint32_t max_chunks = 64);

// The orbit camera of `state` as the renderer's camera in the volume's frame
// (world units): the orbit is in units of the volume's longest side.
CameraState viewer_world_camera(const ViewerState& state, const VolumePlacement& placement);

}  // namespace vxr::xr
