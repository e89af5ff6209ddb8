// Small scatter/line plots as PNG for benchmark reports (time vs error,
// scaling curves). No dependencies beyond core/image: a 5x7 bitmap font,
// linear or log10 axes, labelled ticks, a legend in the corner with the least data.
#pragma once

#include <array>
#include <string>
#include <vector>

#include "core/image.h"

namespace vxr::bench {

struct PlotSeries {
  std::string label;
  std::vector<double> x, y;
  std::array<uint8_t, 3> color{31, 119, 180};
  bool line = false;     // connect points in the order given
  bool markers = true;
  int marker_radius = 3;
};

struct PlotSpec {
  std::string title;
  std::string x_label, y_label;
  bool log_x = false, log_y = false;
  bool y_from_zero = false;  // a linear y axis reaches 0 (shares, counts: heights read from the floor)
  uint32_t width = 800, height = 560;
  std::vector<PlotSeries> series;
};

// Points with non-finite coordinates (or <= 0 on a log axis) are skipped.
ImageRgba8 render_plot(const PlotSpec& spec);

// The reports' series colours, in turn (six, then again), and a colour
// halfway to white: the same series' second kind (skipping off, a probe).
std::array<uint8_t, 3> series_colour(size_t i);
std::array<uint8_t, 3> lighter(std::array<uint8_t, 3> c);

}  // namespace vxr::bench
