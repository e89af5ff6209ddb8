// The flags vxr view and vxr render share for the volume's geometry and
// opacity, registered in one place (parsed by engine/render/volume_session.h).
#pragma once

#include <CLI/CLI.hpp>

#include "render/volume_session.h"

namespace vxr::cli {

// --voxel-size X,Y,Z, --opacity LO:A,HI:B, --opacity-unit-distance D into `f`.
void add_volume_flags(CLI::App* cmd, SessionFlags* f);

// --timepoint T against the input's count: kInvalidArgument naming both.
Status check_timepoint(const std::string& input, uint32_t timepoint, uint32_t timepoints);

}  // namespace vxr::cli
