// RenderSettings / Scene: the JSON that `vxr render --settings` reads and
// cards store round-trips losslessly, and bad JSON is refused by key.
#include <doctest/doctest.h>

#include "scene/render_settings.h"

using namespace vxr;

TEST_CASE("settings: every field survives a JSON round trip") {
  RenderSettings s;
  s.model = OpticalModel::kIsosurface;
  s.channels.resize(2);
  s.channels[1].enabled = false;
  s.channels[1].window_lo = -3.5;
  s.channels[1].window_hi = 1e4;
  s.channels[1].gamma = 0.7;
  s.channels[1].colormap = "magenta";
  s.channels[0].color_points = {{0.0, {0, 0, 1}}, {1.0, {1, 0.5, 0}}};
  s.channels[0].opacity_points = {{0.2, 0.0}, {0.8, 0.9}};
  s.blend = ChannelBlend::kComposite;
  s.step_voxels = 0.125;
  s.density = 1.5;
  s.early_termination = 0.01;
  s.jitter = true;
  s.sample_offset = 0.25;
  s.iso_value = 77.25;
  s.iso_channel = 1;
  s.shading = {0.1, 0.2, 0.3, 40};
  s.depth_color = DepthColorMode::kAxisY;
  s.gradient_opacity = {true, 0.01, 0.2};
  s.max_steps = 1234;
  auto back = render_settings_from_json(render_settings_to_json(s));
  REQUIRE(back.is_ok());
  CHECK(*back == s);

  Scene sc;
  sc.volume = "head.vxc";
  sc.has_camera = true;
  sc.camera = {{1, 2, 3}, {0, 0, 0}, {0, 0, 1}, 55};
  sc.render = s;
  auto sb = scene_from_json(scene_to_json(sc));
  REQUIRE(sb.is_ok());
  CHECK(*sb == sc);
}

TEST_CASE("settings: missing keys keep defaults, bad ones are named") {
  auto d = render_settings_from_json(R"({"model": "mip"})");
  REQUIRE(d.is_ok());
  CHECK(d->model == OpticalModel::kMip);
  CHECK(d->channels.size() == 1);
  CHECK(d->step_voxels == 0.5);
  auto bad = render_settings_from_json("{\"model\": ");
  CHECK(bad.status().code() == ErrorCode::kInvalidArgument);
  CHECK(bad.status().message().find("malformed JSON") != std::string::npos);
  auto model = render_settings_from_json(R"({"model": "xray"})");
  CHECK(model.status().message().find("xray") != std::string::npos);
  auto type = render_settings_from_json(R"({"step_voxels": "fast"})");
  CHECK(type.status().code() == ErrorCode::kInvalidArgument);
  auto window = render_settings_from_json(R"({"channels": [{"window": [1, 2, 3]}]})");
  CHECK(window.status().message().find("window") != std::string::npos);
}
