#include <doctest/doctest.h>

#include <cmath>

#include "bench/plot.h"

using namespace vxr;

namespace {
bool has_colour_near(const ImageRgba8& img, int cx, int cy, int r, std::array<uint8_t, 3> c) {
  for (int y = cy - r; y <= cy + r; ++y)
    for (int x = cx - r; x <= cx + r; ++x) {
      if (x < 0 || y < 0 || x >= int(img.width) || y >= int(img.height)) continue;
      const uint8_t* p = img.at(x, y);
      if (p[0] == c[0] && p[1] == c[1] && p[2] == c[2]) return true;
    }
  return false;
}

constexpr std::array<uint8_t, 3> kRed{200, 0, 0};

bench::PlotSeries red_points(std::string label, std::vector<double> x, std::vector<double> y) {
  bench::PlotSeries a;
  a.label = std::move(label);
  a.x = std::move(x);
  a.y = std::move(y);
  a.color = kRed;
  return a;
}
}  // namespace

TEST_CASE("bench plot: points land where their coordinates say, on linear and log axes") {
  // Designated, not assigned member by member: GCC 12 warns falsely (-Wmaybe-uninitialized) on that.
  bench::PlotSpec spec{.title = "time vs error", .x_label = "ms", .y_label = "rmse", .log_y = true, .width = 400,
                       .height = 300};
  spec.series.push_back(red_points("all", {1, 2, 3}, {1, 10, 100}));
  const ImageRgba8 img = bench::render_plot(spec);
  REQUIRE(img.width == 400);
  // Axes: x from 80 to 380 with 5% padding; y from 240 (bottom) to 40 (top), log.
  // x=2 is the middle of the x range, y=10 the middle of the log range.
  const int mid_x = 80 + (380 - 80) / 2, mid_y = 240 - (240 - 40) / 2;
  CHECK(has_colour_near(img, mid_x, mid_y, 2, kRed));
  // Nothing red far from the three points (e.g. lower-right corner of the plot area).
  CHECK_FALSE(has_colour_near(img, 370, 230, 3, kRed));
  // Non-finite and non-positive (log) values are skipped, not drawn at NaN.
  spec.series[0].y = {std::nan(""), -1, 100};
  const ImageRgba8 img2 = bench::render_plot(spec);
  CHECK(img2.width == 400);
}

TEST_CASE("bench plot: y_from_zero puts 0 on a linear y axis, so heights read from the floor") {
  bench::PlotSpec spec{.title = "shares", .x_label = "scene", .y_label = "share", .width = 400, .height = 300};
  spec.series.push_back(red_points("share", {1, 3}, {5, 10}));
  // Plot area as above: x 80..380, y 240 (bottom) .. 40 (top); each axis padded by 5% of its span.
  // From its data alone the y axis spans 4.75..10.25: y = 5 sits near the bottom.
  CHECK(has_colour_near(bench::render_plot(spec), 95, 231, 2, kRed));
  // From zero it spans -0.5..10.5: y = 5 is at 240 - 5.5 / 11 * 200 = 140.
  spec.y_from_zero = true;
  const ImageRgba8 img = bench::render_plot(spec);
  CHECK(has_colour_near(img, 95, 140, 2, kRed));
  CHECK_FALSE(has_colour_near(img, 95, 231, 3, kRed));
}

TEST_CASE("bench plot: the legend takes the corner with the least data under it, on a box no line crosses") {
  // Plot area as above: x 80..380, y 240 (bottom) .. 40 (top); both axes span -0.5..10.5.
  bench::PlotSpec spec{.title = "legend", .x_label = "x", .y_label = "y", .width = 400, .height = 300};
  spec.series.push_back(red_points("points", {0, 9, 10}, {0, 9, 10}));
  // The legend box is 60 x 17 px, 8 px inside a corner: top left x 88..147, y 48..64;
  // top right x 312..371. The points (9, 9) and (10, 10) lie at the top right.
  const std::array<uint8_t, 3> black{0, 0, 0};
  const ImageRgba8 img = bench::render_plot(spec);
  CHECK(has_colour_near(img, 120, 56, 8, black));
  CHECK_FALSE(has_colour_near(img, 340, 56, 8, black));
  CHECK(has_colour_near(img, 366, 49, 2, kRed));  // the point the old top-right legend would have covered

  // A line along the top and the bottom runs under every corner: the legend
  // (top left, the first of the corners with the fewest pixels) is drawn over it.
  spec.series[0].line = true;
  spec.series[0].markers = false;
  spec.series[0].x = {0, 10, 10, 0};
  spec.series[0].y = {10, 10, 0, 0};
  const ImageRgba8 crossed = bench::render_plot(spec);
  CHECK(has_colour_near(crossed, 200, 49, 1, kRed));  // the top line, right of the legend
  CHECK_FALSE(has_colour_near(crossed, 125, 49, 1, kRed));  // under the legend's box
  CHECK(has_colour_near(crossed, 125, 56, 8, black));  // the label
}
