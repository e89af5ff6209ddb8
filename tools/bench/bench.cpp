#include "bench.h"

#include "bench/plot.h"
#include "core/image.h"
#include "core/output_file.h"

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <thread>

namespace vxr::bench {

void add_common_options(CLI::App* cmd, BenchOptions& o) {
  cmd->add_flag("--json", o.json, "also print the JSON report on stdout");
  cmd->add_option("--out", o.out_dir, "folder for reports and plots (default: out/bench)");
  cmd->add_option("--repeats", o.repeats, "timed runs per point; the median is reported")->check(CLI::Range(1, 1000));
}

double median(std::vector<double> v) {
  if (v.empty()) return 0.0;
  std::sort(v.begin(), v.end());
  const size_t n = v.size();
  return n % 2 ? v[n / 2] : 0.5 * (v[n / 2 - 1] + v[n / 2]);
}

double ms_since(std::chrono::steady_clock::time_point t0) {
  return std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
}

double median_ms(int repeats, const std::function<Status()>& fn, Status* error) {
  if (Status s = fn(); !s.is_ok()) {
    if (error) *error = s;
    return 0.0;
  }
  std::vector<double> times;
  for (int i = 0; i < repeats; ++i) {
    const auto t0 = std::chrono::steady_clock::now();
    if (Status s = fn(); !s.is_ok()) {
      if (error) *error = s;
      return 0.0;
    }
    times.push_back(ms_since(t0));
  }
  return median(times);
}

namespace {
// <out_dir>/<file>, the folder created if need be (a failure shows when the file is written).
std::string out_path(const BenchOptions& o, const std::string& file) {
  std::error_code ec;
  std::filesystem::create_directories(o.out_dir, ec);
  return (std::filesystem::path(o.out_dir) / file).string();
}
}  // namespace

Result<std::string> write_report(const BenchOptions& o, const std::string& name, nlohmann::json doc,
                                 const gpu::Context* ctx) {
  nlohmann::json machine = {{"cpu_threads", std::thread::hardware_concurrency()}};
  if (ctx) {
    machine["device"] = ctx->info().name;
    machine["driver"] = ctx->info().driver_info;
    machine["fingerprint"] = ctx->info().fingerprint();
  }
  doc["machine"] = machine;
  const std::string path = out_path(o, name + ".json");
  if (Status w = write_file_atomically(path, doc.dump(2, ' ', false, nlohmann::json::error_handler_t::replace) + "\n"); !w) return w;
  if (o.json) std::printf("%s\n", doc.dump(2).c_str());
  std::printf("%s\n", path.c_str());
  return path;
}

Result<std::string> write_plot(const BenchOptions& o, const std::string& name, const PlotSpec& plot) {
  const std::string path = out_path(o, name + ".png");
  VXR_RETURN_IF_ERROR(write_png(path, render_plot(plot)));
  return path;
}

}  // namespace vxr::bench
