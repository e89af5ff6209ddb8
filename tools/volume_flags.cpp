#include "volume_flags.h"

namespace vxr::cli {
namespace {

// --voxel-size X,Y,Z, --opacity LO:A,HI:B, --opacity-unit-distance D.
void add_volume_flags(CLI::App* cmd, SessionFlags* f) {
  cmd->add_option("--voxel-size", f->voxel_size,
                  "X,Y,Z: physical size of one voxel (world units), overriding the file's; e.g. 1,1,2");
  cmd->add_option("--opacity", f->opacity,
                  "LO:A,HI:B: opacity ramp over the window (LO, HI fractions 0..1): 0 below LO, A..B linear, B above");
  cmd->add_option("--opacity-unit-distance", f->opacity_unit_distance,
                  "D: opacity per D world units (physical voxel size, as VTK); 0: per voxel (default)");
}

}  // namespace

void add_session_flags(CLI::App* cmd, SessionFlags* f) {
  cmd->add_option("--settings", f->settings,
                  "render settings JSON (RenderSettings, or a Scene with render, camera, channels, timepoint); the "
                  "flags override it");
  cmd->add_option("--model", f->model, "optical model: ea (default), emission, mip, minip, average or iso");
  cmd->add_option("--colormap", f->colormap,
                  "channel 0's colour map: gray, viridis, magma, inferno, plasma, turbo, hot, red, green, blue, cyan, "
                  "magenta, yellow (default: hot; a distinct colour per channel when several are drawn)");
  cmd->add_option("--window", f->window, "LO,HI: channel 0's window in data units (default: 0.5..99.5 percentiles of each drawn channel)");
  cmd->add_option("--step", f->step, "sample step in voxels (default 0.5)");
  cmd->add_option("--iso", f->iso,
                  "V: draw the isosurface at V (data units of the iso channel); implies --model iso unless --model is given "
                  "(default value: the middle of the window)");
  cmd->add_option("--channel", f->channel, "channels to draw, e.g. 2 or 0,2 (default: the first up to 4)");
  cmd->add_option("--timepoint", f->timepoint, "timepoint to draw (default 0)");
  add_volume_flags(cmd, f);
}

void note_session_flags(const CLI::App* cmd, SessionFlags* f) { f->timepoint_given = cmd->count("--timepoint") > 0; }

}  // namespace vxr::cli
