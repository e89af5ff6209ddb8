// `vxr bench import`: how fast `vxr import` converts, next to the bare LZ4
// codec on the same bytes in the same run, so the ratio shows how close the
// import gets to its codec bound.
//
// Data: the given inputs (any format open_import_source reads), else the
// bundled MRI sample; `--synthetic N` instead makes an N^3 u16 volume that
// looks like noisy fluorescence microscopy (volume/synthetic_microscopy.h). Reports, in out/bench/import.json: import MB/s
// (level-0 bytes / wall time, pyramid and file writing included, median of
// --repeats), and for LZ4 and byte-shuffle + LZ4 on chunk-sized blocks of
// the level-0 data: compression and decompression MB/s and ratios.
#include <lz4.h>

#include <array>
#include <chrono>
#include <cstdio>
#include <cstring>
#include <filesystem>

#include "assets/assets.h"
#include "bench.h"
#include "core/progress.h"
#include "volume/chunk_codec.h"
#include "volume/container_reader.h"
#include "volume/importers/import_source.h"
#include "volume/memory_slab_source.h"
#include "volume/pyramid_builder.h"
#include "volume/synthetic_microscopy.h"
#include "volume/tiff_writer.h"

namespace vxr::bench {
using cli::fail;
using cli::kExitOk;
namespace {

struct Options {
  BenchOptions common;
  std::vector<std::string> inputs;
  uint32_t synthetic = 0;
  uint32_t chunk = 64;
  std::string memory = "512M";
};

struct CodecFigures {
  double compress_mb_s = 0, decompress_mb_s = 0, ratio = 0;
  uint64_t decode_errors = 0;  // must stay 0: the timed decode really decoded every block
};

// Compresses `data` in blocks of `block` bytes, repeating until ~0.3 s passed.
CodecFigures measure_codec(const std::vector<uint8_t>& data, size_t block, uint32_t bpv, bool shuffle) {
  std::vector<uint8_t> shuffled(block), out(static_cast<size_t>(LZ4_compressBound(static_cast<int>(block))));
  std::vector<std::vector<uint8_t>> compressed;
  uint64_t in_bytes = 0, out_bytes = 0;
  auto t0 = std::chrono::steady_clock::now();
  double seconds = 0;
  int passes = 0;
  do {
    for (size_t off = 0; off < data.size(); off += block) {
      const size_t n = std::min(block, data.size() - off);
      const uint8_t* src = data.data() + off;
      if (shuffle) {
        byte_shuffle(src, shuffled.data(), n / bpv, bpv);
        src = shuffled.data();
      }
      const int c = LZ4_compress_default(reinterpret_cast<const char*>(src), reinterpret_cast<char*>(out.data()),
                                         static_cast<int>(n), static_cast<int>(out.size()));
      if (passes == 0) {
        in_bytes += n;
        out_bytes += static_cast<uint64_t>(c);
        compressed.emplace_back(out.begin(), out.begin() + c);
      }
    }
    ++passes;
    seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  } while (seconds < 0.3);
  CodecFigures f;
  if (compressed.empty()) return f;
  f.compress_mb_s = double(in_bytes) * passes / seconds / 1e6;
  f.ratio = double(in_bytes) / double(out_bytes);
  std::vector<uint8_t> dec(block);
  t0 = std::chrono::steady_clock::now();
  passes = 0;
  do {
    size_t off = 0;
    for (const auto& c : compressed) {
      const size_t n = std::min(block, data.size() - off);
      if (LZ4_decompress_safe(reinterpret_cast<const char*>(c.data()), reinterpret_cast<char*>(dec.data()),
                              static_cast<int>(c.size()), static_cast<int>(n)) != static_cast<int>(n))
        f.decode_errors++;
      if (shuffle) byte_unshuffle(dec.data(), shuffled.data(), n / bpv, bpv);
      if (passes == 0 && std::memcmp(shuffle ? shuffled.data() : dec.data(), data.data() + off, n) != 0)
        f.decode_errors++;
      off += n;
    }
    ++passes;
    seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  } while (seconds < 0.3);
  f.decompress_mb_s = double(in_bytes) * passes / seconds / 1e6;
  return f;
}

int run(const Options& o) {
  std::unique_ptr<SlabSource> source;
  std::string data_name;
  if (o.synthetic) {
    source = std::make_unique<SyntheticMicroscopySource>(std::array<uint64_t, 3>{o.synthetic, o.synthetic, o.synthetic});
    data_name = "synthetic noisy u16 microscopy " + std::to_string(o.synthetic) + "^3";
  } else if (!o.inputs.empty()) {
    auto s = open_import_source(o.inputs);
    if (!s) return fail(s.status());
    source = std::move(*s);
    data_name = o.inputs.front();
  } else {
    auto v = assets::sample_volume();
    if (!v) return fail(v.status());
    source = std::make_unique<MemorySlabSource>(*v);
    data_name = "bundled MRI sample (assets/mri-stack)";
  }
  const VolumeInfo info = source->info();
  const auto mem = parse_byte_size(o.memory);
  if (!mem) return fail(invalid_argument("--memory '" + o.memory + "': give a size like 512M"), cli::kExitUsage);
  ImportOptions opt;
  opt.chunk_size = o.chunk;
  opt.memory_bytes = *mem;
  std::error_code ec;
  std::filesystem::create_directories(o.common.out_dir, ec);
  const std::string tmp = (std::filesystem::path(o.common.out_dir) / "bench_import_tmp.vxc").string();
  const uint64_t input_bytes = info.voxels_per_volume() * dtype_bytes(info.dtype) * info.channels * info.timepoints;

  std::vector<double> seconds;
  double ratio = 0;
  uint64_t chunks = 0;
  for (int i = 0; i < std::max(1, o.common.repeats); ++i) {
    std::filesystem::remove(tmp, ec);
    std::filesystem::remove(tmp + ".partial", ec);
    auto s = build_container(*source, tmp, opt);
    if (!s) return fail(s.status());
    seconds.push_back(s->seconds);
    chunks = s->chunks;
    auto r = ContainerReader::open(tmp);
    if (!r) return fail(r.status());
    ratio = (*r)->compression_ratio();
  }
  std::filesystem::remove(tmp, ec);
  const double import_s = median(seconds);
  const double import_mb_s = double(input_bytes) / import_s / 1e6;

  // The same level-0 bytes (channel 0, timepoint 0; at most 1 GiB) in chunk-payload-sized blocks.
  Box3 box;
  box.size = info.dims;
  const uint64_t plane = info.dims[0] * info.dims[1] * dtype_bytes(info.dtype);
  box.size[2] = std::max<uint64_t>(1, std::min<uint64_t>(info.dims[2], (uint64_t(1) << 30) / plane));
  std::vector<uint8_t> data(box.voxels() * dtype_bytes(info.dtype));
  if (Status s = source->read_region(0, 0, box, data); !s) return fail(s);
  const uint32_t bpv = dtype_bytes(info.dtype);
  const size_t block = size_t(o.chunk + 2) * (o.chunk + 2) * (o.chunk + 2) * bpv;
  const CodecFigures lz4 = measure_codec(data, block, bpv, false);
  CodecFigures shuf;
  if (bpv > 1) shuf = measure_codec(data, block, bpv, true);
  if (lz4.decode_errors || shuf.decode_errors)
    return fail(internal_error("bench import: a timed LZ4 block did not decode back to its input"));
  const CodecFigures& used = default_codec(info.dtype) == vxc::Codec::kShuffleLz4 ? shuf : lz4;

  nlohmann::json doc;
  doc["benchmark"] = "import";
  doc["data"] = data_name;
  doc["dims"] = {info.dims[0], info.dims[1], info.dims[2]};
  doc["dtype"] = dtype_name(info.dtype);
  doc["channels"] = info.channels;
  doc["timepoints"] = info.timepoints;
  doc["input_bytes"] = input_bytes;
  doc["chunk_size"] = o.chunk;
  doc["memory_budget_bytes"] = *mem;
  doc["repeats"] = seconds.size();
  doc["import_seconds_median"] = import_s;
  doc["import_mb_per_s"] = import_mb_s;
  doc["chunks"] = chunks;
  doc["container_compression_ratio"] = ratio;
  doc["lz4"] = {{"compress_mb_per_s", lz4.compress_mb_s}, {"decompress_mb_per_s", lz4.decompress_mb_s}, {"ratio", lz4.ratio}};
  if (bpv > 1)
    doc["shuffle_lz4"] = {
        {"compress_mb_per_s", shuf.compress_mb_s}, {"decompress_mb_per_s", shuf.decompress_mb_s}, {"ratio", shuf.ratio}};
  doc["default_codec"] = bpv > 1 ? "shuffle-lz4" : "lz4";
  doc["import_vs_codec"] = import_mb_s / used.compress_mb_s;
  std::printf("import %.1f MB/s; bare %s %.1f MB/s (ratio %.2f); import reaches %.0f%% of the codec bound\n",
              import_mb_s, bpv > 1 ? "shuffle+LZ4" : "LZ4", used.compress_mb_s, used.ratio,
              100.0 * import_mb_s / used.compress_mb_s);
  auto path = write_report(o.common, "import", doc, nullptr);
  if (!path) return fail(path.status());
  return kExitOk;
}

struct SynthTiffOptions {
  std::string dims = "1024,1024,1100";
  std::string output;
  bool slices = false;
  std::string compression = "none";
  uint64_t seed = 1234;
};

// Writes the synthetic microscopy volume as a TIFF: one multi-page file, or a
// folder of single-page slices (slice_00000.tif, ...). Input for
// tools/measure-import-memory.sh; streams plane by plane.
int run_synth_tiff(const SynthTiffOptions& o) {
  std::array<uint64_t, 3> dims{};
  if (std::sscanf(o.dims.c_str(), "%llu,%llu,%llu", reinterpret_cast<unsigned long long*>(&dims[0]),
                  reinterpret_cast<unsigned long long*>(&dims[1]), reinterpret_cast<unsigned long long*>(&dims[2])) != 3 ||
      dims[0] == 0 || dims[1] == 0 || dims[2] == 0 || dims[0] > 65535 || dims[1] > 65535 || dims[2] > 1000000)
    return fail(invalid_argument("--dims '" + o.dims + "': give x,y,z, e.g. 1024,1024,1100 (x, y at most 65535)"),
                cli::kExitUsage);
  TiffCompression compression = TiffCompression::kNone;
  if (o.compression == "lzw") compression = TiffCompression::kLzw;
  else if (o.compression == "deflate") compression = TiffCompression::kDeflate;
  else if (o.compression != "none")
    return fail(invalid_argument("--compression '" + o.compression + "': use none, lzw or deflate"), cli::kExitUsage);
  SyntheticMicroscopySource source(dims, o.seed);
  VolumeInfo page_info = source.info();
  const uint64_t plane_bytes = dims[0] * dims[1] * 2;
  std::vector<uint8_t> plane(plane_bytes);
  Progress progress("synth-tiff", plane_bytes * dims[2]);
  std::unique_ptr<TiffStackWriter> stack;
  std::error_code ec;
  if (o.slices) {
    std::filesystem::create_directories(o.output, ec);
    if (ec) return fail(io_error(o.output + ": cannot create the folder (" + ec.message() + ")"));
    page_info.dims[2] = 1;
  } else {
    if (const auto parent = std::filesystem::path(o.output).parent_path(); !parent.empty())
      std::filesystem::create_directories(parent, ec);
    auto w = TiffStackWriter::create(o.output, page_info, false, compression);
    if (!w) return fail(w.status());
    stack = std::move(*w);
  }
  for (uint64_t z = 0; z < dims[2]; ++z) {
    Box3 box;
    box.origin = {0, 0, z};
    box.size = {dims[0], dims[1], 1};
    if (Status s = source.read_region(0, 0, box, plane); !s) return fail(s);
    if (stack) {
      if (Status s = stack->write_page(plane.data()); !s) return fail(s);
    } else {
      char name[32];
      std::snprintf(name, sizeof name, "slice_%05llu.tif", static_cast<unsigned long long>(z));
      auto w = TiffStackWriter::create((std::filesystem::path(o.output) / name).string(), page_info, false, compression);
      if (!w) return fail(w.status());
      if (Status s = (*w)->write_page(plane.data()); !s) return fail(s);
      if (Status s = (*w)->finish(); !s) return fail(s);
    }
    progress.advance(plane_bytes);
  }
  if (stack)
    if (Status s = stack->finish(); !s) return fail(s);
  progress.finish();
  std::printf("%s: %llux%llux%llu u16 synthetic microscopy (%zu cells), %.2f GiB of voxels%s%s\n", o.output.c_str(),
              static_cast<unsigned long long>(dims[0]), static_cast<unsigned long long>(dims[1]),
              static_cast<unsigned long long>(dims[2]), source.blob_count(),
              double(plane_bytes * dims[2]) / double(uint64_t(1) << 30), o.slices ? " in single-page slices" : "",
              compression == TiffCompression::kNone ? "" : (", " + o.compression + " compressed").c_str());
  return kExitOk;
}

}  // namespace

void add_synth_tiff_bench(CLI::App& bench, cli::Invocation& inv) {
  auto o = std::make_shared<SynthTiffOptions>();
  auto* cmd = bench.add_subcommand("synth-tiff", "write the synthetic u16 microscopy volume as a TIFF stack (input "
                                                 "for import benchmarks; tools/measure-import-memory.sh)");
  cmd->add_option("--dims", o->dims, "x,y,z voxels (default 1024,1024,1100: 2.15 GiB)");
  cmd->add_option("-o,--output", o->output, "output .tif (or folder with --slices)")->required();
  cmd->add_flag("--slices", o->slices, "write a folder of single-page TIFF slices instead of one multi-page file");
  cmd->add_option("--compression", o->compression, "none (default), lzw or deflate (with the horizontal predictor)");
  cmd->add_option("--seed", o->seed, "random seed (default 1234)");
  cmd->callback([&inv, o] { inv.run = [o] { return run_synth_tiff(*o); }; });
}

void add_import_bench(CLI::App& bench, cli::Invocation& inv) {
  auto o = std::make_shared<Options>();
  o->common.repeats = 3;
  auto* cmd = bench.add_subcommand("import", "import MB/s next to bare LZ4 (and shuffle+LZ4) MB/s on the same data");
  add_common_options(cmd, o->common);
  cmd->add_option("inputs", o->inputs, "input files (default: the bundled MRI sample)");
  cmd->add_option("--synthetic", o->synthetic, "use an N^3 synthetic noisy u16 microscopy-like volume instead");
  cmd->add_option("--chunk", o->chunk, "chunk size (default 64)")->check(CLI::Range(8, 512));
  cmd->add_option("--memory", o->memory, "import memory budget (default 512M)");
  cmd->callback([&inv, o] { inv.run = [o] { return run(*o); }; });
}

}  // namespace vxr::bench
