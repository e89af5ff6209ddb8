// `vxr`: the command line. Each subcommand lives in its own cmd_*.cpp.
#include <cstdio>
#include <exception>
#include <new>

#include "core/sanitizer_defaults.h"
#include "command.h"
#include "core/trace.h"
#include "gpu/context.h"

namespace vxr::cli {

Result<std::unique_ptr<gpu::Context>> open_gpu() { return gpu::Context::create(gpu::ContextOptions::from_env()); }

int fail(const Status& status, int code) {
  std::fprintf(stderr, "vxr: %s\n", status.message().c_str());
  return code;
}

}  // namespace vxr::cli

namespace {
bool has_subcommand(const CLI::App& app, const std::string& name) {
  for (const CLI::App* sub : app.get_subcommands([](const CLI::App*) { return true; }))
    if (sub->get_name() == name) return true;
  return false;
}
}  // namespace

namespace vxr::cli {
void add_play_command(CLI::App& app, Invocation& inv);  // tools/cmd_play.cpp
}

int run_vxr(int argc, char** argv) {
  using namespace vxr::cli;
  CLI::App app{"vxr: explore very large multidimensional images in OpenXR, a desktop window, or headless"};
  app.name("vxr");
  app.require_subcommand(1);
  app.fallthrough();  // lets `vxr demo --trace t.json` reach the global option
  std::string trace_path;
  app.add_option("--trace", trace_path,
                 "write a Chrome trace-event JSON (Perfetto, chrome://tracing); needs a profile build");

  Invocation inv;
  add_version_command(app, inv);
  add_demo_command(app, inv);
  add_render_command(app, inv);
  add_compare_command(app, inv);
  add_bench_command(app, inv);
  add_view_command(app, inv);
  add_import_command(app, inv);
  add_info_command(app, inv);
  add_verify_command(app, inv);
  add_export_tiff_command(app, inv);
  add_annotate_command(app, inv);
  add_cards_command(app, inv);
  add_project_command(app, inv);
  add_catalog_command(app, inv);
  add_play_command(app, inv);

  // CLI11 reports a stray word as "a subcommand is required"; name it instead.
  if (argc > 1 && argv[1][0] != '-' && !has_subcommand(app, argv[1])) {
    std::fprintf(stderr, "vxr: unknown command '%s'\n\n%s", argv[1], app.help().c_str());
    return kExitUsage;
  }
  try {
    app.parse(argc, argv);
  } catch (const CLI::CallForHelp& e) {
    return app.exit(e);
  } catch (const CLI::CallForAllHelp& e) {
    return app.exit(e);
  } catch (const CLI::ParseError& e) {
    // Usage of the subcommand that was being parsed, else of vxr itself.
    const auto chosen = app.get_subcommands();
    const std::string usage = chosen.empty() ? app.help() : chosen.back()->help();
    std::fprintf(stderr, "vxr: %s\n\n%s", e.what(), usage.c_str());
    return kExitUsage;
  }

  if (!trace_path.empty()) {
#ifdef VXR_PROFILE
    vxr::trace::start();
#else
    std::fprintf(stderr, "vxr: --trace needs a profile build (cmake --preset profile && cmake --build --preset profile)\n");
    return kExitUsage;
#endif
  }

  int code = inv.run ? inv.run() : kExitUsage;

  if (!trace_path.empty()) {
    vxr::Status s = vxr::trace::write(trace_path);
    if (!s.is_ok()) code = fail(s);
  }
  // With validation on, any message is a failure even if the work "succeeded".
  if (const uint64_t n = vxr::gpu::validation_message_count(); n > 0) {
    std::fprintf(stderr, "vxr: %llu Vulkan validation message(s); first: %s\n", static_cast<unsigned long long>(n),
                 vxr::gpu::first_validation_message().c_str());
    if (code == kExitOk) code = 3;
  }
  return code;
}

// Last line of defence: a third-party exception (nlohmann::json, std::filesystem,
// an allocation) must end in one line and exit 1, never in abort() and a core.
int main(int argc, char** argv) {
  try {
    return run_vxr(argc, argv);
  } catch (const std::bad_alloc&) {
    std::fprintf(stderr, "vxr: out of memory; lower --memory or the output size, or free memory\n");
  } catch (const std::exception& e) {
    std::fprintf(stderr, "vxr: internal error: %s (please report this with the command line)\n", e.what());
  } catch (...) {
    std::fprintf(stderr, "vxr: internal error: unknown exception (please report this with the command line)\n");
  }
  return vxr::cli::kExitFailure;
}
