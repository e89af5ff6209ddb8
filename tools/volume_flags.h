// The flags vxr view and vxr render share for the volume's geometry and
// opacity, registered in one place (parsed by engine/render/volume_session.h).
#pragma once

#include <CLI/CLI.hpp>

#include "render/volume_session.h"

namespace vxr::cli {

// --voxel-size X,Y,Z, --opacity LO:A,HI:B, --opacity-unit-distance D into `f`.
void add_volume_flags(CLI::App* cmd, SessionFlags* f);

}  // namespace vxr::cli
