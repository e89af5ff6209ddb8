// Shared plumbing for `vxr bench <what>`: options, timing, JSON output.
//
// Benchmarks measure; they never pass or fail on speed. Each writes
// <out>/<name>.json (and plots where it has them) and prints the paths.
#pragma once

#include <CLI/CLI.hpp>
#include <chrono>
#include <functional>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "command.h"
#include "core/status.h"

namespace vxr::bench {

struct PlotSpec;

struct BenchOptions {
  bool json = false;                // print the JSON document on stdout too
  std::string out_dir = "out/bench";
  int repeats = 5;                  // timed runs per point; the median is reported
};

void add_common_options(CLI::App* cmd, BenchOptions& options);

// Runs `fn` once untimed (warm-up: shader compilation, caches), then
// `repeats` times; returns the median wall time in milliseconds.
double median_ms(int repeats, const std::function<Status()>& fn, Status* error);

double median(std::vector<double> values);

// Wall milliseconds since `t0`.
double ms_since(std::chrono::steady_clock::time_point t0);

// Adds "machine" facts (device, driver, fingerprint, CPU threads) to `doc`,
// writes <out_dir>/<name>.json atomically, prints its path (and the document
// with --json). Returns the path.
Result<std::string> write_report(const BenchOptions& options, const std::string& name, nlohmann::json doc,
                                 const gpu::Context* ctx);

// Draws `plot` to <out_dir>/<name>.png (atomically; creates the folder).
// Returns the path, for the report and for the caller to print.
Result<std::string> write_plot(const BenchOptions& options, const std::string& name, const PlotSpec& plot);

// One registration per benchmark, called from tools/cmd_bench.cpp.
void add_roofline_bench(CLI::App& bench, cli::Invocation& inv);
void add_xr_bench(CLI::App& bench, cli::Invocation& inv);
void add_lod_bench(CLI::App& bench, cli::Invocation& inv);
void add_import_bench(CLI::App& bench, cli::Invocation& inv);
void add_synth_tiff_bench(CLI::App& bench, cli::Invocation& inv);
void add_stability_bench(CLI::App& bench, cli::Invocation& inv);
void add_accuracy_bench(CLI::App& bench, cli::Invocation& inv);
void add_peer_bench(CLI::App& bench, cli::Invocation& inv);

}  // namespace vxr::bench
