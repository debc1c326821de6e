#include "plot_png.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <stdexcept>

#if defined(__GNUC__)
#pragma GCC diagnostic push
#pragma GCC diagnostic ignored "-Wunused-function"
#pragma GCC diagnostic ignored "-Wsign-compare"
#pragma GCC diagnostic ignored "-Wmissing-field-initializers"
#pragma GCC diagnostic ignored "-Wconversion"
#endif
#define STB_IMAGE_WRITE_IMPLEMENTATION
#define STB_IMAGE_WRITE_STATIC
#include <stb/stb_easy_font.h>
#include <stb/stb_image_write.h>
#if defined(__GNUC__)
#pragma GCC diagnostic pop
#endif

namespace lightpatch::tool {

namespace {

struct Rgb {
  uint8_t r, g, b;
};

constexpr Rgb kBlack{0, 0, 0};
constexpr Rgb kGrid{225, 225, 225};
constexpr Rgb kGridMinor{242, 242, 242};
constexpr Rgb kText{40, 40, 40};
constexpr Rgb kFront{200, 30, 30};
// Distinguishable on white (Tableau 10, without the red kept for the front).
constexpr Rgb kSeries[] = {{31, 119, 180},  {255, 127, 14}, {44, 160, 44},
                           {148, 103, 189}, {140, 86, 75},  {227, 119, 194},
                           {127, 127, 127}, {188, 189, 34}, {23, 190, 207}};

class Canvas {
 public:
  Canvas(int w, int h) : w_(w), h_(h), rgb_(size_t(w) * size_t(h) * 3, 255) {}

  void pixel(int x, int y, Rgb c) {
    if (x < 0 || y < 0 || x >= w_ || y >= h_) return;
    uint8_t* p = &rgb_[(size_t(y) * size_t(w_) + size_t(x)) * 3];
    p[0] = c.r;
    p[1] = c.g;
    p[2] = c.b;
  }
  void rect(int x0, int y0, int x1, int y1, Rgb c) {  // inclusive-exclusive
    for (int y = std::max(0, y0); y < std::min(h_, y1); ++y) {
      for (int x = std::max(0, x0); x < std::min(w_, x1); ++x) pixel(x, y, c);
    }
  }
  // A line `thick` pixels wide (square brush), Bresenham.
  void line(int x0, int y0, int x1, int y1, Rgb c, int thick = 1) {
    const int dx = std::abs(x1 - x0), dy = -std::abs(y1 - y0);
    const int sx = x0 < x1 ? 1 : -1, sy = y0 < y1 ? 1 : -1;
    int err = dx + dy;
    const int lo = -(thick - 1) / 2, hi = thick / 2;
    for (;;) {
      rect(x0 + lo, y0 + lo, x0 + hi + 1, y0 + hi + 1, c);
      if (x0 == x1 && y0 == y1) break;
      const int e2 = 2 * err;
      if (e2 >= dy) {
        err += dy;
        x0 += sx;
      }
      if (e2 <= dx) {
        err += dx;
        y0 += sy;
      }
    }
  }
  void disc(int cx, int cy, double r, Rgb c) {
    const int ri = int(std::ceil(r));
    for (int y = -ri; y <= ri; ++y) {
      for (int x = -ri; x <= ri; ++x) {
        if (x * x + y * y <= r * r) pixel(cx + x, cy + y, c);
      }
    }
  }
  void ring(int cx, int cy, double r0, double r1, Rgb c) {
    const int ri = int(std::ceil(r1));
    for (int y = -ri; y <= ri; ++y) {
      for (int x = -ri; x <= ri; ++x) {
        const double d2 = x * x + y * y;
        if (d2 <= r1 * r1 && d2 >= r0 * r0) pixel(cx + x, cy + y, c);
      }
    }
  }
  // Text with its top-left corner at (x, y), each font pixel `scale` pixels.
  void text(int x, int y, const std::string& s, Rgb c, int scale = 2) {
    std::vector<char> buffer(s.size() * 300 + 1024);
    std::string copy = s;
    const int quads =
        stb_easy_font_print(0.0f, 0.0f, copy.data(), nullptr, buffer.data(), int(buffer.size()));
    struct Vertex {
      float x, y, z;
      uint8_t color[4];
    };
    static_assert(sizeof(Vertex) == 16);
    const Vertex* v = reinterpret_cast<const Vertex*>(buffer.data());
    for (int q = 0; q < quads; ++q) {
      const Vertex* quad = v + 4 * q;
      float qx0 = quad[0].x, qx1 = quad[0].x, qy0 = quad[0].y, qy1 = quad[0].y;
      for (int k = 1; k < 4; ++k) {
        qx0 = std::min(qx0, quad[k].x);
        qx1 = std::max(qx1, quad[k].x);
        qy0 = std::min(qy0, quad[k].y);
        qy1 = std::max(qy1, quad[k].y);
      }
      rect(x + int(std::lround(qx0 * float(scale))), y + int(std::lround(qy0 * float(scale))),
           x + int(std::lround(qx1 * float(scale))), y + int(std::lround(qy1 * float(scale))), c);
    }
  }
  static int text_width(const std::string& s, int scale = 2) {
    std::string copy = s;
    return stb_easy_font_width(copy.data()) * scale;
  }

  int width() const { return w_; }
  int height() const { return h_; }
  const std::vector<uint8_t>& rgb() const { return rgb_; }

 private:
  int w_, h_;
  std::vector<uint8_t> rgb_;
};

bool drawable(const PlotPoint& p) {
  return std::isfinite(p.x) && std::isfinite(p.y) && p.x > 0.0 && p.y > 0.0;
}

// Log axis range: whole decades around the data, at least one decade.
void log_range(double lo, double hi, double* a, double* b) {
  double la = std::floor(std::log10(lo) + 1e-9), lb = std::ceil(std::log10(hi) - 1e-9);
  if (lb <= la) lb = la + 1.0;
  *a = la;
  *b = lb;
}

std::string tick_text(double v) {
  char buf[32];
  std::snprintf(buf, sizeof(buf), "%g", v);
  return buf;
}

void on_png(void* context, void* data, int size) {
  auto* out = static_cast<std::vector<uint8_t>*>(context);
  const uint8_t* p = static_cast<const uint8_t*>(data);
  out->insert(out->end(), p, p + size);
}

}  // namespace

std::vector<uint8_t> render_plot_png(const PlotSpec& spec) {
  Canvas c(spec.width, spec.height);
  const int left = 90, right = spec.width - 250, top = 60, bottom = spec.height - 70;

  double xmin = HUGE_VAL, xmax = -HUGE_VAL, ymin = HUGE_VAL, ymax = -HUGE_VAL;
  for (const PlotPoint& p : spec.points) {
    if (!drawable(p)) continue;
    xmin = std::min(xmin, p.x);
    xmax = std::max(xmax, p.x);
    ymin = std::min(ymin, p.y);
    ymax = std::max(ymax, p.y);
  }
  if (!(xmin <= xmax)) xmin = 0.1, xmax = 10.0, ymin = 0.1, ymax = 10.0;
  double lx0, lx1, ly0, ly1;
  log_range(xmin, xmax, &lx0, &lx1);
  log_range(ymin, ymax, &ly0, &ly1);
  auto px = [&](double x) {
    return left + int(std::lround((std::log10(x) - lx0) / (lx1 - lx0) * (right - left)));
  };
  auto py = [&](double y) {
    return bottom - int(std::lround((std::log10(y) - ly0) / (ly1 - ly0) * (bottom - top)));
  };

  // Grid and tick labels: 1, 2, 5 per decade (labelled), decades darker.
  for (double d = lx0; d <= lx1 + 1e-9; d += 1.0) {
    for (double m : {1.0, 2.0, 5.0}) {
      const double v = m * std::pow(10.0, d);
      if (std::log10(v) > lx1 + 1e-9) break;
      const int x = px(v);
      c.line(x, top, x, bottom, m == 1.0 ? kGrid : kGridMinor);
      const std::string t = tick_text(v);
      c.text(x - Canvas::text_width(t) / 2, bottom + 8, t, kText);
    }
  }
  for (double d = ly0; d <= ly1 + 1e-9; d += 1.0) {
    for (double m : {1.0, 2.0, 5.0}) {
      const double v = m * std::pow(10.0, d);
      if (std::log10(v) > ly1 + 1e-9) break;
      const int y = py(v);
      c.line(left, y, right, y, m == 1.0 ? kGrid : kGridMinor);
      const std::string t = tick_text(v);
      c.text(left - 8 - Canvas::text_width(t), y - 7, t, kText);
    }
  }
  c.line(left, bottom, right, bottom, kBlack, 2);
  c.line(left, top, left, bottom, kBlack, 2);
  c.text(left, 16, spec.title, kBlack, 2);
  c.text((left + right) / 2 - Canvas::text_width(spec.x_label) / 2, bottom + 36, spec.x_label,
         kBlack);
  c.text(left, top - 22, spec.y_label, kBlack);

  // The front, in x order.
  std::vector<const PlotPoint*> front;
  for (const PlotPoint& p : spec.points) {
    if (p.front && drawable(p)) front.push_back(&p);
  }
  std::sort(front.begin(), front.end(),
            [](const PlotPoint* a, const PlotPoint* b) { return a->x < b->x; });
  for (size_t i = 1; i < front.size(); ++i) {
    c.line(px(front[i - 1]->x), py(front[i - 1]->y), px(front[i]->x), py(front[i]->y), kFront, 2);
  }
  const size_t palette = sizeof(kSeries) / sizeof(kSeries[0]);
  for (const PlotPoint& p : spec.points) {
    if (!drawable(p)) continue;
    const Rgb col = kSeries[size_t(std::max(0, p.series)) % palette];
    if (p.front) c.ring(px(p.x), py(p.y), 7.0, 9.5, kFront);
    c.disc(px(p.x), py(p.y), 5.5, col);
  }
  for (const PlotPoint& p : spec.points) {
    if (!drawable(p) || p.label.empty()) continue;
    c.text(px(p.x) + 11, py(p.y) - 18, p.label, kBlack);
  }

  // Legend.
  int ly = top + 4;
  const int lx = right + 24;
  for (size_t s = 0; s < spec.series.size(); ++s) {
    c.disc(lx + 6, ly + 7, 5.5, kSeries[s % palette]);
    c.text(lx + 20, ly, spec.series[s], kText);
    ly += 24;
  }
  ly += 6;
  c.line(lx, ly + 7, lx + 12, ly + 7, kFront, 2);
  c.ring(lx + 6, ly + 7, 7.0, 9.5, kFront);
  c.text(lx + 20, ly, spec.front_label, kText);

  return encode_png(c.width(), c.height(), c.rgb());
}

std::vector<uint8_t> encode_png(int width, int height, const std::vector<uint8_t>& rgb) {
  std::vector<uint8_t> png;
  if (width <= 0 || height <= 0 || rgb.size() != size_t(width) * size_t(height) * 3 ||
      !stbi_write_png_to_func(on_png, &png, width, height, 3, rgb.data(), width * 3)) {
    throw std::runtime_error("PNG encoding failed");
  }
  return png;
}

}  // namespace lightpatch::tool
