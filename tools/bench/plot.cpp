#include "plot.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstring>

namespace vxr::bench {
namespace {

// 5x7 glyphs, one byte per row, low 5 bits, MSB of those = leftmost pixel.
struct Glyph {
  char c;
  uint8_t rows[7];
};
constexpr Glyph kFont[] = {
    {'0', {0x0E, 0x11, 0x13, 0x15, 0x19, 0x11, 0x0E}}, {'1', {0x04, 0x0C, 0x04, 0x04, 0x04, 0x04, 0x0E}},
    {'2', {0x0E, 0x11, 0x01, 0x02, 0x04, 0x08, 0x1F}}, {'3', {0x1F, 0x02, 0x04, 0x02, 0x01, 0x11, 0x0E}},
    {'4', {0x02, 0x06, 0x0A, 0x12, 0x1F, 0x02, 0x02}}, {'5', {0x1F, 0x10, 0x1E, 0x01, 0x01, 0x11, 0x0E}},
    {'6', {0x06, 0x08, 0x10, 0x1E, 0x11, 0x11, 0x0E}}, {'7', {0x1F, 0x01, 0x02, 0x04, 0x08, 0x08, 0x08}},
    {'8', {0x0E, 0x11, 0x11, 0x0E, 0x11, 0x11, 0x0E}}, {'9', {0x0E, 0x11, 0x11, 0x0F, 0x01, 0x02, 0x0C}},
    {'A', {0x0E, 0x11, 0x11, 0x1F, 0x11, 0x11, 0x11}}, {'B', {0x1E, 0x11, 0x11, 0x1E, 0x11, 0x11, 0x1E}},
    {'C', {0x0E, 0x11, 0x10, 0x10, 0x10, 0x11, 0x0E}}, {'D', {0x1C, 0x12, 0x11, 0x11, 0x11, 0x12, 0x1C}},
    {'E', {0x1F, 0x10, 0x10, 0x1E, 0x10, 0x10, 0x1F}}, {'F', {0x1F, 0x10, 0x10, 0x1E, 0x10, 0x10, 0x10}},
    {'G', {0x0E, 0x11, 0x10, 0x17, 0x11, 0x11, 0x0F}}, {'H', {0x11, 0x11, 0x11, 0x1F, 0x11, 0x11, 0x11}},
    {'I', {0x0E, 0x04, 0x04, 0x04, 0x04, 0x04, 0x0E}}, {'J', {0x07, 0x02, 0x02, 0x02, 0x02, 0x12, 0x0C}},
    {'K', {0x11, 0x12, 0x14, 0x18, 0x14, 0x12, 0x11}}, {'L', {0x10, 0x10, 0x10, 0x10, 0x10, 0x10, 0x1F}},
    {'M', {0x11, 0x1B, 0x15, 0x15, 0x11, 0x11, 0x11}}, {'N', {0x11, 0x11, 0x19, 0x15, 0x13, 0x11, 0x11}},
    {'O', {0x0E, 0x11, 0x11, 0x11, 0x11, 0x11, 0x0E}}, {'P', {0x1E, 0x11, 0x11, 0x1E, 0x10, 0x10, 0x10}},
    {'Q', {0x0E, 0x11, 0x11, 0x11, 0x15, 0x12, 0x0D}}, {'R', {0x1E, 0x11, 0x11, 0x1E, 0x14, 0x12, 0x11}},
    {'S', {0x0F, 0x10, 0x10, 0x0E, 0x01, 0x01, 0x1E}}, {'T', {0x1F, 0x04, 0x04, 0x04, 0x04, 0x04, 0x04}},
    {'U', {0x11, 0x11, 0x11, 0x11, 0x11, 0x11, 0x0E}}, {'V', {0x11, 0x11, 0x11, 0x11, 0x11, 0x0A, 0x04}},
    {'W', {0x11, 0x11, 0x11, 0x15, 0x15, 0x15, 0x0A}}, {'X', {0x11, 0x11, 0x0A, 0x04, 0x0A, 0x11, 0x11}},
    {'Y', {0x11, 0x11, 0x11, 0x0A, 0x04, 0x04, 0x04}}, {'Z', {0x1F, 0x01, 0x02, 0x04, 0x08, 0x10, 0x1F}},
    {'.', {0x00, 0x00, 0x00, 0x00, 0x00, 0x0C, 0x0C}}, {',', {0x00, 0x00, 0x00, 0x00, 0x0C, 0x04, 0x08}},
    {'-', {0x00, 0x00, 0x00, 0x1F, 0x00, 0x00, 0x00}}, {'+', {0x00, 0x04, 0x04, 0x1F, 0x04, 0x04, 0x00}},
    {'/', {0x00, 0x01, 0x02, 0x04, 0x08, 0x10, 0x00}}, {'(', {0x02, 0x04, 0x08, 0x08, 0x08, 0x04, 0x02}},
    {')', {0x08, 0x04, 0x02, 0x02, 0x02, 0x04, 0x08}}, {':', {0x00, 0x0C, 0x0C, 0x00, 0x0C, 0x0C, 0x00}},
    {'%', {0x18, 0x19, 0x02, 0x04, 0x08, 0x13, 0x03}}, {'=', {0x00, 0x00, 0x1F, 0x00, 0x1F, 0x00, 0x00}},
    {'_', {0x00, 0x00, 0x00, 0x00, 0x00, 0x00, 0x1F}}, {'^', {0x04, 0x0A, 0x11, 0x00, 0x00, 0x00, 0x00}},
    {'<', {0x02, 0x04, 0x08, 0x10, 0x08, 0x04, 0x02}}, {'>', {0x08, 0x04, 0x02, 0x01, 0x02, 0x04, 0x08}},
    {'*', {0x00, 0x04, 0x15, 0x0E, 0x15, 0x04, 0x00}}, {'#', {0x0A, 0x0A, 0x1F, 0x0A, 0x1F, 0x0A, 0x0A}},
    {'[', {0x0E, 0x08, 0x08, 0x08, 0x08, 0x08, 0x0E}}, {']', {0x0E, 0x02, 0x02, 0x02, 0x02, 0x02, 0x0E}},
};

const Glyph* find_glyph(char c) {
  c = static_cast<char>(std::toupper(static_cast<unsigned char>(c)));
  for (const Glyph& g : kFont)
    if (g.c == c) return &g;
  return nullptr;  // space and unknown characters draw nothing
}

struct Canvas {
  ImageRgba8& img;
  void pixel(int x, int y, std::array<uint8_t, 3> c) {
    if (x < 0 || y < 0 || x >= int(img.width) || y >= int(img.height)) return;
    uint8_t* p = img.at(x, y);
    p[0] = c[0], p[1] = c[1], p[2] = c[2], p[3] = 255;
  }
  void line(double x0, double y0, double x1, double y1, std::array<uint8_t, 3> c) {
    const int n = static_cast<int>(std::max(std::abs(x1 - x0), std::abs(y1 - y0))) + 1;
    for (int i = 0; i <= n; ++i) {
      const double t = double(i) / n;
      pixel(int(std::lround(x0 + t * (x1 - x0))), int(std::lround(y0 + t * (y1 - y0))), c);
    }
  }
  void disc(int cx, int cy, int r, std::array<uint8_t, 3> c) {
    for (int y = -r; y <= r; ++y)
      for (int x = -r; x <= r; ++x)
        if (x * x + y * y <= r * r) pixel(cx + x, cy + y, c);
  }
  // Text with its top-left at (x, y); scale 1 = 6 px per character.
  void text(int x, int y, const std::string& s, std::array<uint8_t, 3> c, int scale = 1, bool vertical = false) {
    for (size_t i = 0; i < s.size(); ++i) {
      const Glyph* g = find_glyph(s[i]);
      if (!g) continue;
      for (int r = 0; r < 7; ++r)
        for (int col = 0; col < 5; ++col)
          if (g->rows[r] & (0x10 >> col))
            for (int sy = 0; sy < scale; ++sy)
              for (int sx = 0; sx < scale; ++sx) {
                const int gx = int(i) * 6 * scale + col * scale + sx, gy = r * scale + sy;
                if (vertical)
                  pixel(x + gy, y - gx, c);  // reads bottom to top
                else
                  pixel(x + gx, y + gy, c);
              }
    }
  }
};

int text_width(const std::string& s, int scale = 1) { return int(s.size()) * 6 * scale; }

std::string tick_label(double v) {
  char buf[32];
  const double a = std::abs(v);
  if (v == 0.0)
    std::snprintf(buf, sizeof buf, "0");
  else if (a >= 1e4 || a < 1e-3)
    std::snprintf(buf, sizeof buf, "%.0e", v);
  else
    std::snprintf(buf, sizeof buf, "%.3g", v);
  return buf;
}

struct Axis {
  bool log = false;
  double lo = 0, hi = 1;
  double map(double v) const { return log ? std::log10(v) : v; }
  void fit(const std::vector<double>& values) {
    double mn = INFINITY, mx = -INFINITY;
    for (double v : values) {
      if (!std::isfinite(v) || (log && v <= 0)) continue;
      mn = std::min(mn, map(v));
      mx = std::max(mx, map(v));
    }
    if (!std::isfinite(mn)) mn = 0, mx = 1;
    if (mx - mn < 1e-12) mn -= 0.5, mx += 0.5;
    const double pad = 0.05 * (mx - mn);
    lo = mn - pad, hi = mx + pad;
  }
  // Tick positions in mapped units.
  std::vector<double> ticks() const {
    std::vector<double> t;
    if (log) {
      for (double e = std::ceil(lo); e <= hi; e += 1.0) t.push_back(e);
      if (t.size() >= 2) return t;
      // Less than two decades: 1-2-5 ticks.
      t.clear();
      for (double e = std::floor(lo); e <= hi; e += 1.0)
        for (double m : {1.0, 2.0, 5.0})
          if (const double v = e + std::log10(m); v >= lo && v <= hi) t.push_back(v);
      if (t.size() >= 2) return t;
      t.clear();
    }
    const double raw = (hi - lo) / 6.0;
    const double mag = std::pow(10.0, std::floor(std::log10(raw)));
    const double step = raw / mag < 2 ? 2 * mag : raw / mag < 5 ? 5 * mag : 10 * mag;
    t.clear();
    for (double v = std::ceil(lo / step) * step; v <= hi; v += step) t.push_back(v);
    return t;
  }
  std::string label(double mapped) const { return tick_label(log ? std::pow(10.0, mapped) : mapped); }
};

constexpr std::array<uint8_t, 3> kGrid{225, 225, 225};  // grid lines: background, not data, to the legend

// The legend, after the data: in the corner of the plot area where the
// fewest data pixels lie under it (top right first on a tie), on a white
// box so that no line runs through its labels.
void draw_legend(Canvas& cv, const std::vector<PlotSeries>& series, int left, int top, int right, int bottom) {
  constexpr int kRow = 14, kPad = 5, kMargin = 8;
  int rows = 0, widest = 0;
  for (const auto& s : series)
    if (!s.label.empty()) ++rows, widest = std::max(widest, text_width(s.label));
  if (rows == 0) return;
  const int w = 14 + widest + 2 * kPad, h = rows * kRow + 2 * kPad - 7;
  const std::array<uint8_t, 3> white{255, 255, 255}, frame{160, 160, 160};
  auto data_pixels = [&](int x0, int y0) {
    int n = 0;
    for (int y = y0; y < y0 + h; ++y)
      for (int x = x0; x < x0 + w; ++x) {
        const uint8_t* p = cv.img.at(x, y);
        const bool background = (p[0] == 255 && p[1] == 255 && p[2] == 255) ||
                                (p[0] == kGrid[0] && p[1] == kGrid[1] && p[2] == kGrid[2]);
        n += background ? 0 : 1;
      }
    return n;
  };
  const int xs[2] = {right - kMargin - w, left + kMargin}, ys[2] = {top + kMargin, bottom - kMargin - h};
  int bx = xs[0], by = ys[0], fewest = -1;
  if (xs[1] >= xs[0] || ys[1] <= ys[0]) {  // a plot too small for corners: top right
    bx = std::max(xs[0], 0), by = ys[0];
  } else {
    for (int y0 : ys)
      for (int x0 : xs)
        if (const int n = data_pixels(x0, y0); fewest < 0 || n < fewest) fewest = n, bx = x0, by = y0;
  }
  for (int y = by; y < by + h; ++y)
    for (int x = bx; x < bx + w; ++x) cv.pixel(x, y, white);
  cv.line(bx, by, bx + w - 1, by, frame);
  cv.line(bx, by + h - 1, bx + w - 1, by + h - 1, frame);
  cv.line(bx, by, bx, by + h - 1, frame);
  cv.line(bx + w - 1, by, bx + w - 1, by + h - 1, frame);
  int y = by + kPad;
  for (const auto& s : series) {
    if (s.label.empty()) continue;
    cv.disc(bx + kPad + 4, y + 3, 3, s.color);
    cv.text(bx + kPad + 14, y, s.label, {0, 0, 0});
    y += kRow;
  }
}

}  // namespace

std::array<uint8_t, 3> series_colour(size_t i) {
  static constexpr std::array<uint8_t, 3> kColours[] = {{31, 119, 180}, {214, 39, 40}, {44, 160, 44},
                                                        {148, 103, 189}, {255, 127, 14}, {140, 86, 75}};
  return kColours[i % std::size(kColours)];
}

std::array<uint8_t, 3> lighter(std::array<uint8_t, 3> c) {
  return {uint8_t((c[0] + 255) / 2), uint8_t((c[1] + 255) / 2), uint8_t((c[2] + 255) / 2)};
}

ImageRgba8 render_plot(const PlotSpec& spec) {
  ImageRgba8 img(spec.width, spec.height);
  std::fill(img.pixels.begin(), img.pixels.end(), 255);
  Canvas cv{img};
  const std::array<uint8_t, 3> black{0, 0, 0}, grid = kGrid, grey{90, 90, 90};
  const int left = 80, right = int(spec.width) - 20, top = 40, bottom = int(spec.height) - 60;

  Axis ax{spec.log_x}, ay{spec.log_y};
  std::vector<double> xs, ys;
  for (const auto& s : spec.series) {
    xs.insert(xs.end(), s.x.begin(), s.x.end());
    ys.insert(ys.end(), s.y.begin(), s.y.end());
  }
  if (spec.y_from_zero && !spec.log_y) ys.push_back(0.0);
  ax.fit(xs);
  ay.fit(ys);
  auto px = [&](double v) { return left + (ax.map(v) - ax.lo) / (ax.hi - ax.lo) * (right - left); };
  auto py = [&](double v) { return bottom - (ay.map(v) - ay.lo) / (ay.hi - ay.lo) * (bottom - top); };

  for (double t : ax.ticks()) {
    const double x = left + (t - ax.lo) / (ax.hi - ax.lo) * (right - left);
    cv.line(x, top, x, bottom, grid);
    const std::string l = ax.label(t);
    cv.text(int(x) - text_width(l) / 2, bottom + 8, l, grey);
  }
  for (double t : ay.ticks()) {
    const double y = bottom - (t - ay.lo) / (ay.hi - ay.lo) * (bottom - top);
    cv.line(left, y, right, y, grid);
    const std::string l = ay.label(t);
    cv.text(left - 6 - text_width(l), int(y) - 3, l, grey);
  }
  cv.line(left, bottom, right, bottom, black);
  cv.line(left, top, left, bottom, black);
  cv.text((left + right) / 2 - text_width(spec.title, 2) / 2, 10, spec.title, black, 2);
  const std::string xl = spec.x_label + (spec.log_x ? " (log)" : "");
  const std::string yl = spec.y_label + (spec.log_y ? " (log)" : "");
  cv.text((left + right) / 2 - text_width(xl) / 2, bottom + 30, xl, black);
  cv.text(12, (top + bottom) / 2 + text_width(yl) / 2, yl, black, 1, /*vertical=*/true);

  for (const auto& s : spec.series) {
    bool have_prev = false;
    double prev_x = 0, prev_y = 0;
    for (size_t i = 0; i < std::min(s.x.size(), s.y.size()); ++i) {
      const double x = s.x[i], y = s.y[i];
      if (!std::isfinite(x) || !std::isfinite(y) || (spec.log_x && x <= 0) || (spec.log_y && y <= 0)) continue;
      const double X = px(x), Y = py(y);
      if (s.line && have_prev) cv.line(prev_x, prev_y, X, Y, s.color);
      if (s.markers) cv.disc(int(std::lround(X)), int(std::lround(Y)), s.marker_radius, s.color);
      have_prev = true, prev_x = X, prev_y = Y;
    }
  }
  draw_legend(cv, spec.series, left, top, right, bottom);
  return img;
}

}  // namespace vxr::bench
