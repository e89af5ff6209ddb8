// Tool scripts: the analysis tools (tools.h) driven from a JSON file, the way
// `vxr annotate play` and tests drive them without a headset or a mouse.
//
//   {"events": [
//     {"tool": "count", "class": "nucleus", "color": [1, 0, 0, 1]},
//     {"press": [10, 20, 5]},
//     {"timepoint": 3, "press": [11, 20, 5]},
//     {"tool": "measure"}, {"press": [0, 0, 0]}, {"move": [3, 4, 0]}, {"release": [3, 4, 0]},
//     {"tool": "trace", "radius": 2}, {"press": [1, 1, 1]}, {"pick": [1, 1, 1]}, {"finish": true}
//   ]}
//
// An entry may set the tool, the class and colour, the timepoint and the node
// radius (they hold for later entries), and at most one action: press, move,
// release, pick, remove (each with the cursor [x, y, z] in voxels) or finish.
#pragma once

#include <array>
#include <functional>
#include <optional>
#include <string>
#include <vector>

#include "annotate/tools.h"

namespace vxr::annotate {

struct ToolStep {
  size_t index = 0;  // position in "events", for messages
  std::optional<Tool> tool;
  std::optional<std::string> cls;
  std::optional<std::array<double, 4>> color;
  std::optional<uint32_t> timepoint;
  std::optional<double> radius;
  std::optional<ToolAction> action;
  Vec3 cursor{0, 0, 0};
};

// Parses the script text; errors name `source`, the event index and the key.
Result<std::vector<ToolStep>> parse_tool_script(const std::string& text, const std::string& source);

// Applies the steps in order, calling `after` after each one that holds an
// action. Stops at the first refused edit: earlier edits stay (each is synced),
// and the error names the event.
Status run_tool_script(ToolPalette& palette, const std::vector<ToolStep>& steps,
                       const std::function<void(const ToolStep&, const ToolLiveState&)>& after = {});

}  // namespace vxr::annotate
