// `vxr demo`: renders the bundled sample volume to DIR/demo.png through the
// one renderer (open_volume_session's source, the brick renderer).
#include <cstdio>
#include <algorithm>
#include <filesystem>
#include <vector>

#include "command.h"
#include "core/trace.h"
#include "render/lod/brick_renderer.h"
#include "render/volume_session.h"

namespace vxr::cli {

void add_demo_command(CLI::App& app, Invocation& inv) {
  auto* cmd = app.add_subcommand("demo", "render the bundled sample volume (an MRI head) to DIR/demo.png");
  auto out_dir = std::make_shared<std::string>("out");
  cmd->add_option("--out", *out_dir, "output folder (default: out)");
  cmd->callback([&inv, out_dir] {
    inv.run = [out_dir] {
      VXR_TRACE_SCOPE("demo");
      auto session = open_volume_session("", {});
      if (!session) return fail(session.status());
      auto gpu = open_gpu();
      if (!gpu) return fail(gpu.status());
      BrickRendererOptions ro;
      ro.preload_if_fits = true;  // the whole sample at full detail from the first frame
      auto caster = BrickRenderer::create(**gpu, *session->source, ro);
      if (!caster) return fail(caster.status());

      // Four views of the head, 256x256 each, in one 512x512 picture: emission-absorption
      // (hot), MIP (viridis), the shaded skin isosurface, and colour by depth (turbo).
      const VolumePlacement placement = (*caster)->placement();
      const Camera camera = orbit_camera(placement, 30.0, 25.0, 1.25);
      RenderSettings base;
      base.channels[0].window_lo = 20;
      base.channels[0].window_hi = 220;
      base.step_voxels = 0.5;
      base.density = 0.08;
      std::vector<RenderSettings> views(4, base);
      views[0].channels[0].colormap = "hot";
      views[1].model = OpticalModel::kMip;
      views[1].channels[0].colormap = "viridis";
      views[2].model = OpticalModel::kIsosurface;
      views[2].iso_value = 60;
      views[2].channels[0].color_points = {{0.0, {0.95, 0.8, 0.7}}, {1.0, {0.95, 0.8, 0.7}}};  // skin
      views[3].channels[0].colormap = "turbo";
      views[3].depth_color = DepthColorMode::kView;
      views[3].density = 0.2;
      ImageRgba8 mosaic(512, 512);
      for (int k = 0; k < 4; ++k) {
        auto image = (*caster)->render(camera, views[k], BrickFrameSettings{}, 256, 256);
        if (!image) return fail(image.status());
        const ImageRgba8 shown = over_black(*image);
        for (uint32_t y = 0; y < 256; ++y)
          for (uint32_t x = 0; x < 256; ++x)
            std::copy_n(shown.at(x, y), 4, mosaic.at(x + (k % 2) * 256, y + (k / 2) * 256));
      }

      std::error_code ec;
      std::filesystem::create_directories(*out_dir, ec);
      const std::string path = (std::filesystem::path(*out_dir) / "demo.png").string();
      if (Status s = write_png(path, mosaic); !s) return fail(s);
      std::printf("%s\n", path.c_str());
      return kExitOk;
    };
  });
}

}  // namespace vxr::cli
