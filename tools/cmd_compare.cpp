// `vxr compare a.png b.png [--json]`: how far apart two pictures are, in 8-bit
// units over all four channels: largest difference, RMSE, PSNR.
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <nlohmann/json.hpp>

#include "command.h"
#include "core/output_file.h"
#include "core/image.h"

namespace vxr::cli {

void add_compare_command(CLI::App& app, Invocation& inv) {
  struct Options {
    std::string a, b;
    bool json = false;
    std::string side_by_side;
  };
  auto o = std::make_shared<Options>();
  auto* cmd = app.add_subcommand("compare", "max-abs, RMSE (8-bit units) and PSNR (dB) between two PNGs");
  cmd->add_option("a", o->a, "first PNG")->required();
  cmd->add_option("b", o->b, "second PNG")->required();
  cmd->add_flag("--json", o->json, "print {\"max_abs\", \"rmse\", \"psnr\"} as JSON");
  cmd->add_option("--side-by-side", o->side_by_side, "also write a PNG: a | b | difference (x16, over black)");
  cmd->callback([&inv, o] {
    inv.run = [o] {
      if (!o->side_by_side.empty()) {
        if (Status st = check_output(o->side_by_side, {{o->a, o->b}}, "--side-by-side"); !st) return fail(st, kExitUsage);
      }
      auto a = read_png(o->a);
      if (!a) return fail(a.status());
      auto b = read_png(o->b);
      if (!b) return fail(b.status());
      if (a->width != b->width || a->height != b->height)
        return fail(invalid_argument(o->a + " is " + std::to_string(a->width) + "x" + std::to_string(a->height) + " but " +
                                     o->b + " is " + std::to_string(b->width) + "x" + std::to_string(b->height) +
                                     "; compare images of the same size"),
                    kExitUsage);
      const PixelDifference diff = compare_pixels(a->pixels, b->pixels);
      const int max_abs = diff.max_abs;
      const double rmse = diff.rmse;
      if (!o->side_by_side.empty()) {
        const uint32_t w = a->width, h = a->height;
        ImageRgba8 out(3 * w, h);
        for (uint32_t y = 0; y < h; ++y)
          for (uint32_t x = 0; x < w; ++x) {
            const uint8_t* pa = a->at(x, y);
            const uint8_t* pb = b->at(x, y);
            uint8_t* d = out.at(2 * w + x, y);
            for (int c = 0; c < 3; ++c) {
              out.at(x, y)[c] = pa[c];
              out.at(w + x, y)[c] = pb[c];
              d[c] = static_cast<uint8_t>(std::min(255, 16 * std::abs(int(pa[c]) - int(pb[c]))));
            }
            out.at(x, y)[3] = out.at(w + x, y)[3] = d[3] = 255;
          }
        if (Status st = write_png(o->side_by_side, out); !st) return fail(st);
      }
      const double psnr = rmse > 0 ? 20.0 * std::log10(255.0 / rmse) : INFINITY;
      if (o->json) {
        nlohmann::json j = {{"max_abs", max_abs}, {"rmse", rmse}, {"identical", rmse == 0.0}};
        j["psnr"] = std::isfinite(psnr) ? nlohmann::json(psnr) : nlohmann::json(nullptr);  // JSON has no infinity
        std::printf("%s\n", j.dump().c_str());
      } else {
        std::printf("max_abs %d  rmse %.4f  psnr %s dB\n", max_abs, rmse,
                    std::isfinite(psnr) ? std::to_string(psnr).c_str() : "inf");
      }
      return kExitOk;
    };
  });
}

}  // namespace vxr::cli
