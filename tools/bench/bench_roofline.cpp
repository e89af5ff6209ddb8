// `vxr bench roofline`: the device's ceilings and the ray caster's share of them.
#include <algorithm>
#include <cmath>
#include <cstdio>

#include "bench.h"
#include "render/lod/memory_volume.h"
#include "roofline.h"

namespace vxr::bench {

void add_roofline_bench(CLI::App& bench, cli::Invocation& inv) {
  auto* cmd = bench.add_subcommand("roofline",
                                   "measure the device's memory and sampling ceilings and the ray caster's share");
  auto opt = std::make_shared<BenchOptions>();
  add_common_options(cmd, *opt);
  cmd->callback([&inv, opt] {
    inv.run = [opt] {
      auto gpu = cli::open_gpu();
      if (!gpu) return cli::fail(gpu.status());
      gpu::Context& ctx = **gpu;
      std::fprintf(stderr, "roofline: calibrating %s ...\n", ctx.info().name.c_str());
      auto roof = measure_roofline(ctx, opt->repeats);
      if (!roof) return cli::fail(roof.status());

      // The ray caster on a 256^3 u8 volume, MIP, 512x512, 1-voxel steps.
      DenseVolume vol;
      vol.dims = {256, 256, 256};
      vol.data.resize(vol.voxel_count());
      for (uint32_t z = 0, i = 0; z < 256; ++z)
        for (uint32_t y = 0; y < 256; ++y)
          for (uint32_t x = 0; x < 256; ++x, ++i)
            vol.data[i] = static_cast<uint8_t>(127.5 + 127.5 * std::sin(x * 0.11) * std::cos(y * 0.07 + z * 0.05));
      auto caster = MemoryVolumeRenderer::create(ctx, {vol});
      if (!caster) return cli::fail(caster.status());
      const VolumePlacement placement{vol.dims, vol.voxel_size};
      const Camera cam = orbit_camera(placement, 30.0, 20.0, 1.3);
      RenderSettings rs;
      rs.model = OpticalModel::kMip;
      rs.step_voxels = 1.0;
      Status err;
      BrickFrameSettings frame;
      frame.lod.skip_empty = false;  // every sample marched: the count below is exact
      const double ms =
          median_ms(opt->repeats, [&] { return (*caster)->render(cam, rs, 512, 512, frame).status(); }, &err);
      if (!err.is_ok()) return cli::fail(err);
      const uint64_t samples = dense_sample_count(cam, placement, rs.step_voxels, 512, 512);  // MIP never terminates early
      const double rate = samples / (ms * 1e-3);

      nlohmann::json doc = {
          {"ceilings",
           {{"copy_gb_per_s", roof->copy_gb_per_s},
            {"trilinear_samples_per_s", roof->trilinear_samples_per_s},
            {"transfer_gb_per_s", roof->transfer_gb_per_s},
            {"copy_ms", roof->copy_ms},
            {"transfer_ms", roof->transfer_ms},
            {"sample_ms", roof->sample_ms}}},
          {"raycaster",
           {{"scene", "256^3 u8, MIP, 512x512, step 1 voxel"},
            {"ms", ms},
            {"samples", samples},
            {"samples_per_s", rate},
            {"roofline_ratio", rate / roof->trilinear_samples_per_s},
            {"note", "ms is wall time of render() incl. submit, readback of 1 MiB"}}},
      };
      std::fprintf(stderr, "roofline: shader copy %.1f GB/s, vkCmdCopyBuffer %.1f GB/s, trilinear %.0f M samples/s; ray caster %.0f M samples/s (%.2f of ceiling)\n",
                   roof->copy_gb_per_s, roof->transfer_gb_per_s, roof->trilinear_samples_per_s / 1e6, rate / 1e6,
                   rate / roof->trilinear_samples_per_s);
      auto path = write_report(*opt, "roofline", doc, &ctx);
      return path ? cli::kExitOk : cli::fail(path.status());
    };
  });
}

}  // namespace vxr::bench
