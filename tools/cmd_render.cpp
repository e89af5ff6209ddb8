// `vxr render INPUT -o out.png`: one picture of a volume through the one
// renderer vxr view uses. Only flags live here: what they do is
// render/render_command.h.
#include <cstdio>

#include "command.h"
#include "render/render_command.h"
#include "volume_flags.h"

namespace vxr::cli {
namespace {

int run(const RenderCommandOptions& o) {
  const RenderReport report{[](const std::string& line) { std::printf("%s\n", line.c_str()); },
                            [](const std::string& line) { std::fprintf(stderr, "vxr: %s\n", line.c_str()); }};
  RenderFailure failure = RenderFailure::kWork;
  if (Status st = run_render_command(o, open_gpu, report, &failure); !st)
    return fail(st, failure == RenderFailure::kUsage ? kExitUsage : kExitFailure);
  return kExitOk;
}

}  // namespace

void add_render_command(CLI::App& app, Invocation& inv) {
  auto o = std::make_shared<RenderCommandOptions>();
  auto* cmd = app.add_subcommand("render", "render one picture of a volume (.vxc, OME-Zarr, TIFF, OME-TIFF, slices, .ims, raw+JSON, procedural:vessels:SIDE) to PNG");
  cmd->add_option("input", o->input, "the volume (optional with --card: the card's volume)");
  cmd->add_option("-o,--out", o->output, "output PNG")->required();
  cmd->add_option("--camera", o->camera, "px,py,pz,tx,ty,tz,ux,uy,uz: eye, target, up in world units (volume centred at 0)");
  cmd->add_option("--fov", o->fov, "vertical field of view in degrees");
  cmd->add_option("--size", o->size, "WxH (default 512x512)");
  add_session_flags(cmd, &o->flags);
  cmd->add_option("--lod-bias", o->lod_bias, "log2 of voxels per pixel accepted (+1 coarser, -1 finer; default 0)");
  cmd->add_option("--frame-budget-ms", o->frame_budget_ms,
                  "render --frames frames, adjusting the LOD bias to hold this frame time");
  cmd->add_option("--frames", o->frames, "frames to render (default: until converged; 30 with a frame budget)");
  cmd->add_flag("--stats", o->stats, "print the final frame's statistics (bricks, samples, uploads, cache hits)");
  cmd->add_flag("--reference", o->reference,
                "draw the CPU reference (double precision, whole volume, slow) instead; with --json: measure each GPU "
                "frame against it");
  cmd->add_option("--reference-step", o->reference_step, "the reference's step in voxels (default 1/16)");
  cmd->add_flag("--no-skip", o->no_skip, "march empty space too (no brick or cell skipping; same image, for timing)");
  cmd->add_flag("--json", o->json,
                "print per-frame GPU ms, wall ms and samples as JSON (with --reference: RMSE against the CPU "
                "reference of the finest level, 8-bit units)");
  add_annotations_option(cmd, o->flags.annotations);
  cmd->add_option("--card", o->card,
                  "STORE:ID (or ID of the --annotations store): restore a card's scene (volume, camera, settings, size); "
                  "flags override");
  cmd->add_option("--save-card", o->save_card, "STORE: also store the picture as a card with the full scene to restore it");
  cmd->add_option("--card-title", o->card_title, "with --save-card: the card's title");
  cmd->add_option("--card-note", o->card_note, "with --save-card: the card's note");
  cmd->callback([&inv, o, cmd] {
    o->lod_bias_given = cmd->count("--lod-bias") > 0;
    o->size_given = cmd->count("--size") > 0;
    note_session_flags(cmd, &o->flags);
    inv.run = [o] { return run(*o); };
  });
}

}  // namespace vxr::cli
