#include "volume_flags.h"

namespace vxr::cli {

void add_volume_flags(CLI::App* cmd, SessionFlags* f) {
  cmd->add_option("--voxel-size", f->voxel_size,
                  "X,Y,Z: physical size of one voxel (world units), overriding the file's; e.g. 1,1,2");
  cmd->add_option("--opacity", f->opacity,
                  "LO:A,HI:B: opacity ramp over the window (LO, HI fractions 0..1): 0 below LO, A..B linear, B above");
  cmd->add_option("--opacity-unit-distance", f->opacity_unit_distance,
                  "D: opacity per D world units (physical voxel size, as VTK); 0: per voxel (default)");
}

Status check_timepoint(const std::string& input, uint32_t timepoint, uint32_t timepoints) {
  if (timepoint < timepoints) return Status::ok();
  return invalid_argument("--timepoint: " + std::to_string(timepoint) + ", but " + input + " has " +
                          std::to_string(timepoints) + " timepoint(s) (0.." + std::to_string(timepoints - 1) + ")");
}

}  // namespace vxr::cli
