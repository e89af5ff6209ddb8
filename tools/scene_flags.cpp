// Flags `vxr render` and `vxr view` share, registered and parsed here once so
// both commands read them the same way (the card loader they share is
// render/card_scene.h).
#include "command.h"

namespace vxr::cli {

void add_annotations_option(CLI::App* cmd, std::string& store) {
  cmd->add_option("--annotations", store,
                  "annotation store (vxr annotate) whose markers, skeletons and meshes are drawn with the volume; "
                  "a project folder NAME.vxr given as the input draws its own store");
}

}  // namespace vxr::cli
