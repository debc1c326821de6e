// A small scatter plot rendered to PNG bytes, for `lightpatch accuracy`: log-log axes with
// labelled decades, one colour per series, a marked front of points joined by a line, and text
// labels beside chosen points. Text uses stb_easy_font (libstb-dev), a bitmap font made of
// rectangles; no font library is needed.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

namespace lightpatch::tool {

struct PlotPoint {
  double x = 0.0, y = 0.0;  // data units; points with x or y <= 0 or not finite are not drawn
  int series = 0;           // index into PlotSpec::series
  bool front = false;       // on the marked front (ringed, joined by a line in x order)
  std::string label;        // drawn beside the point when not empty
};

struct PlotSpec {
  std::string title;
  std::string x_label, y_label;
  std::vector<std::string> series;  // legend names; colours are picked in order
  std::string front_label = "Pareto front";
  std::vector<PlotPoint> points;
  int width = 1000, height = 640;  // pixels
};

// Renders the plot (RGB) and encodes it as PNG. Throws std::runtime_error if encoding fails.
std::vector<uint8_t> render_plot_png(const PlotSpec& spec);

// Encodes width x height RGB8 pixels (rows top to bottom) as PNG. Throws std::runtime_error.
std::vector<uint8_t> encode_png(int width, int height, const std::vector<uint8_t>& rgb);

}  // namespace lightpatch::tool
