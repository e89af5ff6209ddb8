#include "xr/desktop/viewer_keys.h"

#include <GLFW/glfw3.h>

namespace vxr::xr {

std::optional<ViewerKey> viewer_key_from_glfw(int key, int action) {
  if (action != GLFW_PRESS && action != GLFW_REPEAT) return std::nullopt;
  // Toggles and quit act once per press, not on auto-repeat.
  const bool repeat = action == GLFW_REPEAT;
  switch (key) {
    case GLFW_KEY_ESCAPE: return repeat ? std::nullopt : std::optional(ViewerKey::kQuit);
    case GLFW_KEY_R: return ViewerKey::kResetView;
    case GLFW_KEY_1: return ViewerKey::kAxisX;
    case GLFW_KEY_2: return ViewerKey::kAxisY;
    case GLFW_KEY_3: return ViewerKey::kAxisZ;
    case GLFW_KEY_M: return repeat ? std::nullopt : std::optional(ViewerKey::kNextModel);
    case GLFW_KEY_C: return repeat ? std::nullopt : std::optional(ViewerKey::kNextColormap);
    case GLFW_KEY_RIGHT: return ViewerKey::kTimeNext;
    case GLFW_KEY_LEFT: return ViewerKey::kTimePrev;
    case GLFW_KEY_SPACE: return repeat ? std::nullopt : std::optional(ViewerKey::kPlayPause);
    case GLFW_KEY_COMMA: return ViewerKey::kStepBack;
    case GLFW_KEY_PERIOD: return ViewerKey::kStepForward;
    case GLFW_KEY_LEFT_BRACKET: return repeat ? std::nullopt : std::optional(ViewerKey::kSlower);
    case GLFW_KEY_RIGHT_BRACKET: return repeat ? std::nullopt : std::optional(ViewerKey::kFaster);
    case GLFW_KEY_H:
    case GLFW_KEY_F1: return repeat ? std::nullopt : std::optional(ViewerKey::kToggleHelp);
    case GLFW_KEY_ENTER:
    case GLFW_KEY_KP_ENTER: return repeat ? std::nullopt : std::optional(ViewerKey::kFinishTool);
    case GLFW_KEY_TAB: return repeat ? std::nullopt : std::optional(ViewerKey::kToggleUi);
    default: return std::nullopt;
  }
}

FlyInput held_fly_keys(const std::function<bool(int)>& pressed) {
  auto axis = [&](int plus, int minus) { return (pressed(plus) ? 1.0 : 0.0) - (pressed(minus) ? 1.0 : 0.0); };
  return {axis(GLFW_KEY_W, GLFW_KEY_S), axis(GLFW_KEY_D, GLFW_KEY_A), axis(GLFW_KEY_E, GLFW_KEY_Q)};
}

}  // namespace vxr::xr
