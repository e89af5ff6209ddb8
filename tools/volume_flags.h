// The flags vxr view and vxr render share for the session (what is drawn and
// how), registered in one place; engine/render/volume_session.h parses them.
#pragma once

#include <CLI/CLI.hpp>

#include "render/volume_session.h"

namespace vxr::cli {

// --settings --model --colormap --window --step --iso --channel --timepoint
// --voxel-size --opacity --opacity-unit-distance into `f`. Call note_session_flags(cmd, f) in the
// command's callback (it records which were given).
void add_session_flags(CLI::App* cmd, SessionFlags* f);
void note_session_flags(const CLI::App* cmd, SessionFlags* f);

}  // namespace vxr::cli
