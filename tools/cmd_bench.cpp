// `vxr bench <what>`: the parent of every benchmark. Each benchmark lives in
// tools/bench/bench_<what>.cpp and is registered here with one line.
#include "bench/bench.h"
#include "command.h"

namespace vxr::bench {
void add_movie_bench(CLI::App& bench, cli::Invocation& inv);  // bench_movie.cpp
void add_desktop_bench(CLI::App& bench, cli::Invocation& inv);  // bench_desktop.cpp
}

namespace vxr::cli {

void add_bench_command(CLI::App& app, Invocation& inv) {
  auto* bench = app.add_subcommand("bench", "run a benchmark; writes JSON (and plots) under out/bench/");
  bench->require_subcommand(1);
  bench::add_roofline_bench(*bench, inv);
  bench::add_xr_bench(*bench, inv);
  bench::add_lod_bench(*bench, inv);
  bench::add_peer_bench(*bench, inv);
  bench::add_import_bench(*bench, inv);
  bench::add_synth_tiff_bench(*bench, inv);
  bench::add_stability_bench(*bench, inv);
  bench::add_accuracy_bench(*bench, inv);
  bench::add_movie_bench(*bench, inv);
  bench::add_desktop_bench(*bench, inv);
}

}  // namespace vxr::cli
