// How `vxr` subcommands plug into the command line: one file per subcommand,
// each with an add_*_command() that registers its options and sets `run`.
#pragma once

#include <CLI/CLI.hpp>
#include <functional>
#include <memory>
#include <string>

#include "core/status.h"
#include "gpu/context.h"
#include "render/camera.h"
#include "render/card_scene.h"
#include "scene/render_settings.h"

namespace vxr::cli {

// Exit codes shared by every subcommand.
constexpr int kExitOk = 0;
constexpr int kExitFailure = 1;  // the work failed (bad file, GPU error, ...)
constexpr int kExitUsage = 2;    // the command line or settings were wrong

struct Invocation {
  std::function<int()> run;  // set by the chosen subcommand's callback
};

void add_version_command(CLI::App& app, Invocation& inv);
void add_demo_command(CLI::App& app, Invocation& inv);
void add_render_command(CLI::App& app, Invocation& inv);
void add_compare_command(CLI::App& app, Invocation& inv);
void add_bench_command(CLI::App& app, Invocation& inv);
void add_view_command(CLI::App& app, Invocation& inv);
void add_import_command(CLI::App& app, Invocation& inv);
void add_info_command(CLI::App& app, Invocation& inv);
void add_verify_command(CLI::App& app, Invocation& inv);
void add_export_tiff_command(CLI::App& app, Invocation& inv);
void add_annotate_command(CLI::App& app, Invocation& inv);
void add_cards_command(CLI::App& app, Invocation& inv);
void add_project_command(CLI::App& app, Invocation& inv);
void add_catalog_command(CLI::App& app, Invocation& inv);

// `vxr import INPUTS -o OUTPUT` with the default options (what `vxr project
// create` runs); prints as `vxr import` does and returns its exit code.
int import_volume(const std::vector<std::string>& inputs, const std::string& output, const std::string& voxel_size,
                  const std::string& unit);

// Shared by `vxr render` and `vxr view` (tools/scene_flags.cpp):
// --annotations STORE.
void add_annotations_option(CLI::App* cmd, std::string& store);

// Opens the Vulkan device (VXR_DEVICE, VXR_VALIDATION from the environment).
Result<std::unique_ptr<gpu::Context>> open_gpu();

// Prints "vxr: <message>" on stderr and returns `code`.
int fail(const Status& status, int code = kExitFailure);

}  // namespace vxr::cli
