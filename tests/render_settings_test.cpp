// RenderSettings / Scene: the JSON that `vxr render --settings` reads and
// cards store round-trips losslessly, and bad JSON is refused by key.
#include <doctest/doctest.h>

#include <cmath>

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
  s.clip = {true, {0.6, 0.8, 0.0}, -0.3125, true, {0.1, 0.2, 0.0}, {0.9, 0.75, 1.0}};
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
  auto clip = render_settings_from_json(R"({"clip": 3})");
  CHECK(clip.status().message().find("\"clip\" must be an object") != std::string::npos);
  auto cut = render_settings_from_json(R"({"clip": {"cut": {"offset": "far"}}})");
  CHECK(cut.status().message().find("offset") != std::string::npos);
}

TEST_CASE("scene: transform, timepoint, channels, viewport and renderer survive a JSON round trip bit for bit") {
  Scene sc;
  sc.volume = "/data/embryo.vxc";
  sc.timepoint = 7;
  sc.channels = {2, 0};
  // Doubles that a %g-style writer would round: the round trip must keep every bit.
  sc.transform.position = {0.1, -1.0 / 3.0, 1e-300};
  sc.transform.rotation = {std::cos(0.3), 0.0, std::sin(0.3), 1e-17};
  sc.transform.scale = 2.0 / 3.0;
  sc.has_camera = true;
  sc.camera = {{0.1 + 0.2, 2, 3}, {0, 0, 0.7}, {0, 1, 0}, 41.123456789012345};
  sc.viewport = {640, 480};
  sc.renderer = "dense";
  sc.path = "fragment";
  sc.lod_bias = -0.75;
  auto back = scene_from_json(scene_to_json(sc));
  REQUIRE(back.is_ok());
  CHECK(*back == sc);
  // A default scene stays default (no camera, identity transform).
  auto plain = scene_from_json(scene_to_json(Scene{}));
  REQUIRE(plain.is_ok());
  CHECK(*plain == Scene{});
}

TEST_CASE("scene: bad transform, viewport and renderer are refused by name") {
  auto zero = scene_from_json(R"({"transform": {"rotation": [0, 0, 0, 0]}})");
  CHECK(zero.status().message().find("zero quaternion") != std::string::npos);
  auto scale = scene_from_json(R"({"transform": {"scale": -1}})");
  CHECK(scale.status().message().find("transform.scale") != std::string::npos);
  auto vp = scene_from_json(R"({"viewport": [640, 0]})");
  CHECK(vp.status().message().find("viewport") != std::string::npos);
  auto r = scene_from_json(R"({"renderer": "magic"})");
  CHECK(r.status().message().find("magic") != std::string::npos);
  auto tp = scene_from_json(R"({"timepoint": "last"})");
  CHECK(tp.status().code() == ErrorCode::kInvalidArgument);
}

TEST_CASE("scene: camera_in_volume_frame undoes the volume transform") {
  CameraState cam{{0, 0, 10}, {4, 0, 0}, {0, 1, 0}, 30};
  // Identity: unchanged.
  CHECK(camera_in_volume_frame(cam, VolumeTransform{}) == cam);
  // Volume moved by +4 in x, turned 90 degrees about y, doubled: the target
  // (the volume centre) maps to 0, and the eye 10 units along world z from
  // it lies 5 units along the volume's -x (R^-1 of +z about y is -x).
  VolumeTransform t;
  t.position = {4, 0, 0};
  t.rotation = {std::sqrt(0.5), 0, std::sqrt(0.5), 0};
  t.scale = 2;
  const CameraState v = camera_in_volume_frame({{4, 0, 10}, {4, 0, 0}, {0, 1, 0}, 30}, t);
  CHECK(v.target[0] == doctest::Approx(0).epsilon(1e-12));
  CHECK(v.eye[0] == doctest::Approx(-5));
  CHECK(std::abs(v.eye[1]) < 1e-12);
  CHECK(std::abs(v.eye[2]) < 1e-12);
  CHECK(v.up[1] == doctest::Approx(1));
  CHECK(v.fov_y_deg == 30);
}
