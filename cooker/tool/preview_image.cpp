#include "preview_image.h"

#include <algorithm>
#include <cmath>

#include "args.h"
#include "lightpatch/cooker/error.h"
#include "lightpatch/cooker/io.h"
#include "plot_png.h"

namespace lightpatch::tool {

namespace {

uint8_t srgb_byte(float linear) {
  const float c = std::clamp(linear, 0.0f, 1.0f);
  const float s = c <= 0.0031308f ? 12.92f * c : 1.055f * std::pow(c, 1.0f / 2.4f) - 0.055f;
  return static_cast<uint8_t>(std::lround(s * 255.0f));
}

// Linear factor that maps the 99th percentile of the lit texels' largest channel to 1.
float auto_exposure(const cooker::FloatImage& map) {
  std::vector<float> lit;
  const size_t ch = size_t(map.channels);
  for (size_t i = 0; i + ch <= map.data.size(); i += ch) {
    float m = 0.0f;
    for (size_t c = 0; c < ch; ++c) m = std::max(m, map.data[i + c]);
    if (m > 0.0f && std::isfinite(m)) lit.push_back(m);
  }
  if (lit.empty()) return 1.0f;
  const size_t k = std::min(lit.size() - 1, lit.size() * 99 / 100);
  std::nth_element(lit.begin(), lit.begin() + std::ptrdiff_t(k), lit.end());
  return lit[k] > 0.0f ? 1.0f / lit[k] : 1.0f;
}

glm::vec3 linear_rgb(const cooker::FloatImage& map, size_t texel) {
  const size_t ch = size_t(map.channels);
  if (ch >= 3) return {map.data[texel * ch], map.data[texel * ch + 1], map.data[texel * ch + 2]};
  return glm::vec3(map.data[texel * ch]);
}

// A colour of its own per instance: hues spread by the golden ratio; semi-dynamic objects
// saturated, static meshes pale.
glm::vec3 instance_colour(int instance, int object) {
  const float h = object >= 0 ? std::fmod(0.97f + 0.618034f * float(object), 1.0f)
                              : std::fmod(0.47f + 0.618034f * float(instance), 1.0f);
  const float s = object >= 0 ? 0.9f : 0.25f;
  const glm::vec3 k = glm::clamp(
      glm::abs(glm::mod(glm::vec3(h * 6.0f) + glm::vec3(0, 4, 2), 6.0f) - 3.0f) - 1.0f, 0.0f, 1.0f);
  return glm::mix(glm::vec3(1.0f), k, s);
}

// Texels a UV triangle covers (centre inside, or within half a texel of it).
template <typename F>
void for_covered(const glm::vec2 tri[3], int w, int h, F&& f) {
  const glm::vec2 lo = glm::min(tri[0], glm::min(tri[1], tri[2])) - 0.5f;
  const glm::vec2 hi = glm::max(tri[0], glm::max(tri[1], tri[2])) + 0.5f;
  const float area =
      (tri[1].x - tri[0].x) * (tri[2].y - tri[0].y) - (tri[1].y - tri[0].y) * (tri[2].x - tri[0].x);
  for (int y = std::max(0, int(std::floor(lo.y))); y <= std::min(h - 1, int(hi.y)); ++y)
    for (int x = std::max(0, int(std::floor(lo.x))); x <= std::min(w - 1, int(hi.x)); ++x) {
      const glm::vec2 p(float(x) + 0.5f, float(y) + 0.5f);
      bool covered = true;
      for (int k = 0; k < 3 && covered; ++k) {
        const glm::vec2 a = tri[k], b = tri[(k + 1) % 3], e = b - a;
        const float len = glm::length(e);
        if (!(len > 0.0f)) continue;
        // Signed distance of p from the edge, positive inside (either winding).
        const float d = (e.x * (p.y - a.y) - e.y * (p.x - a.x)) / len * (area >= 0.0f ? 1 : -1);
        covered = d >= -0.5f;
      }
      if (covered) f(x, y);
    }
}

}  // namespace

PreviewView parse_preview_view(const std::string& name) {
  if (name == "lightmap") return PreviewView::kLightmap;
  if (name == "atlases") return PreviewView::kAtlases;
  if (name == "charts") return PreviewView::kCharts;
  if (name == "checker") return PreviewView::kChecker;
  throw cooker::CookError("--view takes lightmap, atlases, charts or checker, not '" + name + "'");
}

ChartTriangles pack_charts(const PackView& pack) {
  ChartTriangles c;
  for (uint32_t m = 0; m < pack.mesh_count(); ++m) {
    const pack::MeshRecord& r = pack.mesh(m);
    const pack::MeshVertex* v = pack.mesh_vertices(m);
    const uint32_t* idx = pack.mesh_indices(m);
    const int object = r.object == pack::kNone16 ? -1 : int(r.object);
    for (uint32_t k = 0; k + 2 < r.index_count; k += 3) {
      for (int j = 0; j < 3; ++j) c.uv.push_back({v[idx[k + j]].u, v[idx[k + j]].v});
      c.instance.push_back(int(m));
      c.object.push_back(object);
    }
  }
  return c;
}

ChartTriangles layout_charts(const cooker::Scene& scene, const cooker::Layout& layout) {
  ChartTriangles c;
  for (size_t m = 0; m < layout.meshes.size(); ++m) {
    const cooker::MeshLayout& ml = layout.meshes[m];
    for (size_t k = 0; k + 2 < ml.indices.size(); k += 3) {
      for (size_t j = 0; j < 3; ++j) c.uv.push_back(ml.uv[ml.indices[k + j]]);
      c.instance.push_back(int(m));
      c.object.push_back(scene.meshes[m].object);
    }
  }
  return c;
}

RgbImage tonemap(const cooker::FloatImage& map, float exposure) {
  RgbImage img{map.width, map.height, {}};
  img.rgb.resize(size_t(map.width) * size_t(map.height) * 3);
  const float k = auto_exposure(map) * exposure;
  for (size_t t = 0; t < size_t(map.width) * size_t(map.height); ++t) {
    const glm::vec3 c = linear_rgb(map, t);
    const bool negative = c.x < 0.0f || c.y < 0.0f || c.z < 0.0f;
    for (int j = 0; j < 3; ++j)
      img.rgb[t * 3 + size_t(j)] = negative ? (j == 1 ? 0 : 255) : srgb_byte(c[j] * k);
  }
  return img;
}

RgbImage chart_image(const cooker::FloatImage& map, const ChartTriangles& charts, bool checker,
                     float exposure) {
  RgbImage img{map.width, map.height, {}};
  img.rgb.assign(size_t(map.width) * size_t(map.height) * 3, 0);
  const float k = auto_exposure(map) * exposure;
  const glm::vec2 size(float(map.width), float(map.height));
  for (size_t t = 0; t < charts.instance.size(); ++t) {
    const glm::vec2 tri[3] = {charts.uv[3 * t] * size, charts.uv[3 * t + 1] * size,
                              charts.uv[3 * t + 2] * size};
    const glm::vec3 colour = instance_colour(charts.instance[t], charts.object[t]);
    for_covered(tri, map.width, map.height, [&](int x, int y) {
      const size_t i = size_t(y) * size_t(map.width) + size_t(x);
      float shade;
      if (checker) {
        shade = (x + y) % 2 == 0 ? 1.0f : 0.45f;
      } else {
        const glm::vec3 c = linear_rgb(map, i) * k;
        const float lum = std::clamp(0.2126f * c.x + 0.7152f * c.y + 0.0722f * c.z, 0.0f, 1.0f);
        shade = 0.3f + 0.7f * lum;
      }
      for (int j = 0; j < 3; ++j) img.rgb[i * 3 + size_t(j)] = srgb_byte(colour[j] * shade);
    });
  }
  return img;
}

RgbImage atlas_image(const PackView& pack) {
  RgbImage img;
  for (uint32_t a = 0; a < pack.atlas_count(); ++a) {
    img.width = std::max(img.width, int(pack.atlas(a).width) * 4);
    img.height += int(pack.atlas(a).height);
  }
  img.rgb.assign(size_t(img.width) * size_t(img.height) * 3, 0);
  int top = 0;
  for (uint32_t a = 0; a < pack.atlas_count(); ++a) {
    const int aw = int(pack.atlas(a).width), ah = int(pack.atlas(a).height);
    const uint8_t* px = pack.atlas_pixels(a);
    for (int y = 0; y < ah; ++y)
      for (int x = 0; x < aw; ++x)
        for (int c = 0; c < 4; ++c) {
          const uint8_t v = px[(size_t(y) * size_t(aw) + size_t(x)) * 4 + size_t(c)];
          const size_t o = (size_t(top + y) * size_t(img.width) + size_t(c * aw + x)) * 3;
          img.rgb[o] = img.rgb[o + 1] = img.rgb[o + 2] = v;
        }
    top += ah;
  }
  return img;
}

RgbImage zoomed(const RgbImage& image, int zoom) {
  if (zoom <= 1) return image;
  RgbImage out{image.width * zoom, image.height * zoom, {}};
  out.rgb.resize(size_t(out.width) * size_t(out.height) * 3);
  for (int y = 0; y < out.height; ++y)
    for (int x = 0; x < out.width; ++x)
      for (int c = 0; c < 3; ++c)
        out.rgb[(size_t(y) * size_t(out.width) + size_t(x)) * 3 + size_t(c)] =
            image.rgb[(size_t(y / zoom) * size_t(image.width) + size_t(x / zoom)) * 3 + size_t(c)];
  return out;
}

PreviewOptions parse_preview_options(Args& args, const char* png_option) {
  PreviewOptions o;
  if (png_option) args.option(png_option, &o.png);
  std::string view;
  if (args.option("--view", &view)) {
    try {
      o.view = parse_preview_view(view);
    } catch (const cooker::CookError& e) {
      throw ArgsError(e.what());
    }
  }
  o.exposure = args.float_option("--exposure", 1.0f, 1e-6f, 1e6f);
  o.zoom = args.int_option("--zoom", 1, 1, 16);
  return o;
}

void write_preview(const PreviewOptions& options, const cooker::FloatImage& map,
                   const ChartTriangles& charts, const PackView* pack) {
  RgbImage img;
  switch (options.view) {
    case PreviewView::kLightmap:
      img = tonemap(map, options.exposure);
      break;
    case PreviewView::kAtlases:
      if (!pack) throw cooker::CookError("--view atlases needs a pack (lightpatch preview)");
      img = atlas_image(*pack);
      break;
    case PreviewView::kCharts:
    case PreviewView::kChecker:
      img = chart_image(map, charts, options.view == PreviewView::kChecker, options.exposure);
      break;
  }
  img = zoomed(img, options.zoom);
  const std::vector<uint8_t> png = encode_png(img.width, img.height, img.rgb);
  cooker::write_file_atomic(options.png, png.data(), png.size());
}

}  // namespace lightpatch::tool
