// `vxr export-tiff`: one level of a .vxc container as a multi-page TIFF
// (ImageJ hyperstack layout), so data leaves as it came.
#include <cstdio>

#include "command.h"
#include "core/output_file.h"
#include "core/progress.h"
#include "volume/container_reader.h"
#include "volume/tiff_export.h"
#include "volume/tiff_writer.h"

namespace vxr::cli {

void add_export_tiff_command(CLI::App& app, Invocation& inv) {
  struct Args {
    std::string input, output;
    uint32_t level = 0;
    int64_t channel = -1, timepoint = -1;
  };
  auto a = std::make_shared<Args>();
  auto* cmd = app.add_subcommand("export-tiff", "write one level of a .vxc container as a multi-page TIFF");
  cmd->add_option("file", a->input, ".vxc container")->required();
  cmd->add_option("-o,--output", a->output, "TIFF to write (BigTIFF past 4 GB; appears only when complete)")->required();
  cmd->add_option("--level", a->level, "pyramid level (0 = full resolution)");
  cmd->add_option("--channel", a->channel, "only this channel (default: all, as an ImageJ hyperstack)")
      ->check(CLI::NonNegativeNumber);
  cmd->add_option("--timepoint", a->timepoint, "only this timepoint (default: all)")->check(CLI::NonNegativeNumber);
  cmd->callback([&inv, a] {
    inv.run = [a] {
      if (Status s = check_output(a->output, {{a->input}}, "-o"); !s) return fail(s, kExitUsage);
      auto reader = ContainerReader::open(a->input);
      if (!reader) return fail(reader.status());
      const ChunkSource& src = **reader;
      TiffExportOptions o;
      o.level = a->level;
      if (a->channel >= 0) o.channel = uint32_t(a->channel);
      if (a->timepoint >= 0) o.timepoint = uint32_t(a->timepoint);
      if (o.level >= src.levels().size() || (o.channel && *o.channel >= src.info().channels) ||
          (o.timepoint && *o.timepoint >= src.info().timepoints)) {
        const Status s = export_tiff(src, a->output, o);  // names the option that is out of range
        return fail(Status(s.code(), a->input + ": " + s.message()), kExitUsage);
      }
      const LevelInfo& lv = src.levels()[o.level];
      VolumeInfo out = src.info();
      out.dims = lv.dims;
      out.channels = o.channel ? 1 : out.channels;
      out.timepoints = o.timepoint ? 1 : out.timepoints;
      const uint64_t bytes = out.voxels_per_volume() * dtype_bytes(out.dtype) * out.channels * out.timepoints;
      Progress progress("export-tiff", bytes);
      o.progress = &progress;
      if (Status s = export_tiff(src, a->output, o); !s) return fail(s);
      progress.finish();
      std::printf("%s: %llux%llux%llu %s, %u channel(s), %u timepoint(s), level %u%s\n", a->output.c_str(),
                  (unsigned long long)out.dims[0], (unsigned long long)out.dims[1], (unsigned long long)out.dims[2],
                  dtype_name(out.dtype), out.channels, out.timepoints, o.level,
                  needs_big_tiff(out) ? ", BigTIFF" : "");
      return kExitOk;
    };
  });
}

}  // namespace vxr::cli
