// `vxr demo`: renders the bundled sample volume to DIR/demo.png.
#include <cstdio>
#include <filesystem>

#include "assets/assets.h"
#include "command.h"
#include "core/trace.h"
#include "render/raycaster.h"

namespace vxr::cli {

void add_demo_command(CLI::App& app, Invocation& inv) {
  auto* cmd = app.add_subcommand("demo", "render the bundled sample volume (an MRI head) to DIR/demo.png");
  auto out_dir = std::make_shared<std::string>("out");
  cmd->add_option("--out", *out_dir, "output folder (default: out)");
  cmd->callback([&inv, out_dir] {
    inv.run = [out_dir] {
      VXR_TRACE_SCOPE("demo");
      auto volume = assets::sample_volume();
      if (!volume) return fail(volume.status());
      auto gpu = open_gpu();
      if (!gpu) return fail(gpu.status());
      auto caster = Raycaster::create(**gpu);
      if (!caster) return fail(caster.status());
      if (Status s = (*caster)->set_volume(*volume); !s) return fail(s);

      const VolumePlacement placement{volume->dims, volume->voxel_size};
      RaycastSettings settings;
      settings.colormap = "hot";
      settings.window_lo = 20;
      settings.window_hi = 220;
      settings.step_voxels = 0.5;
      settings.density = 0.08;
      auto image = (*caster)->render(orbit_camera(placement, 30.0, 25.0, 1.25), settings, 512, 512);
      if (!image) return fail(image.status());

      std::error_code ec;
      std::filesystem::create_directories(*out_dir, ec);
      const std::string path = (std::filesystem::path(*out_dir) / "demo.png").string();
      if (Status s = write_png(path, over_black(*image)); !s) return fail(s);
      std::printf("%s\n", path.c_str());
      return kExitOk;
    };
  });
}

}  // namespace vxr::cli
