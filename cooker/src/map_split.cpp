#include "map_split.h"

#include <algorithm>

#include "lightpatch/cooker/error.h"
#include "lightpatch/indirect_map.h"
#include "lightpatch/patch_decode.h"

namespace lightpatch::cooker {

std::vector<Region> coarse_regions(const std::vector<Region>& regions, int scale, int width,
                                   int height) {
  std::vector<Rect> rects;
  for (const Region& r : regions) {
    const int x0 = std::clamp(r.rect.x / scale, 0, width);
    const int y0 = std::clamp(r.rect.y / scale, 0, height);
    const int x1 = std::clamp((r.rect.x + r.rect.w + scale - 1) / scale, 0, width);
    const int y1 = std::clamp((r.rect.y + r.rect.h + scale - 1) / scale, 0, height);
    if (x1 > x0 && y1 > y0) rects.push_back(Rect{x0, y0, x1 - x0, y1 - y0});
  }
  // Charts laid out on whole blocks never overlap here; UVs used as they are may.
  auto overlap = [](const Rect& a, const Rect& b) {
    return a.x < b.x + b.w && b.x < a.x + a.w && a.y < b.y + b.h && b.y < a.y + a.h;
  };
  for (bool merged = true; merged;) {
    merged = false;
    for (size_t i = 0; i < rects.size() && !merged; ++i)
      for (size_t j = i + 1; j < rects.size() && !merged; ++j) {
        if (!overlap(rects[i], rects[j])) continue;
        const Rect& a = rects[i];
        const Rect& b = rects[j];
        const int x0 = std::min(a.x, b.x), y0 = std::min(a.y, b.y);
        const int x1 = std::max(a.x + a.w, b.x + b.w), y1 = std::max(a.y + a.h, b.y + b.h);
        rects[i] = Rect{x0, y0, x1 - x0, y1 - y0};
        rects.erase(rects.begin() + std::ptrdiff_t(j));
        merged = true;
      }
  }
  std::vector<Region> out(rects.size());
  for (size_t i = 0; i < rects.size(); ++i) out[i].rect = rects[i];
  return out;
}

void add_decoded(const SourcePatch& patch, const QuantizedPatch& q, FloatImage& map) {
  if (patch.level != 0) throw CookError("add_decoded: a magnified patch");
  const float sign = patch.negative ? -1.0f : 1.0f;
  const Rect& r = patch.dest;
  for (int y = 0; y < r.h; ++y)
    for (int x = 0; x < r.w; ++x)
      for (int c = 0; c < map.channels; ++c) {
        const uint8_t* codes = &q.codes[(size_t(y) * r.w + x) * size_t(patch.channels)];
        auto value = [&](int k) {
          return sign * q.scale * patch_decode_unit(codes[k], q.encoding);
        };
        float v;
        if (patch.channels == 2)  // two tints (pack_format.h, "Decoding a patch texel")
          v = value(0) * (float(patch.tint[c]) / 255.0f) +
              value(1) * (float(patch.tint_b[c]) / 255.0f);
        else
          v = value(patch.channels == 1 ? 0 : c) * (float(patch.tint[c]) / 255.0f);
        map.at(r.x + x, r.y + y, c) += v;
      }
}

FloatImage light_map_part(const FloatImage& map, const FloatImage& coarse, int scale) {
  FloatImage out = map;
  const uint32_t s = uint32_t(scale);
  for (int y = 0; y < map.height; ++y)
    for (int x = 0; x < map.width; ++x) {
      float v[3];
      sample_indirect(coarse.data.data(), uint32_t(coarse.channels), uint32_t(coarse.width),
                      uint32_t(coarse.height), s, uint32_t(x), uint32_t(y), v);
      for (int c = 0; c < map.channels; ++c) out.at(x, y, c) -= v[c];
    }
  return out;
}

}  // namespace lightpatch::cooker
