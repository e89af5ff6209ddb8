// `vxr verify`: checks every checksum and the index of a .vxc container.
#include <cstdio>

#include "command.h"
#include "volume/container_verify.h"

namespace vxr::cli {

void add_verify_command(CLI::App& app, Invocation& inv) {
  auto path = std::make_shared<std::string>();
  auto* cmd = app.add_subcommand("verify", "check a .vxc container's checksums and index; exit 0 when clean, 1 when not");
  cmd->add_option("file", *path, ".vxc file")->required();
  cmd->callback([&inv, path] {
    inv.run = [path] {
      const VerifyReport rep = verify_container(*path);
      for (const std::string& p : rep.problems) std::printf("BAD %s\n", p.c_str());
      if (rep.ok()) {
        std::printf("%s: OK, %llu chunks checked\n", path->c_str(), (unsigned long long)rep.chunks_checked);
        return kExitOk;
      }
      std::fprintf(stderr, "vxr: %s: %zu problem(s) found (%llu chunks checked)\n", path->c_str(), rep.problems.size(),
                   (unsigned long long)rep.chunks_checked);
      return kExitFailure;
    };
  });
}

}  // namespace vxr::cli
