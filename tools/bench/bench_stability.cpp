// `vxr bench stability --cases N --seed S`: the numerical stress suite
// (bench/stability.h). Exit 0 when every case passes, 1 otherwise; the report
// lists per class {cases, failures, worst_error} and the first failures with
// the seed and index that re-run them alone.
#include <chrono>
#include <cstdio>
#include <map>

#include "bench.h"
#include "bench/stability.h"
#include "core/progress.h"

namespace vxr::bench {

void add_stability_bench(CLI::App& bench, cli::Invocation& inv) {
  auto* cmd = bench.add_subcommand("stability", "seeded numerical stress cases, GPU vs the CPU double reference");
  auto opt = std::make_shared<BenchOptions>();
  auto cases = std::make_shared<uint32_t>(1000);
  auto seed = std::make_shared<uint64_t>(1);
  auto first = std::make_shared<uint32_t>(0);
  add_common_options(cmd, *opt);
  cmd->add_option("--cases", *cases, "number of cases (default 1000)")->check(CLI::Range(1u, 10000000u));
  cmd->add_option("--seed", *seed, "seed of the case generator (default 1)");
  cmd->add_option("--first", *first, "index of the first case (to re-run one failure: --first I --cases 1)");
  cmd->callback([&inv, opt, cases, seed, first] {
    inv.run = [opt, cases, seed, first] {
      auto gpu = cli::open_gpu();
      if (!gpu) return cli::fail(gpu.status());

      const auto pipelines = std::make_shared<BrickPipelines>();  // compiled once for every case
      const auto& classes = stability_classes();
      struct Tally {
        uint32_t cases = 0, failures = 0;
        double worst = 0.0;
        double worst_ratio = 0.0;  // max-abs / case bound, uncapped cases
        uint32_t capped = 0;
        double worst_over_fraction_capped = 0.0;
      };
      std::vector<Tally> tally(classes.size());
      nlohmann::json failures = nlohmann::json::array();
      uint32_t failed = 0, non_finite = 0;
      const auto t0 = std::chrono::steady_clock::now();
      Progress progress("stability", *cases, false);
      for (uint32_t k = 0; k < *cases; ++k) {
        const uint32_t index = *first + k;
        const StabilityCase c = make_stability_case(*seed, index);
        const CaseOutcome o = run_stability_case(**gpu, c, pipelines);
        Tally& t = tally[c.class_index];
        ++t.cases;
        t.worst = std::max(t.worst, o.max_abs);
        if (!o.capped && o.bound > 0) t.worst_ratio = std::max(t.worst_ratio, o.max_abs / o.bound);
        if (o.capped) {
          ++t.capped;
          t.worst_over_fraction_capped = std::max(t.worst_over_fraction_capped, o.over_fraction);
        }
        if (o.non_finite) ++non_finite;
        if (!o.passed) {
          ++t.failures;
          ++failed;
          if (failures.size() < 50)
            failures.push_back({{"index", index},
                                {"class", classes[c.class_index].name},
                                {"error", o.failure},
                                {"max_abs", o.max_abs},
                                {"note", c.note},
                                {"rerun", "vxr bench stability --seed " + std::to_string(*seed) + " --first " +
                                              std::to_string(index) + " --cases 1"}});
        }
        progress.advance(1);
      }
      progress.finish();
      const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();

      nlohmann::json cls = nlohmann::json::object();
      for (size_t i = 0; i < classes.size(); ++i)
        cls[classes[i].name] = {{"cases", tally[i].cases},
                                {"failures", tally[i].failures},
                                {"worst_error", tally[i].worst},
                                {"worst_error_255", tally[i].worst * 255.0},
                                {"worst_error_over_bound", tally[i].worst_ratio},
                                {"capped", tally[i].capped},
                                {"worst_over_fraction_capped", tally[i].worst_over_fraction_capped},
                                {"class_bound", classes[i].bound},
                                {"class_bound_255", classes[i].bound * 255.0},
                                {"why", classes[i].why}};
      nlohmann::json doc = {
          {"seed", *seed},
          {"first", *first},
          {"cases", *cases},
          {"failures", failed},
          {"non_finite", non_finite},
          {"seconds", seconds},
          {"error_metric", "max-abs over all pixels and RGBA channels, 0..1 units, GPU RGBA32F vs the CPU double "
                           "reference at the same step"},
          {"classes", cls},
          {"failed_cases", failures},
      };
      std::fprintf(stderr, "stability: %u cases, %u failed, %u with NaN/Inf, %.1f s\n", *cases, failed, non_finite,
                   seconds);
      auto path = write_report(*opt, "stability", doc, gpu->get());
      if (!path) return cli::fail(path.status());
      return failed == 0 ? cli::kExitOk : cli::kExitFailure;
    };
  });
}

}  // namespace vxr::bench
