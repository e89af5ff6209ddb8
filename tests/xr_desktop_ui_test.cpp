// The desktop viewer under Xvfb, driven by a UI script (vxr view --desktop
// --ui-script): the real MRI stack from ../shared/testdata, screenshots of the
// swapchain image after each change, and the pixels checked: the panels are
// drawn, a colour map change changes the hue, a narrower window brightens,
// count markers and a measurement show, and the store holds what was placed.
#include <doctest/doctest.h>

#include <cmath>
#include <filesystem>
#include <fstream>

#include "annotate/annotation_store.h"
#include "assets/assets.h"
#include "core/image.h"
#include "volume/dense_chunk_source.h"
#include "xr/desktop/desktop_target.h"
#include "xr/desktop/viewer_setup.h"
#include "xr/view_session.h"
#include "xr_test_util.h"

using namespace vxr;

namespace {

const std::string kMri = std::string(VXR_TESTDATA_DIR) + "/slices/mri-stack";
constexpr uint32_t kWidth = 480, kHeight = 360;

std::string viewer_command(const std::string& script, const std::string& extra) {
  return test::own_config(std::filesystem::path(script).parent_path().string()) +
         "xvfb-run -a -s '-screen 0 1024x768x24' " + std::string(VXR_BINARY) + " view " + kMri +
         " --desktop --width " + std::to_string(kWidth) + " --height " + std::to_string(kHeight) + " --ui-script " +
         script + " " + extra;
}

struct Tint {
  double red = 0, green = 0, blue = 0, luminance = 0;  // red/green/blue: shares of r+g+b; luminance 0..255
  size_t pixels = 0;
};
// Mean colour of the volume's pixels (any channel above `floor`) in rows [y0, y1).
Tint tint(const ImageRgba8& img, uint32_t y0, uint32_t y1, int floor = 24) {
  Tint t;
  for (uint32_t y = y0; y < y1; ++y)
    for (uint32_t x = 0; x < img.width; ++x) {
      const uint8_t* p = img.at(x, y);
      if (std::max({p[0], p[1], p[2]}) <= floor) continue;
      const double sum = double(p[0]) + p[1] + p[2];
      t.red += p[0] / sum;
      t.green += p[1] / sum;
      t.blue += p[2] / sum;
      t.luminance += 0.2126 * p[0] + 0.7152 * p[1] + 0.0722 * p[2];
      ++t.pixels;
    }
  if (t.pixels) {
    t.red /= double(t.pixels);
    t.green /= double(t.pixels);
    t.blue /= double(t.pixels);
    t.luminance /= double(t.pixels);
  }
  return t;
}

size_t count_exact(const ImageRgba8& img, uint8_t r, uint8_t g, uint8_t b) {
  size_t n = 0;
  for (uint32_t y = 0; y < img.height; ++y)
    for (uint32_t x = 0; x < img.width; ++x) {
      const uint8_t* p = img.at(x, y);
      n += p[0] == r && p[1] == g && p[2] == b;
    }
  return n;
}

// Pixels of the box [x0, x1) x [y0, y1) that differ between two images.
size_t differing(const ImageRgba8& a, const ImageRgba8& b, uint32_t x0, uint32_t y0, uint32_t x1, uint32_t y1) {
  size_t n = 0;
  for (uint32_t y = y0; y < y1; ++y)
    for (uint32_t x = x0; x < x1; ++x)
      n += a.at(x, y)[0] != b.at(x, y)[0] || a.at(x, y)[1] != b.at(x, y)[1] || a.at(x, y)[2] != b.at(x, y)[2];
  return n;
}

}  // namespace

TEST_CASE("desktop viewer: a scripted session under Xvfb shows each change in its screenshots") {
  const std::string dir = test::xr_out_dir("desktop_ui");
  auto shot = [&](const std::string& name) { return dir + "/" + name + ".png"; };
  const std::string script = dir + "/session.json";
  // Volume-only shots hide the panels so hue and brightness are the volume's.
  std::ofstream(script) << nlohmann::json::array({
                               "wait 3",
                               "ui off",
                               "screenshot " + shot("plain"),
                               "ui on",
                               "wait 2",
                               "screenshot " + shot("panels"),
                               "ui off",
                               "colormap 0 viridis",
                               "screenshot " + shot("viridis"),
                               "window 0 0 60",
                               "screenshot " + shot("bright"),
                               "visible 0 off",
                               "screenshot " + shot("hidden"),
                               "visible 0 on",
                               "count 90 110 13",
                               "count 130 110 13",
                               "measure 80 150 13 150 150 13",
                               "screenshot " + shot("marked"),
                               "card two cells and a distance",
                           })
                               .dump(1);
  const std::string store_dir = dir + "/store";
  std::filesystem::remove_all(store_dir);
  REQUIRE(annotate::AnnotationStore::open(store_dir, true).is_ok());  // vxr view draws an existing store
  const test::ChildResult r = test::run_child(viewer_command(script, "--annotations " + store_dir));
  INFO(r.output);
  REQUIRE(r.exit_code == 0);  // validation is on: any Vulkan message would exit 3
  CHECK(r.output.find("using the desktop window") != std::string::npos);

  std::map<std::string, ImageRgba8> img;
  for (const char* name : {"plain", "panels", "viridis", "bright", "hidden", "marked"}) {
    auto png = read_png(shot(name));
    REQUIRE_MESSAGE(png.is_ok(), name);
    REQUIRE(png->width == kWidth);
    REQUIRE(png->height == kHeight);
    img[name] = std::move(png).value();
  }

  // The volume is there: a good share of the window is lit.
  const Tint plain = tint(img["plain"], 0, kHeight);
  MESSAGE("plain: " << plain.pixels << " lit pixels, shares r/g/b " << plain.red << "/" << plain.green << "/"
                    << plain.blue << ", luminance " << plain.luminance);
  CHECK(plain.pixels > kWidth * kHeight / 10);

  // Panels: the channel panel (top left, 340 px wide) covers pixels the bare render shows otherwise.
  const size_t panel_area = 300 * 100;
  const size_t changed = differing(img["plain"], img["panels"], 10, 10, 310, 110);
  MESSAGE("panel box: " << changed << " of " << panel_area << " pixels differ from the render without panels");
  CHECK(changed > panel_area / 2);
  // ... and not the volume right of the panels (they are 340 px wide from x = 10).
  CHECK(differing(img["plain"], img["panels"], 360, kHeight / 2 - 20, kWidth - 20, kHeight / 2 + 20) == 0);

  // hot -> viridis: from red-dominated to green/blue.
  const Tint viridis = tint(img["viridis"], 0, kHeight);
  MESSAGE("viridis: shares r/g/b " << viridis.red << "/" << viridis.green << "/" << viridis.blue);
  CHECK(plain.red > plain.blue + 0.2);
  CHECK(viridis.blue > plain.blue + 0.1);
  CHECK(viridis.red < plain.red - 0.1);

  // Window 0..60 instead of the data's: the same data maps further up the map: brighter.
  const Tint bright = tint(img["bright"], 0, kHeight);
  MESSAGE("luminance: window from the data " << viridis.luminance << ", window 0..60 " << bright.luminance);
  CHECK(bright.luminance > viridis.luminance * 1.15);

  // The only channel hidden: nothing drawn.
  CHECK(tint(img["hidden"], 0, kHeight, 0).pixels == 0);

  // Markers (class "default": pure yellow discs) and the measurement (a white line) are drawn over the volume.
  const size_t yellow_before = count_exact(img["bright"], 255, 255, 0), yellow = count_exact(img["marked"], 255, 255, 0);
  const size_t white_before = count_exact(img["bright"], 255, 255, 255), white = count_exact(img["marked"], 255, 255, 255);
  MESSAGE("pure yellow pixels " << yellow_before << " -> " << yellow << ", pure white " << white_before << " -> " << white);
  CHECK(yellow >= yellow_before + 2 * 60);  // two discs of radius 6+
  CHECK(white >= white_before + 40);        // a 70-voxel line, 2 px wide

  // The store holds what the session placed, and the card its scene and the last screenshot.
  auto store = annotate::AnnotationStore::open(store_dir, false);
  REQUIRE(store.is_ok());
  auto markers = (*store)->markers();
  REQUIRE(markers.is_ok());
  CHECK(markers->size() == 2);
  auto measurements = (*store)->measurements();
  REQUIRE(measurements.is_ok());
  REQUIRE(measurements->size() == 1);
  CHECK((*store)->length(measurements->front()) == doctest::Approx(70.0 * (*store)->voxel_space().voxel_size[0]));
  auto cards = (*store)->cards();
  REQUIRE(cards.is_ok());
  REQUIRE(cards->size() == 1);
  auto card = (*store)->card(cards->front().id, true);
  REQUIRE(card.is_ok());
  CHECK(card->title == "two cells and a distance");
  CHECK(card->scene_json.find("viridis") != std::string::npos);
  std::ifstream marked(shot("marked"), std::ios::binary);
  const std::vector<uint8_t> marked_bytes((std::istreambuf_iterator<char>(marked)), std::istreambuf_iterator<char>());
  CHECK(card->snapshot_png == marked_bytes);
}

TEST_CASE("desktop viewer: tool clicks place where the window shows them, and a panel card brings its view back") {
  const std::string dir = test::xr_out_dir("desktop_ui_tools");
  auto shot = [&](const std::string& name) { return dir + "/" + name + ".png"; };
  const std::string script = dir + "/tools.json";
  std::ofstream(script) << nlohmann::json::array({
                               "wait 2",
                               "ui off",
                               "screenshot " + shot("before"),
                               "tool count cells",
                               "click 330 180",
                               "tool navigate",
                               "click 100 100",  // navigating: places nothing
                               "tool measure",
                               "click 160 280",
                               "click 320 280",
                               "screenshot " + shot("clicked"),
                               // The panel's card buttons: save this view, change it, restore the card.
                               "panel-card marked view",
                               "colormap 0 viridis",
                               "orbit 80 30",
                               "screenshot " + shot("changed"),
                               "restore-card 1",
                               "screenshot " + shot("restored"),
                           })
                               .dump(1);
  const std::string store_dir = dir + "/store";
  std::filesystem::remove_all(store_dir);
  REQUIRE(annotate::AnnotationStore::open(store_dir, true).is_ok());  // vxr view draws an existing store
  const test::ChildResult r = test::run_child(viewer_command(script, "--annotations " + store_dir));
  INFO(r.output);
  REQUIRE(r.exit_code == 0);
  auto before = read_png(shot("before"));
  auto clicked = read_png(shot("clicked"));
  REQUIRE(before.is_ok());
  REQUIRE(clicked.is_ok());

  auto store = annotate::AnnotationStore::open(store_dir, false);
  REQUIRE(store.is_ok());
  auto markers = (*store)->markers();
  REQUIRE(markers.is_ok());
  REQUIRE(markers->size() == 1);
  const annotate::Marker& m = markers->front();
  CHECK(m.cls == "cells");
  MESSAGE("marker at voxel " << m.pos[0] << ", " << m.pos[1] << ", " << m.pos[2]);
  auto measurements = (*store)->measurements();
  REQUIRE(measurements.is_ok());
  REQUIRE(measurements->size() == 1);
  const annotate::Measurement& d = measurements->front();
  MESSAGE("measurement " << d.a[0] << "," << d.a[1] << "," << d.a[2] << " -> " << d.b[0] << "," << d.b[1] << ","
                         << d.b[2]);
  // Both clicks were on one screen row: the ends differ along one volume axis only ...
  int moved = 0;
  for (int i = 0; i < 3; ++i) moved += std::abs(d.b[i] - d.a[i]) > 1.0;
  CHECK(moved == 1);
  // ... and the marker, on the same plane through the orbit centre, lies where its pixel says
  // along that axis: (330 - 160) / (320 - 160) of the way from the first end to the second.
  for (int i = 0; i < 3; ++i) {
    if (std::abs(d.b[i] - d.a[i]) <= 1.0) continue;
    CHECK(std::abs(d.b[i] - d.a[i]) > 10.0);
    CHECK(m.pos[i] == doctest::Approx(d.a[i] + (330.0 - 160.0) / 160.0 * (d.b[i] - d.a[i])).epsilon(0.01));
  }

  // The window draws them where they were clicked: the class colour (yellow) at the marker's
  // pixel, the measurement's white line along its row; neither was there before.
  // Centre and size of the pure yellow blob within 15 pixels of (cx, cy).
  auto yellow_near = [](const ImageRgba8& img, int cx, int cy) {
    double sx = 0, sy = 0, n = 0;
    for (int y = cy - 15; y <= cy + 15; ++y)
      for (int x = cx - 15; x <= cx + 15; ++x) {
        const uint8_t* p = img.at(uint32_t(x), uint32_t(y));
        if (p[0] != 255 || p[1] != 255 || p[2] != 0) continue;
        sx += x;
        sy += y;
        ++n;
      }
    return std::array<double, 3>{n ? sx / n : 0, n ? sy / n : 0, n};
  };
  const auto disc = yellow_near(*clicked, 330, 180);
  MESSAGE("yellow disc: " << disc[2] << " pixels centred at " << disc[0] << ", " << disc[1]);
  CHECK(disc[2] >= 60);  // radius 6+, less the black rim
  CHECK(std::abs(disc[0] - 330.0) < 1.5);
  CHECK(std::abs(disc[1] - 180.0) < 1.5);
  CHECK(yellow_near(*before, 330, 180)[2] < 10);
  size_t white_on_row = 0;
  for (uint32_t x = 180; x < 300; ++x)
    for (uint32_t y = 279; y <= 281; ++y) {
      const uint8_t* p = clicked->at(x, y);
      white_on_row += p[0] == 255 && p[1] == 255 && p[2] == 255;
    }
  CHECK(white_on_row >= 120);  // a 2-pixel line: at least one white pixel per column

  // The panel's card holds that frame's picture (the clicked view) and its scene; restoring it
  // brings back the colour map and the camera: the window shows the marked view again.
  auto cards = (*store)->cards();
  REQUIRE(cards.is_ok());
  REQUIRE(cards->size() == 1);
  CHECK(cards->front().id == 1);
  auto card = (*store)->card(1, true);
  REQUIRE(card.is_ok());
  CHECK(card->title == "marked view");
  CHECK(card->scene_json.find("viridis") == std::string::npos);
  const std::string card_png = dir + "/card.png";
  std::ofstream(card_png, std::ios::binary).write(reinterpret_cast<const char*>(card->snapshot_png.data()),
                                                  std::streamsize(card->snapshot_png.size()));
  auto card_image = read_png(card_png);
  REQUIRE(card_image.is_ok());
  CHECK(differing(*card_image, *clicked, 0, 0, kWidth, kHeight) == 0);
  auto changed = read_png(shot("changed"));
  auto restored = read_png(shot("restored"));
  REQUIRE(changed.is_ok());
  REQUIRE(restored.is_ok());
  const size_t elsewhere = differing(*changed, *clicked, 0, 0, kWidth, kHeight);
  const size_t back = differing(*restored, *clicked, 0, 0, kWidth, kHeight);
  MESSAGE("pixels differing from the card's view: changed " << elsewhere << ", restored " << back);
  CHECK(elsewhere > kWidth * kHeight / 10);
  CHECK(back < kWidth * kHeight / 1000);  // the orbit comes back from the card's camera to rounding
  for (const auto& entry : std::filesystem::directory_iterator(store_dir))  // the picture's scratch file is gone
    CHECK(entry.path().filename().string().find("card-snapshot") == std::string::npos);
}

TEST_CASE("desktop viewer: playback of the 7-timepoint OME-TIFF shows the timepoints in order, then pauses") {
  const std::string dir = test::xr_out_dir("desktop_ui_play");
  const std::string vxc = dir + "/ts.vxc";
  // As `vxr play`'s tests: the container streams every timepoint (a plain file's session holds timepoint 0).
  const test::ChildResult import = test::run_child(std::string(VXR_BINARY) + " import " + std::string(VXR_TESTDATA_DIR) +
                                                   "/ome-tiff/multi-channel-time-series.ome.tif -o " + vxc);
  REQUIRE_MESSAGE(import.exit_code == 0, import.output);
  auto shot = [&](const std::string& name) { return dir + "/" + name + ".png"; };
  nlohmann::json steps = nlohmann::json::array({"wait 2", "ui off"});
  // What each timepoint looks like, paused.
  for (int t = 0; t < 7; ++t)
    for (const std::string& s : {"time " + std::to_string(t), std::string("wait 3"), "screenshot " + shot("ref" + std::to_string(t))})
      steps.push_back(s);
  steps.push_back("time 0");
  steps.push_back("wait 2");
  steps.push_back("speed 0.5");  // 5 timepoints/s: a few frames each on lavapipe, so most are seen
  steps.push_back("play");
  // Four frames apart, so that even a loaded machine's loader threads get the next timepoints in (two
  // once showed timepoint 0 throughout, with another test on the second core); playback does not loop
  // by default, so a longer window ends at the last timepoint, never back at 0.
  constexpr int kPlayed = 14;
  for (int i = 0; i < kPlayed; ++i) {
    steps.push_back("screenshot " + shot("play" + std::to_string(i)));
    steps.push_back("wait 4");
  }
  for (const std::string& s : {std::string("pause"), "screenshot " + shot("paused0"), std::string("wait 3"),
                              "screenshot " + shot("paused1")})
    steps.push_back(s);
  const std::string script = dir + "/play.json";
  std::ofstream(script) << steps.dump(1);
  const test::ChildResult r = test::run_child(test::own_config(dir) + "VXR_LOG=info xvfb-run -a -s '-screen 0 1024x768x24' " +
                                              std::string(VXR_BINARY) + " view " + vxc + " --desktop --width " +
                                              std::to_string(kWidth) + " --height " + std::to_string(kHeight) +
                                              " --ui-script " + script);
  INFO(r.output);
  REQUIRE(r.exit_code == 0);
  // The next timepoints are queued in the frame loop's cache (the view draws all 3 channels, as vxr render
  // does by default), as volume/playback.h says.
  CHECK(r.output.find("viewer: playback prefetches level 0 of 3 channel(s)") != std::string::npos);

  // The timepoint each screenshot's frame drew, from the viewer's log.
  auto logged = [&](const std::string& name) {
    const std::string key = "viewer: screenshot " + shot(name) + " (timepoint ";
    const size_t at = r.output.find(key);
    REQUIRE_MESSAGE(at != std::string::npos, name);
    return uint32_t(std::stoul(r.output.substr(at + key.size())));
  };
  auto image = [&](const std::string& name) {
    auto png = read_png(shot(name));
    REQUIRE_MESSAGE(png.is_ok(), name);
    return std::move(png).value();
  };
  auto distance = [](const ImageRgba8& a, const ImageRgba8& b) {
    uint64_t d = 0;
    for (size_t i = 0; i < a.pixels.size(); ++i) d += uint64_t(std::abs(int(a.pixels[i]) - int(b.pixels[i])));
    return d;
  };
  std::vector<ImageRgba8> refs;
  for (uint32_t t = 0; t < 7; ++t) {
    CHECK(logged("ref" + std::to_string(t)) == t);
    refs.push_back(image("ref" + std::to_string(t)));
    if (t > 0) CHECK(distance(refs[t], refs[t - 1]) > 0);  // the timepoints look different
  }

  // Playing: never back, never twice the same picture out of turn, and it moves on.
  std::vector<uint32_t> shown;
  for (int i = 0; i < kPlayed; ++i) {
    const uint32_t t = logged("play" + std::to_string(i));
    shown.push_back(t);
    if (i > 0) CHECK(t >= shown[i - 1]);
    // The picture is that timepoint's: nearer its paused render than any other timepoint's.
    const ImageRgba8 img = image("play" + std::to_string(i));
    uint32_t nearest = 0;
    for (uint32_t k = 1; k < 7; ++k)
      if (distance(img, refs[k]) < distance(img, refs[nearest])) nearest = k;
    CHECK_MESSAGE(nearest == t, "frame " << i);
  }
  std::string order;
  for (uint32_t t : shown) order += std::to_string(t) + " ";
  MESSAGE("timepoints drawn while playing: " << order);
  CHECK(shown.front() == 0);
  CHECK(shown.back() > shown.front());
  // Paused: the same timepoint frame after frame.
  CHECK(logged("paused1") == logged("paused0"));
  CHECK(distance(image("paused0"), image("paused1")) == 0);
}

TEST_CASE("desktop viewer: the opacity curve, the cut plane, the clip box and flight change the picture as they should") {
  const std::string dir = test::xr_out_dir("desktop_ui_clip");
  auto shot = [&](const std::string& name) { return dir + "/" + name + ".png"; };
  const std::string script = dir + "/clip.json";
  std::ofstream(script) << nlohmann::json::array({
                               "wait 3", "ui off", "view 3", "wait 1",
                               "screenshot " + shot("base"),
                               "opacity 0 0:0,0.5:0,1:0.3",  // the lower half of the window transparent
                               "screenshot " + shot("faint"),
                               "opacity 0 ramp",
                               "screenshot " + shot("ramp"),
                               "cut x 0.5",  // keeps x >= half: the plane through the eye, seen edge-on
                               "screenshot " + shot("cut"),
                               "cut off",
                               "clip 0.3 0.3 0 0.7 0.7 1",  // a square column along the view
                               "screenshot " + shot("box"),
                               "clip off",
                               "fly 0.4 0 0",  // forward: the volume comes closer
                               "screenshot " + shot("flown"),
                           })
                               .dump(1);
  const test::ChildResult r = test::run_child(viewer_command(script, ""));
  INFO(r.output);
  REQUIRE(r.exit_code == 0);  // validation is on: any Vulkan message would exit 3
  std::map<std::string, ImageRgba8> img;
  for (const char* name : {"base", "faint", "ramp", "cut", "box", "flown"}) {
    auto png = read_png(shot(name));
    REQUIRE_MESSAGE(png.is_ok(), name);
    img[name] = std::move(png).value();
  }
  const Tint base = tint(img["base"], 0, kHeight);
  REQUIRE(base.pixels > kWidth * kHeight / 10);

  // A curve with less opacity everywhere draws a fainter picture; back to the ramp, the same one.
  const Tint faint = tint(img["faint"], 0, kHeight);
  MESSAGE("luminance: ramp " << base.luminance << ", faint curve " << faint.luminance);
  CHECK(faint.luminance < base.luminance * 0.8);
  CHECK(differing(img["base"], img["ramp"], 0, 0, kWidth, kHeight) == 0);

  // Looking along -z from the volume's centre line, the plane x = half passes through the eye: the
  // half of the window showing x < half goes dark, the other half is drawn exactly as before.
  const uint32_t half = kWidth / 2;
  auto lit_in = [](const ImageRgba8& im, uint32_t x0, uint32_t x1) {
    size_t n = 0;
    for (uint32_t y = 0; y < im.height; ++y)
      for (uint32_t x = x0; x < x1; ++x) n += std::max({im.at(x, y)[0], im.at(x, y)[1], im.at(x, y)[2]}) > 24;
    return n;
  };
  const size_t before_left = lit_in(img["base"], 0, half - 2), after_left = lit_in(img["cut"], 0, half - 2);
  const size_t changed_right = differing(img["base"], img["cut"], half + 2, 0, kWidth, kHeight);
  MESSAGE("cut: lit pixels left of the plane " << before_left << " -> " << after_left << ", right of it "
                                                << changed_right << " differ");
  CHECK(before_left > kWidth * kHeight / 20);
  CHECK(after_left < before_left / 20);
  CHECK(changed_right < kWidth * kHeight / 1000);

  // The box keeps a column about the view's centre line: the middle is as before, the rest of the head is gone.
  const size_t box_lit = tint(img["box"], 0, kHeight).pixels;
  MESSAGE("box: lit pixels " << base.pixels << " -> " << box_lit);
  CHECK(box_lit < base.pixels / 2);
  CHECK(box_lit > 0);
  CHECK(differing(img["base"], img["box"], half - 10, kHeight / 2 - 10, half + 10, kHeight / 2 + 10) == 0);

  // Flying forward brings the volume closer: it covers more of the window.
  const size_t flown_lit = tint(img["flown"], 0, kHeight).pixels;
  MESSAGE("fly: lit pixels " << base.pixels << " -> " << flown_lit);
  CHECK(flown_lit > base.pixels * 5 / 4);
}

// One window on the sample with a remembered view (ViewerSetup::view_memory, restore_view), run by
// the next case in a child of this test binary under xvfb-run (the test process has no display).
TEST_CASE("vxr render: a --settings file's clip cuts the picture as the window's does") {
  const std::string dir = test::xr_out_dir("render_clip");
  auto render = [&](const std::string& name, const std::string& clip_json) {
    // Every run through a settings file: one without "clip" is the reference (a file's defaults, not the flags').
    const std::string settings = dir + "/" + name + ".json";
    std::ofstream(settings) << (clip_json.empty() ? std::string("{}") : "{\"clip\": " + clip_json + "}");
    const test::ChildResult r = test::run_child(std::string(VXR_BINARY) + " render " + kMri + " -o " + dir + "/" +
                                                name + ".png --size 160x120 --settings " + settings);
    INFO(r.output);
    REQUIRE(r.exit_code == 0);
    auto png = read_png(dir + "/" + name + ".png");
    REQUIRE(png.is_ok());
    return std::move(png).value();
  };
  const ImageRgba8 plain = render("plain", "");
  const ImageRgba8 whole = render("whole", R"({"roi": {"lo": [0, 0, 0], "hi": [1, 1, 1]}})");
  const ImageRgba8 half = render("half", R"({"cut": {"normal": [1, 0, 0], "offset": -0.5}})");
  const ImageRgba8 none = render("none", R"({"cut": {"normal": [1, 0, 0], "offset": -1.5}})");
  const size_t lit = tint(plain, 0, plain.height).pixels, lit_half = tint(half, 0, half.height).pixels;
  MESSAGE("lit pixels: whole volume " << lit << ", x >= half kept " << lit_half);
  CHECK(differing(plain, whole, 0, 0, plain.width, plain.height) == 0);  // a box around everything clips nothing
  CHECK(lit_half < lit * 3 / 4);
  CHECK(lit_half > lit / 4);
  CHECK(tint(none, 0, none.height, 0).pixels == 0);  // the plane keeps x >= 1.5 of the volume: nothing
}

TEST_CASE("desktop viewer memory: one window run (the Xvfb half of the next case)" * doctest::skip()) {
  const char* memory = std::getenv("VXR_VIEW_MEMORY");
  const char* script = std::getenv("VXR_VIEW_MEMORY_SCRIPT");
  REQUIRE((memory && script));
  auto volume = assets::sample_volume();
  REQUIRE(volume.is_ok());
  const VolumePlacement placement{volume->dims, volume->voxel_size};
  std::vector<DenseVolume> channels{*volume};
  auto source = DenseChunkSource::create(std::move(channels));
  REQUIRE(source.is_ok());
  auto setup = std::make_shared<xr::ViewerSetup>();
  setup->dataset = "sample";
  setup->scene.volume = "sample";
  setup->scene.render = default_view_settings();
  setup->placement = placement;
  setup->transform = xr::default_volume_transform(placement);
  setup->view_memory = memory;
  setup->restore_view = true;
  auto ui = xr::load_ui_script(script, xr::ViewerState(setup->scene, 1, setup->data_range), {}, false);
  REQUIRE(ui.is_ok());
  setup->script = std::move(ui).value();
  xr::DesktopOptions o;
  o.width = 256;
  o.height = 192;
  o.viewer = setup;
  xr::ViewOptions vo;
  vo.settings = setup->scene.render;
  auto window = [&]() -> Result<std::unique_ptr<xr::FrameTarget>> {
    auto t = xr::DesktopTarget::create(o);
    if (!t) return t.status();
    return std::unique_ptr<xr::FrameTarget>(std::move(t).value());
  };
  auto stats = xr::run_view(window, *source, vo, setup->transform);
  REQUIRE_MESSAGE(stats.is_ok(), stats.status().message());
}

TEST_CASE("desktop viewer: the next window on the same dataset starts where the last one closed") {
  const std::string dir = test::xr_out_dir("desktop_ui_memory");
  const std::string memory = dir + "/views/sample.json";
  std::filesystem::remove_all(dir + "/views");
  const std::string self = std::filesystem::read_symlink("/proc/self/exe").string();
  auto run = [&](const std::string& name, const nlohmann::json& steps) {
    const std::string script = dir + "/" + name + ".json";
    std::ofstream(script) << steps.dump(1);
    return test::run_child("VXR_VIEW_MEMORY=" + memory + " VXR_VIEW_MEMORY_SCRIPT=" + script +
                           " xvfb-run -a -s '-screen 0 1024x768x24' " + self +
                           " --no-skip -tc='desktop viewer memory: one window run*'");
  };
  auto shot = [&](const std::string& name) { return dir + "/" + name + ".png"; };
  // First run: a changed view, its picture.
  const test::ChildResult first = run("first", nlohmann::json::array({"wait 2", "ui off", "colormap 0 viridis", "orbit 60 20",
                                                                       "zoom 2", "cut z 0.4", "opacity 0 0:0,1:0.5", "wait 1",
                                                                       "screenshot " + shot("first")}));
  INFO(first.output);
  REQUIRE(first.exit_code == 0);
  std::ifstream in(memory);
  REQUIRE(in.good());
  const std::string text((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  auto scene = scene_from_json(text);
  REQUIRE(scene.is_ok());
  CHECK(scene->volume == "sample");
  CHECK(scene->has_camera);
  CHECK(scene->render.channels.front().colormap == "viridis");
  CHECK(scene->render.channels.front().opacity_points.size() == 2);
  CHECK(scene->render.clip.cut);

  // Second run, no edits: the same picture.
  const test::ChildResult second = run("second", nlohmann::json::array({"wait 3", "ui off", "screenshot " + shot("second")}));
  INFO(second.output);
  REQUIRE(second.exit_code == 0);
  auto a = read_png(shot("first"));
  auto b = read_png(shot("second"));
  REQUIRE(a.is_ok());
  REQUIRE(b.is_ok());
  const size_t moved = differing(*a, *b, 0, 0, a->width, a->height);
  MESSAGE("pixels differing between the first run's last picture and the second's first: " << moved);
  CHECK(moved < a->width * a->height / 1000);  // the orbit comes back from the saved camera to rounding

  // A corrupt memory: one warning naming it, and the default view.
  std::ofstream(memory) << "{\"render\": 7";
  const test::ChildResult third = run("third", nlohmann::json::array({"wait 3", "ui off", "screenshot " + shot("third")}));
  INFO(third.output);
  REQUIRE(third.exit_code == 0);
  CHECK(third.output.find("viewer: " + memory + ": not a remembered view") != std::string::npos);
  auto c = read_png(shot("third"));
  REQUIRE(c.is_ok());
  CHECK(differing(*a, *c, 0, 0, a->width, a->height) > a->width * a->height / 10);
  // ... and closing wrote a good one over it.
  std::ifstream again(memory);
  const std::string rewritten((std::istreambuf_iterator<char>(again)), std::istreambuf_iterator<char>());
  CHECK(scene_from_json(rewritten).is_ok());
}

TEST_CASE("desktop viewer: a bad UI script is one line naming the file and the step") {
  const std::string dir = test::xr_out_dir("desktop_ui_bad");
  struct Case {
    nlohmann::json steps;
    std::string expect;
  };
  const Case cases[] = {
      {nlohmann::json::array({"wait 1", "colormap 0 no-such-map"}), "step 2 ('colormap 0 no-such-map'): "},
      {nlohmann::json::array({"count 1 2 3"}), "step 1 ('count 1 2 3'): needs an annotation store"},
      {nlohmann::json::array({"wait 1", "tool paint"}), "step 2 ('tool paint'): usage: tool navigate|count"},
      {nlohmann::json::array({"click 5"}), "step 1 ('click 5'): usage: click X Y"},
      {nlohmann::json::array({"restore-card 0"}), "step 1 ('restore-card 0'): usage: restore-card ID"},
      {nlohmann::json::array({"drag 1 2 3"}), "step 1 ('drag 1 2 3'): usage: drag X Y X2 Y2"},
      {nlohmann::json::array({"finish"}), "step 1 ('finish'): needs an annotation store"},
      {nlohmann::json::array({"remove cell 3"}), "step 1 ('remove cell 3'): usage: remove marker|measurement|"},
      {nlohmann::json::array({"keyframe", "export-movie " + dir + "/m 5"}),
       "step 2 ('export-movie " + dir + "/m 5'): needs 2 keyframe steps before it (1 so far)"},
      {nlohmann::json::array({"keyframe", "keyframe", "export-movie " + kMri + " 5"}), "step 3 ('export-movie "},
      {nlohmann::json::array({"keyframe", "keyframe", "export-movie " + dir + "/m 1"}),
       "step 3 ('export-movie " + dir + "/m 1'): usage: export-movie OUT FRAMES"},
      {nlohmann::json::array({"wait 1", "play"}), "step 2 ('play'): one timepoint: nothing to play"},
      {nlohmann::json::array({"wait 1", "window 0 50 10"}), "step 2 ('window 0 50 10'): "},
      {nlohmann::json::array({"opacity 0 0.5:0,0.2:1"}), "step 1 ('opacity 0 0.5:0,0.2:1'): opacity points need x rising"},
      {nlohmann::json::array({"cut w 0.5"}), "step 1 ('cut w 0.5'): usage: cut off|on"},
      {nlohmann::json::array({"clip 0.5 0 0 0.4 1 1"}), "step 1 ('clip 0.5 0 0 0.4 1 1'): the clip box needs"},
      {nlohmann::json::array({"screenshot " + kMri}), "step 1 ('screenshot "},
      {nlohmann::json::array({"wait 1", 7}), "step 2: expected a string"},
      {nlohmann::json::object({{"no", "steps"}}), "expected a list of steps"},
  };
  int index = 0;
  for (const Case& c : cases) {
    const std::string script = dir + "/bad" + std::to_string(index++) + ".json";
    std::ofstream(script) << c.steps.dump();
    // Checked before any window opens: no Xvfb needed.
    const test::ChildResult r = test::run_child(std::string(VXR_BINARY) + " view " + kMri +
                                                " --desktop --ui-script " + script);
    INFO(r.output);
    CHECK(r.exit_code == 2);
    CHECK(r.output.find(script + ": " + (c.expect.rfind("step", 0) == 0 ? c.expect : "")) != std::string::npos);
    CHECK(r.output.find(c.expect) != std::string::npos);
    CHECK(std::count(r.output.begin(), r.output.end(), '\n') == 1);
  }
}

TEST_CASE("desktop viewer: vxr view reopens a dataset at its last view unless a look flag is given") {
  const std::string dir = test::xr_out_dir("desktop_ui_remembered");
  std::filesystem::remove_all(dir + "/config");  // a rerun starts with no memory
  const std::string first = dir + "/first.json", second = dir + "/second.json", third = dir + "/third.json";
  std::ofstream(first) << nlohmann::json::array(
      {"ui off", "wait 2", "colormap 0 viridis", "orbit 40 0", "wait 2", "screenshot " + dir + "/last.png"});
  std::ofstream(second) << nlohmann::json::array({"ui off", "wait 2", "screenshot " + dir + "/reopened.png"});
  std::ofstream(third) << nlohmann::json::array({"ui off", "wait 2", "screenshot " + dir + "/flagged.png"});
  for (const auto& [script, extra] : {std::pair{first, ""}, std::pair{second, ""}, std::pair{third, "--colormap hot"}}) {
    const test::ChildResult r = test::run_child(viewer_command(script, extra));
    INFO(r.output);
    REQUIRE(r.exit_code == 0);
  }
  auto last = read_png(dir + "/last.png");
  auto reopened = read_png(dir + "/reopened.png");
  auto flagged = read_png(dir + "/flagged.png");
  REQUIRE(last.is_ok());
  REQUIRE(reopened.is_ok());
  REQUIRE(flagged.is_ok());
  CHECK(reopened->pixels == last->pixels);  // colour map and camera came back
  CHECK(flagged->pixels != last->pixels);   // --colormap: the flags' look, not the memory
}

TEST_CASE("desktop viewer: the Open step closes the window and the viewer opens the new input") {
  const std::string dir = test::xr_out_dir("desktop_ui_open");
  const std::string script = dir + "/open.json";
  const std::string other = std::string(VXR_TESTDATA_DIR) + "/tiff/mri-stack-calibrated.tif";  // the thresholded head
  std::ofstream(script) << nlohmann::json::array({"ui off", "wait 2", "screenshot " + dir + "/first.png", "open " + other});
  // The second window has no script: --frames ends it, --screenshot keeps its last frame.
  const test::ChildResult r = test::run_child(viewer_command(script, "--frames 6 --screenshot " + dir + "/opened.png"));
  INFO(r.output);
  REQUIRE(r.exit_code == 0);
  CHECK(r.output.find("opening " + other) != std::string::npos);
  auto first = read_png(dir + "/first.png");
  auto opened = read_png(dir + "/opened.png");
  REQUIRE(first.is_ok());
  REQUIRE(opened.is_ok());
  CHECK(opened->width == first->width);  // the window's own choices carry over
  CHECK(differing(*first, *opened, 0, 0, first->width, first->height) > first->width * first->height / 20);
  CHECK(tint(*opened, 0, opened->height).pixels > 0);  // the new volume is drawn

  // A step that is not last, or a missing input, is refused before any window opens.
  for (const auto& [steps, why] : {std::pair{nlohmann::json::array({"open " + other, "wait 2"}), "the last step"},
                                   std::pair{nlohmann::json::array({"open " + dir + "/nothing.tif"}), "does not exist"}}) {
    std::ofstream(script) << steps.dump();
    const test::ChildResult bad = test::run_child(viewer_command(script, ""));
    INFO(bad.output);
    CHECK(bad.exit_code == 2);
    CHECK(bad.output.find(why) != std::string::npos);
  }
}

TEST_CASE("desktop viewer: the window follows a resize and the next viewer opens at that size") {
  const std::string dir = test::xr_out_dir("desktop_ui_resize");
  const std::string config = dir + "/config";  // XDG_CONFIG_HOME of both runs: the user's own is left alone
  const std::string first = dir + "/first.json", second = dir + "/second.json";
  std::ofstream(first) << nlohmann::json::array({"wait 2", "resize 400 300", "wait 2", "screenshot " + dir + "/resized.png"});
  std::ofstream(second) << nlohmann::json::array({"wait 2", "screenshot " + dir + "/reopened.png"});
  const test::ChildResult a = test::run_child("XDG_CONFIG_HOME=" + config + " " + viewer_command(first, ""));
  INFO(a.output);
  REQUIRE(a.exit_code == 0);
  auto resized = read_png(dir + "/resized.png");
  REQUIRE(resized.is_ok());
  CHECK(resized->width == 400);
  CHECK(resized->height == 300);
  CHECK(tint(*resized, 0, 300).pixels > 400 * 300 / 20);  // the volume drawn at the new size, not a stale image

  // Without --width/--height the viewer opens at the size the user left.
  const std::string reopen = "XDG_CONFIG_HOME=" + config + " xvfb-run -a -s '-screen 0 1024x768x24' " +
                             std::string(VXR_BINARY) + " view " + kMri + " --desktop --ui-script " + second;
  const test::ChildResult b = test::run_child(reopen);
  INFO(b.output);
  REQUIRE(b.exit_code == 0);
  auto reopened = read_png(dir + "/reopened.png");
  REQUIRE(reopened.is_ok());
  CHECK(reopened->width == 400);
  CHECK(reopened->height == 300);
}

TEST_CASE("desktop viewer: the panel histogram counts every interior voxel once") {
  // 70 x 40 x 9 u16 in chunks of 32 (edge chunks at level 0): voxel value x * 900, bins 1000 wide.
  DenseVolume v;
  v.dims = {70, 40, 9};
  v.dtype = DType::kU16;
  v.data.resize(v.byte_size());
  auto* voxels = reinterpret_cast<uint16_t*>(v.data.data());
  for (uint32_t z = 0; z < 9; ++z)
    for (uint32_t y = 0; y < 40; ++y)
      for (uint32_t x = 0; x < 70; ++x) voxels[(size_t(z) * 40 + y) * 70 + x] = uint16_t(x * 900);
  std::vector<DenseVolume> channels{v};
  auto source = DenseChunkSource::create(std::move(channels), 32, 2);
  REQUIRE(source.is_ok());
  // Level 0 has 3 x 2 x 1 chunks: allowed as it is.
  auto h = xr::coarse_histogram(**source, 0, 0, {0.0, 70000.0}, 70, 6);
  REQUIRE(h.is_ok());
  REQUIRE(h->size() == 70);
  double total = 0;
  for (size_t b = 0; b < 70; ++b) {
    const double count = std::round(std::expm1(double((*h)[b])));  // stored as float log1p
    total += count;
    // Column x falls in bin floor(x * 900 / 1000): each filled bin holds one or two whole columns.
    if (count > 0) CHECK(std::fmod(count, 40.0 * 9.0) == 0.0);
  }
  CHECK(total == doctest::Approx(70.0 * 40 * 9).epsilon(1e-5));
  // A chunk budget of 1: the coarsest level that fits, 35 x 20 x 5 voxels (halved along x and y, maybe z).
  auto coarse = xr::coarse_histogram(**source, 0, 0, {0.0, 70000.0}, 70, 1);
  REQUIRE(coarse.is_ok());
  double coarse_total = 0;
  for (float c : *coarse) coarse_total += std::round(std::expm1(double(c)));
  const LevelInfo* fit = nullptr;
  for (const LevelInfo& l : (*source)->levels())
    if (!fit && uint64_t(l.chunk_counts[0]) * l.chunk_counts[1] * l.chunk_counts[2] <= 1) fit = &l;
  REQUIRE(fit != nullptr);
  CHECK(coarse_total == doctest::Approx(double(fit->dims[0] * fit->dims[1] * fit->dims[2])).epsilon(1e-5));
  CHECK_FALSE(xr::coarse_histogram(**source, 0, 0, {5.0, 5.0}).is_ok());
}

TEST_CASE("vxr bench desktop: the window's frame times while a volume streams in, split at full detail") {
  const std::string dir = test::xr_out_dir("bench_desktop");
  const test::ChildResult r = test::run_child("xvfb-run -a -s '-screen 0 1024x768x24' " + std::string(VXR_BINARY) +
                                              " bench desktop procedural:vessels:4096 --frames 12 --width 160 "
                                              "--height 120 --out " + dir);
  INFO(r.output);
  REQUIRE(r.exit_code == 0);
  std::ifstream in(dir + "/desktop.json");
  const nlohmann::json doc = nlohmann::json::parse(in);
  CHECK(doc["frames"].get<uint64_t>() == 12);
  CHECK(doc["bricks_uploaded"].get<uint64_t>() > 0);
  CHECK(doc["target"].get<std::string>().find("desktop window 160x120") != std::string::npos);
  // A cold cache: the first frames draw ancestors while bricks stream in, then full detail.
  REQUIRE(doc["full_detail_at_frame"].is_number());
  const uint64_t full = doc["full_detail_at_frame"].get<uint64_t>();
  CHECK(doc["first_frame_missing_bricks"].get<uint64_t>() > 0);
  CHECK(doc["streaming"]["frames"].get<uint64_t>() == full - 1);
  CHECK(doc["settled"]["frames"].get<uint64_t>() == 12 - full);
  CHECK(doc["settled"]["interval_ms"]["p50"].get<double>() > 0.0);
}
