// The desktop window under Xvfb: vxr opens it, presents, and what the X
// server shows in the window (grabbed with XGetImage) is the volume, pixel
// for pixel what the same view renders offscreen (sRGB-encoded on an sRGB window).
#include <doctest/doctest.h>

#include <algorithm>
#include <cmath>

#include "assets/assets.h"
#include "golden.h"
#include "gpu_fixture.h"
#include "volume/dense_chunk_source.h"
#include "xr/eye_renderer.h"
#include "xr/view_session.h"
#include "xr_test_util.h"

using namespace vxr;
using namespace vxr::xr;

TEST_CASE("desktop: the window opens under Xvfb and the screenshot shows the volume") {
  test::GpuTestScope scope;
  const std::string dir = test::xr_out_dir("desktop");
  const std::string shot = dir + "/screenshot.png";
  const test::ChildResult r = test::run_child(test::own_config(dir) + "xvfb-run -a -s '-screen 0 640x480x24' " + std::string(VXR_BINARY) +
                                              " view --sample --desktop --no-ui --frames 3 --width 128 --height 128"
                                              " --screenshot " + shot);
  INFO(r.output);
  REQUIRE(r.exit_code == 0);
  CHECK(r.output.find("using the desktop window") != std::string::npos);
  auto img = read_png(shot);
  REQUIRE(img.is_ok());
  REQUIRE(img->width == 128);
  REQUIRE(img->height == 128);
  CHECK(test::looks_non_blank(*img));

  // The same view offscreen: head at the start pose looking at the volume, +-40 degrees.
  auto volume = assets::sample_volume();
  REQUIRE(volume.is_ok());
  std::vector<DenseVolume> channels{*volume};
  auto source = DenseChunkSource::create(std::move(channels));
  REQUIRE(source.is_ok());
  auto eyes = EyeRenderer::create(test::gpu_context(), *source);
  REQUIRE(eyes.is_ok());
  ViewSpec view;
  view.pose.position = {0.0, 1.6, 0.0};
  view.fov = {-0.6981317, 0.6981317, 0.6981317, -0.6981317};
  view.width = view.height = 128;
  auto expected = (*eyes)->render(view, default_volume_transform((*eyes)->placement()), default_view_settings(), {});
  REQUIRE(expected.is_ok());
  // The window is sRGB where the X server offers it (Xvfb does): the eye
  // holds the linear value encoded. The offscreen byte b stands for a linear
  // value within b +- 0.5 (/255), so the window's byte must lie within the
  // encodings of those ends (+-1 for the encoder's rounding).
  const bool srgb = r.output.find("sRGB swapchain") != std::string::npos;
  CHECK((srgb || r.output.find("UNORM swapchain") != std::string::npos));
  auto encode = [](double v) {
    v = std::clamp(v, 0.0, 1.0);
    return 255.0 * (v <= 0.0031308 ? 12.92 * v : 1.055 * std::pow(v, 1.0 / 2.4) - 0.055);
  };
  const ImageRgba8 offscreen = over_black(*expected);
  int outside = 0, worst = 0;
  for (uint32_t y = 0; y < 128; ++y)
    for (uint32_t x = 0; x < 128; ++x)
      for (int c = 0; c < 3; ++c) {
        const double b = offscreen.at(x, y)[c];
        const double lo = srgb ? std::floor(encode((b - 0.5) / 255.0)) - 1 : b - 1;
        const double hi = srgb ? std::ceil(encode((b + 0.5) / 255.0)) + 1 : b + 1;
        const double w = img->at(x, y)[c];
        if (w < lo || w > hi) {
          ++outside;
          worst = std::max(worst, int(std::max(lo - w, w - hi)));
        }
      }
  MESSAGE("screenshot vs offscreen (" << std::string(srgb ? "sRGB" : "UNORM") << " window): " << outside
                                      << " channels outside the bound, by at most " << worst);
  CHECK(outside == 0);
}

TEST_CASE("desktop: --mirror shows exactly what the headset's swapchain images hold") {
  const std::string dir = test::xr_out_dir("mirror");
  test::use_test_runtime(dir, R"({"view": {"width": 64, "height": 64}, "dump_frames": [3]})");
  const std::string shot = dir + "/mirror.png";
  const test::ChildResult r = test::run_child(test::own_config(dir) + "xvfb-run -a -s '-screen 0 640x480x24' " + std::string(VXR_BINARY) +
                                              " view --sample --xr --mirror --frames 3 --width 64 --height 64"
                                              " --screenshot " + shot);
  INFO(r.output);
  REQUIRE(r.exit_code == 0);
  CHECK(r.output.find("mirrored to a desktop window 128x64") != std::string::npos);
  auto window = read_png(shot);
  REQUIRE(window.is_ok());
  REQUIRE(window->width == 128);
  REQUIRE(window->height == 64);
  for (int eye = 0; eye < 2; ++eye) {
    auto swap = read_png(dir + "/dump/frame000003_" + (eye == 0 ? "left" : "right") + ".png");
    REQUIRE(swap.is_ok());
    CHECK(test::looks_non_blank(*swap));
    int max_abs = 0;
    for (uint32_t y = 0; y < 64; ++y)
      for (uint32_t x = 0; x < 64; ++x)
        for (int c = 0; c < 3; ++c)
          max_abs = std::max(max_abs, std::abs(int(window->at(eye * 64 + x, y)[c]) - int(swap->at(x, y)[c])));
    CHECK(max_abs == 0);
  }
  CHECK(test::core_validation_messages(dir).empty());
}
