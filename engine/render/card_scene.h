// A card's Scene and the camera a Scene is drawn with: what `vxr render
// --card`, `vxr view --card` and a --settings Scene with a camera share.
#pragma once

#include <string>

#include "core/status.h"
#include "render/camera.h"
#include "scene/render_settings.h"

namespace vxr {

// A card's Scene: "STORE:ID", or "ID" of the --annotations store, else of
// the project folder given as the input (either may be empty).
// kInvalidArgument for a malformed spec or a card without a scene; the
// store's own error (kNotFound...) when it cannot be opened or lacks the card.
Result<Scene> load_card_scene(const std::string& spec, const std::string& annotations_flag = "",
                              const std::string& input = "");

// A Scene's own camera (or the default orbit view; `flat`: a single slice
// seen from above) in the world, before its volume transform: where
// `vxr render`'s --camera/--fov flags apply and what a card stores.
Camera scene_world_camera(const Scene& scene, const VolumePlacement& placement, bool flat);

// The camera a Scene is drawn with, in the volume frame the renderers use:
// its own (or the default orbit view; `flat`: a single slice seen from
// above), then its volume transform undone.
Camera scene_camera(const Scene& scene, const VolumePlacement& placement, bool flat);

// `world` (the volume placed by `transform`) as the renderers see it: the
// volume at the origin and the camera moved the opposite way.
Camera camera_in_volume_frame(const Camera& world, const VolumeTransform& transform);

}  // namespace vxr
