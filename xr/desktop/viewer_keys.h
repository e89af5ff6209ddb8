// GLFW key events -> the viewer's window-system-free keys (viewer_state.h).
// Keys come from GLFW's key callback, not from polling, so a tap shorter than
// a frame (a quick Esc) is still seen.
#pragma once

#include <functional>
#include <optional>

#include "xr/desktop/viewer_state.h"

namespace vxr::xr {

// `key` and `action` as GLFW passes them to a key callback; nullopt for keys
// the viewer ignores and for releases.
std::optional<ViewerKey> viewer_key_from_glfw(int key, int action);

// `pressed(GLFW_KEY_...)` says whether a key is held now (glfwGetKey): the fly
// keys W/S, D/A, E/Q as directions. Polled each frame, not from events, so a
// held key flies smoothly instead of at the keyboard's repeat rate.
FlyInput held_fly_keys(const std::function<bool(int)>& pressed);

}  // namespace vxr::xr
