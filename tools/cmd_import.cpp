// `vxr import`: converts image files into a .vxc container with its pyramid.
#include <cstdio>
#include <sstream>

#include "command.h"
#include "core/output_file.h"
#include "core/progress.h"
#include "core/trace.h"
#include "volume/importers/import_source.h"
#include "volume/pyramid_builder.h"

namespace vxr::cli {
namespace {

struct ImportArgs {
  std::vector<std::string> inputs;
  std::string output;
  std::string voxel_size;
  std::string unit;
  uint32_t chunk = 64;
  std::string memory = "512M";
  bool resume = false;
  std::string downsample = "mean";
  std::string codec = "auto";
  uint32_t threads = 2;
};

std::optional<std::array<double, 3>> parse_voxel_size(const std::string& s) {
  std::array<double, 3> v{};
  std::stringstream ss(s);
  std::string part;
  int n = 0;
  while (std::getline(ss, part, ',')) {
    if (n >= 3) return std::nullopt;
    try {
      size_t pos = 0;
      v[n] = std::stod(part, &pos);
      if (pos != part.size() || !(v[n] > 0)) return std::nullopt;
    } catch (...) {
      return std::nullopt;
    }
    ++n;
  }
  if (n != 3) return std::nullopt;
  return v;
}

// A unit goes into the container and every JSON report: printable UTF-8, short.
bool is_plain_unit(const std::string& u) {
  if (u.size() > 32) return false;
  for (size_t i = 0; i < u.size();) {
    const auto c = static_cast<unsigned char>(u[i]);
    const int n = c < 0x80 ? 1 : (c >> 5) == 0x6 ? 2 : (c >> 4) == 0xe ? 3 : (c >> 3) == 0x1e ? 4 : 0;
    if (n == 0 || i + n > u.size() || (n == 1 && (c < 0x20 || c == 0x7f))) return false;
    for (int k = 1; k < n; ++k)
      if ((static_cast<unsigned char>(u[i + k]) >> 6) != 0x2) return false;
    i += n;
  }
  return true;
}

int run_import(const ImportArgs& a) {
  VXR_TRACE_SCOPE("import");
  ImportHints hints;
  if (!a.voxel_size.empty()) {
    hints.voxel_size = parse_voxel_size(a.voxel_size);
    if (!hints.voxel_size)
      return fail(invalid_argument("--voxel-size '" + a.voxel_size + "': give three positive numbers, e.g. 0.5,0.5,2"),
                  kExitUsage);
  }
  if (!a.unit.empty()) {
    if (!is_plain_unit(a.unit))
      return fail(invalid_argument("--unit: give a short unit name in UTF-8 letters, e.g. um, nm, mm, micrometer"),
                  kExitUsage);
    hints.unit = a.unit;
  }
  ImportOptions opt;
  opt.chunk_size = a.chunk;
  opt.resume = a.resume;
  opt.threads = std::max(1u, a.threads);
  const auto mem = parse_byte_size(a.memory);
  if (!mem || *mem < (uint64_t(16) << 20))
    return fail(invalid_argument("--memory '" + a.memory + "': give a size of at least 16M, e.g. 512M or 2G"), kExitUsage);
  opt.memory_bytes = *mem;
  hints.memory_bytes = *mem;  // readers size their buffers against it too
  if (a.downsample == "max") opt.downsample = vxc::Downsample::kMax;
  else if (a.downsample != "mean")
    return fail(invalid_argument("--downsample '" + a.downsample + "': use mean or max"), kExitUsage);
  if (a.codec == "lz4") opt.codec = vxc::Codec::kLz4;
  else if (a.codec == "shuffle-lz4") opt.codec = vxc::Codec::kShuffleLz4;
  else if (a.codec == "raw") opt.codec = vxc::Codec::kRaw;
  else if (a.codec != "auto")
    return fail(invalid_argument("--codec '" + a.codec + "': use auto, lz4, shuffle-lz4 or raw"), kExitUsage);

  auto source = open_import_source(a.inputs, hints);
  if (!source) return fail(source.status());
  std::vector<std::string> inputs = a.inputs;
  for (const std::string& f : (*source)->files()) inputs.push_back(f);
  if (Status s = check_output(a.output, inputs, "-o"); !s) return fail(s, kExitUsage);
  for (const std::string& w : (*source)->warnings()) std::fprintf(stderr, "vxr: warning: %s\n", w.c_str());
  auto layout = import_layout((*source)->info(), opt);
  if (!layout) return fail(layout.status(), kExitUsage);
  Progress progress("import", pyramid_work_bytes(*layout));
  auto summary = build_container(**source, a.output, opt, &progress);
  progress.finish();
  if (!summary) {
    const ErrorCode c = summary.status().code();
    return fail(summary.status(), c == ErrorCode::kInvalidArgument ? kExitUsage : kExitFailure);
  }
  const auto& L = summary->layout;
  std::printf("%s: %llux%llux%llu %s, %u channel(s), %u timepoint(s), %zu levels, %llu chunks (%llu resumed), "
              "%.2f s, %.1f MB/s, compression ratio %.2f\n",
              a.output.c_str(), (unsigned long long)L.info.dims[0], (unsigned long long)L.info.dims[1],
              (unsigned long long)L.info.dims[2], dtype_name(L.info.dtype), L.info.channels, L.info.timepoints,
              L.levels.size(), (unsigned long long)summary->chunks, (unsigned long long)summary->chunks_resumed,
              summary->seconds, summary->seconds > 0 ? summary->input_bytes / summary->seconds / 1e6 : 0.0,
              summary->file_bytes ? double(pyramid_work_bytes(L)) / double(summary->file_bytes) : 0.0);
  return kExitOk;
}

}  // namespace

int import_volume(const std::vector<std::string>& inputs, const std::string& output, const std::string& voxel_size,
                  const std::string& unit) {
  ImportArgs a;
  a.inputs = inputs;
  a.output = output;
  a.voxel_size = voxel_size;
  a.unit = unit;
  return run_import(a);
}

void add_import_command(CLI::App& app, Invocation& inv) {
  auto args = std::make_shared<ImportArgs>();
  auto* cmd = app.add_subcommand("import", "convert image files (raw+JSON, TIFF, OME-Zarr, ...) into a .vxc container with its "
                                           "resolution pyramid");
  cmd->add_option("inputs", args->inputs, "input file(s), folder or glob")->required();
  cmd->add_option("-o,--output", args->output, "output .vxc file")->required();
  cmd->add_option("--voxel-size", args->voxel_size, "voxel size x,y,z (overrides the file's)");
  cmd->add_option("--unit", args->unit, "unit of the voxel size, e.g. um, nm, mm");
  cmd->add_option("--chunk", args->chunk, "chunk size in voxels per side (default 64)")->check(CLI::Range(8, 512));
  cmd->add_option("--memory", args->memory, "memory budget for voxel buffers, e.g. 512M, 2G (default 512M)");
  cmd->add_flag("--resume", args->resume, "continue an interrupted import of the same output");
  cmd->add_option("--downsample", args->downsample, "pyramid downsampling: mean (default) or max");
  cmd->add_option("--codec", args->codec, "chunk codec: auto (default), lz4, shuffle-lz4, raw");
  cmd->add_option("--threads", args->threads, "encoder threads (default 2)")->check(CLI::Range(1, 64));
  cmd->callback([&inv, args] { inv.run = [args] { return run_import(*args); }; });
}

}  // namespace vxr::cli
