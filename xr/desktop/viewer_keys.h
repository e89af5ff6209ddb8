// GLFW key events -> the viewer's window-system-free keys (viewer_state.h).
// Keys come from GLFW's key callback, not from polling, so a tap shorter than
// a frame (a quick Esc) is still seen.
#pragma once

#include <optional>

#include "xr/desktop/viewer_state.h"

namespace vxr::xr {

// `key` and `action` as GLFW passes them to a key callback; nullopt for keys
// the viewer ignores and for releases.
std::optional<ViewerKey> viewer_key_from_glfw(int key, int action);

}  // namespace vxr::xr
