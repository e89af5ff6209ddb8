// `vxr version`: the vxr version and the Vulkan device it would use.
#include <cstdio>

#include "command.h"

namespace vxr::cli {

void add_version_command(CLI::App& app, Invocation& inv) {
  auto* cmd = app.add_subcommand("version", "print the vxr version and the Vulkan device, driver and API version");
  cmd->callback([&inv] {
    inv.run = [] {
      std::printf("vxr %s\n", VXR_VERSION);
      auto gpu = open_gpu();
      if (!gpu) return fail(gpu.status());
      const auto& info = (*gpu)->info();
      std::printf("device: %s\ndriver: %s (%s)\napi: %s\n", info.name.c_str(), info.driver_name.c_str(),
                  info.driver_info.c_str(), info.api_string().c_str());
      return kExitOk;
    };
  });
}

}  // namespace vxr::cli
