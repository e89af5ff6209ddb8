// Pose scripts: head and controller motion, button presses and test-runtime
// directives in one JSON file, read by the headless target and by the OpenXR
// test runtime (xr/test_runtime), so a test can drive either the same way.
//
//   {
//     "view": {"width": 128, "height": 128, "ipd_m": 0.064,
//              "fov_deg": {"left": -40, "right": 40, "up": 40, "down": -40}},
//     "keys": [
//       {"frame": 0,  "head": {"position": [0, 1.6, 0], "orientation": [0, 0, 0, 1]},
//        "left": {"grip": {"position": [-0.1, 1.4, -0.4]}, "squeeze": 0}},
//       {"frame": 10, "left": {"squeeze": 1}},
//       {"frame": 20, "left": {"grip": {"position": [0.1, 1.4, -0.4]}}}
//     ]
//   }
//
// A hand names its physical controls: "squeeze", "trigger" (0..1),
// "thumbstick" [x, y] (a Vive's trackpad), and the buttons "menu",
// "thumbstick_click" (a Vive's trackpad click), "trackpad_click" (Windows
// Mixed Reality's trackpad), "a" (A, or X on a left Touch) and "b" (B or Y).
// The test runtime answers each action from the control its binding names
// (so a script tests the bindings); the headless target reads the buttons
// as an Oculus Touch pair does: a -> primary, b -> secondary,
// thumbstick_click -> stick_click (xr/pose.h).
//
// Orientation is [x, y, z, w] (OpenXR order). A key changes only what it
// names; everything else carries over from the key before. Between keys,
// positions are interpolated linearly and orientations by slerp; with
// "interpolation": "smooth" (camera movies) positions follow a cubic Hermite
// spline through the keys (Catmull-Rom tangents over the key frames, zero at
// the first and last key so a movie eases in and out) and orientations
// follow SQUAD, so velocity has no jump at a key. Buttons, squeeze, trigger
// and thumbstick step at the key. Other top-level members
// (runtime directives) are left in `raw` for whoever understands them.
//
// This file does not depend on vxr_core: the test runtime library builds it too.
#pragma once

#include <cstdint>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "xr/pose.h"

namespace vxr::xr {

struct ScriptHand {
  bool tracked = true;
  Pose grip;
  Pose aim;
  double squeeze = 0.0, trigger = 0.0;
  glm::dvec2 thumbstick{0.0};
  bool menu = false;
  bool thumbstick_click = false, trackpad_click = false;
  bool a = false, b = false;  // A/X, B/Y
};

struct ScriptFrame {
  Pose head;
  ScriptHand hands[2];
};

enum class Interpolation { kLinear, kSmooth };

struct Script {
  uint32_t width = 128, height = 128;
  Interpolation interpolation = Interpolation::kLinear;
  double ipd_m = 0.064;
  Fov fov{-0.6981317, 0.6981317, 0.6981317, -0.6981317};  // +-40 degrees
  std::vector<std::pair<uint64_t, ScriptFrame>> keys;       // complete states, ascending frames
  nlohmann::json raw;

  // The state at `frame` (holds the last key's state after it); fractional
  // frames are allowed (sub-frame motion, tests of smoothness).
  ScriptFrame at(double frame) const;
  uint64_t last_key_frame() const { return keys.empty() ? 0 : keys.back().first; }
};

// The default state: head at 1.6 m looking along -z, hands in front at 1.3 m.
ScriptFrame default_script_frame();

// Parses a script from text / a file; on failure returns false and sets `error`
// to one line naming what is wrong.
bool parse_script_text(const std::string& text, Script& out, std::string& error);
bool load_script(const std::string& path, Script& out, std::string& error);

}  // namespace vxr::xr
