// Volume manipulation from controller input, independent of any device:
// one-hand grab moves and turns the volume rigidly with the hand; two-hand
// pinch scales about the hands' midpoint. Asserted on the transform numbers.
#include <doctest/doctest.h>

#include "xr/interaction.h"
#include "xr/script.h"

using namespace vxr;
using namespace vxr::xr;

namespace {

InputState hands(glm::dvec3 l, double grab_l, glm::dvec3 r, double grab_r) {
  InputState s;
  s.hands[kLeft].tracked = s.hands[kRight].tracked = true;
  s.hands[kLeft].grip.position = l;
  s.hands[kRight].grip.position = r;
  s.hands[kLeft].grab = grab_l;
  s.hands[kRight].grab = grab_r;
  return s;
}

void check_vec(const glm::dvec3& a, const glm::dvec3& b, double eps = 1e-12) {
  CHECK(a.x == doctest::Approx(b.x).epsilon(eps));
  CHECK(a.y == doctest::Approx(b.y).epsilon(eps));
  CHECK(a.z == doctest::Approx(b.z).epsilon(eps));
}

VolumeTransform start() {
  VolumeTransform t;
  t.position = {0.0, 1.5, -0.5};
  t.scale = 0.001;
  return t;
}

}  // namespace

TEST_CASE("interaction: one-hand grab moves the volume with the hand, release leaves it there") {
  VolumeTransform t = start();
  GrabInteraction g;
  g.update(hands({0.1, 1.2, -0.3}, 0.0, {0.3, 1.2, -0.3}, 0.0), t);
  check_vec(t.position, {0.0, 1.5, -0.5});
  auto started = g.update(hands({0.1, 1.2, -0.3}, 1.0, {0.3, 1.2, -0.3}, 0.0), t);
  CHECK(started[kLeft]);
  CHECK(!started[kRight]);
  g.update(hands({0.3, 1.0, -0.2}, 1.0, {0.3, 1.2, -0.3}, 0.0), t);
  check_vec(t.position, {0.2, 1.3, -0.4});  // moved by the hand's (0.2, -0.2, 0.1)
  CHECK(t.scale == 0.001);
  g.update(hands({0.5, 1.0, -0.2}, 0.1, {0.3, 1.2, -0.3}, 0.0), t);  // released: no longer follows
  check_vec(t.position, {0.2, 1.3, -0.4});
}

TEST_CASE("interaction: one-hand grab turns the volume about the hand") {
  VolumeTransform t = start();
  GrabInteraction g;
  InputState in = hands({0.0, 1.5, -0.3}, 1.0, {0.3, 1.2, -0.3}, 0.0);
  g.update(in, t);
  // Hand turns 90 degrees about +y in place: the centre 0.2 m in front (-z) of it swings to its -x side.
  in.hands[kLeft].grip.orientation = glm::angleAxis(glm::half_pi<double>(), glm::dvec3(0, 1, 0));
  g.update(in, t);
  check_vec(t.position, {-0.2, 1.5, -0.3}, 1e-12);
  const glm::dvec3 x_axis = t.orientation * glm::dvec3(1, 0, 0);
  check_vec(x_axis + glm::dvec3(0, 0, 2), {0.0, 0.0, 1.0}, 1e-12);  // +x now points along -z
}

TEST_CASE("interaction: two-hand pinch scales about the midpoint of the hands") {
  VolumeTransform t = start();
  GrabInteraction g;
  g.update(hands({-0.1, 1.2, -0.3}, 1.0, {0.1, 1.2, -0.3}, 1.0), t);
  // Hands twice as far apart, midpoint (0, 1.2, -0.3) unchanged: scale x2 about the midpoint.
  g.update(hands({-0.2, 1.2, -0.3}, 1.0, {0.2, 1.2, -0.3}, 1.0), t);
  CHECK(t.scale == doctest::Approx(0.002).epsilon(1e-12));
  check_vec(t.position, glm::dvec3(0, 1.2, -0.3) + 2.0 * (glm::dvec3(0, 1.5, -0.5) - glm::dvec3(0, 1.2, -0.3)));
  // The volume point that sat under the midpoint still does.
  const glm::dvec3 p = start().to_volume({0.0, 1.2, -0.3});
  check_vec(t.to_reference(p), {0.0, 1.2, -0.3});
  // Pinch in to half the start distance: scale 0.5 of the start.
  g.update(hands({-0.05, 1.2, -0.3}, 1.0, {0.05, 1.2, -0.3}, 1.0), t);
  CHECK(t.scale == doctest::Approx(0.0005).epsilon(1e-12));
  // Letting go of one hand hands over to a one-hand grab without a jump.
  const VolumeTransform before = t;
  g.update(hands({-0.05, 1.2, -0.3}, 0.0, {0.05, 1.2, -0.3}, 1.0), t);
  check_vec(t.position, before.position);
  CHECK(t.scale == before.scale);
}

TEST_CASE("interaction: a scripted pinch through the pose-script interpolation gives the expected scale") {
  Script s;
  std::string err;
  REQUIRE(parse_script_text(R"({"keys": [
      {"frame": 0, "left": {"grip": {"position": [-0.1, 1.3, -0.3]}, "squeeze": 1},
                   "right": {"grip": {"position": [0.1, 1.3, -0.3]}, "squeeze": 1}},
      {"frame": 10, "left": {"grip": {"position": [-0.3, 1.3, -0.3]}},
                    "right": {"grip": {"position": [0.3, 1.3, -0.3]}}}]})",
                            s, err));
  VolumeTransform t = start();
  GrabInteraction g;
  for (uint64_t f = 0; f <= 10; ++f) {
    const ScriptFrame sf = s.at(f);
    InputState in;
    for (int h = 0; h < 2; ++h) {
      in.hands[h].tracked = true;
      in.hands[h].grip = sf.hands[h].grip;
      in.hands[h].grab = sf.hands[h].squeeze;
    }
    g.update(in, t);
    if (f == 5) CHECK(t.scale == doctest::Approx(0.002).epsilon(1e-12));
  }
  CHECK(t.scale == doctest::Approx(0.003).epsilon(1e-12));
}

TEST_CASE("script: bad input is refused with a message") {
  Script s;
  std::string err;
  CHECK(!parse_script_text(R"({"keys": [{"frame": 5}, {"frame": 5}]})", s, err));
  CHECK(err.find("increasing") != std::string::npos);
  CHECK(!parse_script_text("{", s, err));
  CHECK(!parse_script_text(R"({"view": {"width": 0}})", s, err));
}

namespace {

// A camera path for a movie: four head keys, uneven spacing, turning as it goes.
const char* kCameraPath = R"({"interpolation": "%s", "keys": [
  {"frame": 0,  "head": {"position": [0, 1.6, 0],     "orientation": [0, 0, 0, 1]}},
  {"frame": 10, "head": {"position": [0.5, 1.7, -0.2], "orientation": [0, 0.3826834, 0, 0.9238795]}},
  {"frame": 30, "head": {"position": [0.6, 1.5, -0.9], "orientation": [0.1305262, 0.7010574, 0, 0.7010574]}},
  {"frame": 40, "head": {"position": [0, 1.6, -1.2],   "orientation": [0, 1, 0, 0]}}]})";

Script camera_path(const char* mode) {
  char text[1024];
  std::snprintf(text, sizeof text, kCameraPath, mode);
  Script s;
  std::string err;
  REQUIRE_MESSAGE(parse_script_text(text, s, err), err);
  return s;
}

// Velocity of the head just before and just after frame f (central differences on each side).
std::pair<glm::dvec3, glm::dvec3> velocity_around(const Script& s, double f) {
  const double e = 1e-4;
  const glm::dvec3 before = (s.at(f).head.position - s.at(f - e).head.position) / e;
  const glm::dvec3 after = (s.at(f + e).head.position - s.at(f).head.position) / e;
  return {before, after};
}

// Angular velocity (radians per frame) just before and after frame f, as rotation vectors.
std::pair<glm::dvec3, glm::dvec3> spin_around(const Script& s, double f) {
  const double e = 1e-4;
  auto rotvec = [](const glm::dquat& a, const glm::dquat& b) {
    glm::dquat d = b * glm::conjugate(a);
    if (d.w < 0) d = -d;
    return 2.0 * glm::dvec3(d.x, d.y, d.z);
  };
  return {rotvec(s.at(f - e).head.orientation, s.at(f).head.orientation) / e,
          rotvec(s.at(f).head.orientation, s.at(f + e).head.orientation) / e};
}

}  // namespace

TEST_CASE("script: a smooth camera path passes through every key with no velocity jump, easing at the ends") {
  const Script smooth = camera_path("smooth"), linear = camera_path("linear");
  REQUIRE(smooth.interpolation == Interpolation::kSmooth);
  for (const auto& [frame, key] : smooth.keys) {
    const Pose p = smooth.at(double(frame)).head;
    check_vec(p.position, key.head.position, 1e-12);
    CHECK(std::abs(glm::dot(p.orientation, key.head.orientation)) == doctest::Approx(1.0).epsilon(1e-12));
  }
  for (double f : {10.0, 30.0}) {
    const auto [vb, va] = velocity_around(smooth, f);
    CHECK(glm::length(va - vb) < 1e-3 * glm::length(va));
    const auto [wb, wa] = spin_around(smooth, f);
    CHECK(glm::length(wa - wb) < 1e-3 * glm::length(wa));
    // The check can fail: the linear path's velocity jumps at the same keys.
    const auto [lb, la] = velocity_around(linear, f);
    CHECK(glm::length(la - lb) > 0.1 * glm::length(la));
  }
  // Eases in and out: no motion at the first and last key.
  CHECK(glm::length(smooth.at(1e-4).head.position - smooth.at(0.0).head.position) < 1e-6);
  CHECK(glm::length(smooth.at(40.0).head.position - smooth.at(40.0 - 1e-4).head.position) < 1e-6);
  for (double f = 0; f <= 40; f += 0.25)
    CHECK(glm::length(smooth.at(f).head.orientation) == doctest::Approx(1.0).epsilon(1e-12));
  std::string err;
  Script bad;
  CHECK(!parse_script_text(R"({"interpolation": "cubic"})", bad, err));
  CHECK(err.find("\"smooth\"") != std::string::npos);
}

TEST_CASE("interaction: thumbstick forward flies along the aim ray (the volume comes closer)") {
  VolumeTransform t = start();
  GrabInteraction g;
  InputState in = hands({0.1, 1.2, -0.3}, 0.0, {0.3, 1.2, -0.3}, 0.0);
  // Right hand aims along -x (turned 90 degrees left about +y), stick fully forward for 0.1 s.
  in.hands[kRight].aim.orientation = glm::angleAxis(glm::half_pi<double>(), glm::dvec3(0, 1, 0));
  in.hands[kRight].thumbstick = {0.0, 1.0};
  g.update(in, t, 0.1);
  check_vec(t.position, {0.05, 1.5, -0.5}, 1e-12);  // flew 0.05 m along -x: the volume moved +x
  // Inside the deadzone nothing moves; while grabbing, the stick is ignored.
  in.hands[kRight].thumbstick = {0.0, 0.1};
  g.update(in, t, 0.1);
  check_vec(t.position, {0.05, 1.5, -0.5}, 1e-12);
  in.hands[kRight].thumbstick = {0.0, 1.0};
  in.hands[kLeft].grab = 1.0;
  g.update(in, t, 0.1);
  check_vec(t.position, {0.05, 1.5, -0.5}, 1e-12);
}
