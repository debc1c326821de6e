#include "texel_footprint.h"

#include <algorithm>
#include <cmath>

#include "direct_light.h"
#include "worker_pool.h"

namespace lightpatch::cooker {

namespace {

// Neighbours farther than this many median texel spacings were pushed out of solid geometry (or
// belong to another part of the chart): they do not bound the footprint.
constexpr float kMaxGapSpacings = 2.0f;
// Neighbours must face the same way to be the same surface.
constexpr float kSameSurfaceCos = 0.7f;

}  // namespace

std::vector<TexelFootprint> texel_footprints(const TexelSet& texels, const Tracer* tracer,
                                             int threads) {
  const int w = texels.width, h = texels.height;
  std::vector<TexelFootprint> out(texels.position.size());
  auto same = [&](size_t a, int x, int y) {
    if (x < 0 || y < 0 || x >= w || y >= h) return false;
    const size_t b = texels.index(x, y);
    return texels.valid[b] && texels.mesh[b] == texels.mesh[a] &&
           glm::dot(texels.normal[a], texels.normal[b]) >= kSameSurfaceCos;
  };
  // The median spacing of neighbouring texels of one surface: the scale of a plausible step.
  std::vector<float> gaps;
  for (int y = 0; y < h; y += std::max(1, h / 64))
    for (int x = 0; x + 1 < w; ++x) {
      const size_t t = texels.index(x, y);
      if (texels.valid[t] && same(t, x + 1, y))
        gaps.push_back(glm::length(texels.position[t + 1] - texels.position[t]));
    }
  if (gaps.empty()) return out;
  std::nth_element(gaps.begin(), gaps.begin() + long(gaps.size() / 2), gaps.end());
  const float max_gap = kMaxGapSpacings * gaps[gaps.size() / 2];
  for (int y = 0; y < h; ++y) {
    for (int x = 0; x < w; ++x) {
      const size_t t = texels.index(x, y);
      if (!texels.valid[t]) continue;
      const glm::vec3 p = texels.position[t], n = texels.normal[t];
      // One axis: the step to each neighbour along it that is the same surface nearby.
      auto axis = [&](int dx, int dy, glm::vec3* step, float* lo, float* hi) {
        glm::vec3 fwd(0.0f), back(0.0f);
        bool has_fwd = same(t, x + dx, y + dy), has_back = same(t, x - dx, y - dy);
        if (has_fwd) fwd = texels.position[texels.index(x + dx, y + dy)] - p;
        if (has_back) back = p - texels.position[texels.index(x - dx, y - dy)];
        has_fwd = has_fwd && glm::length(fwd) <= max_gap;
        has_back = has_back && glm::length(back) <= max_gap;
        glm::vec3 s = has_fwd && has_back ? 0.5f * (fwd + back) : has_fwd ? fwd : back;
        s -= n * glm::dot(n, s);  // in the tangent plane
        *step = s;
        *lo = has_back ? -0.5f : 0.0f;
        *hi = has_fwd ? 0.5f : 0.0f;
      };
      TexelFootprint& f = out[t];
      axis(1, 0, &f.u, &f.a0, &f.a1);
      axis(0, 1, &f.v, &f.b0, &f.b1);
    }
  }
  if (!tracer) return out;
  const float eps = tracer->epsilon();
  parallel_for(h, threads, [&](int y) {
    for (int x = 0; x < w; ++x) {
      const size_t t = texels.index(x, y);
      if (!texels.valid[t]) continue;
      TexelFootprint& f = out[t];
      const glm::vec3 origin = texels.position[t] + texels.normal[t] * eps;
      // Whether static geometry stands between the sample point and the patch point at cell
      // coordinates (i, j) (cell corners at whole numbers, centres at halves), within `reach` of
      // the way: a corner on a wall's face (a cell that ends where the wall stands) is open.
      auto blocked = [&](float i, float j, float reach) {
        const float a = f.a0 + i / kFootprintCells * (f.a1 - f.a0);
        const float b = f.b0 + j / kFootprintCells * (f.b1 - f.b0);
        const glm::vec3 d = f.u * a + f.v * b;
        const float len = glm::length(d);
        return len > eps && tracer->intersect(origin, d / len, 0.0f, reach * len, false).hit;
      };
      // A cell is open when its centre and its four corners are: a cell that a wall only partly
      // covers would put points inside the wall, whose rays travel inside solid geometry (inside
      // a wall's slab, past a partition into the next room;
      // Probes.TheSealedRoomStaysDarkInTheLampsMapAtEveryPreset).
      constexpr int kCorners = kFootprintCells + 1;
      bool corner[kCorners * kCorners];
      for (int j = 0; j < kCorners; ++j)
        for (int i = 0; i < kCorners; ++i)
          corner[i + kCorners * j] = blocked(float(i), float(j), 0.99f);
      uint16_t open = 0;
      for (int j = 0; j < kFootprintCells; ++j) {
        for (int i = 0; i < kFootprintCells; ++i) {
          const bool closed = blocked(float(i) + 0.5f, float(j) + 0.5f, 1.0f) ||
                              corner[i + kCorners * j] || corner[i + 1 + kCorners * j] ||
                              corner[i + kCorners * (j + 1)] || corner[i + 1 + kCorners * (j + 1)];
          if (!closed) open |= uint16_t(1u << (i + kFootprintCells * j));
        }
      }
      if (open != 0) {
        f.open = open;
      } else {
        // Every cell runs into geometry (a corner texel of a small prop's chart, whose smooth
        // normal's tangent plane cuts into the prop; a texel in a gap narrower than itself):
        // the texel is its sample point, which is in the open (texel_builder.cpp pushes it out).
        // Keeping all cells put most of its points inside solid geometry: the small inn's worst
        // texels were such, 2-10x darker in the path tracer than the cook's gather made them
        // (docs/accuracy.md, section (n)).
        f.a0 = f.a1 = f.b0 = f.b1 = 0.0f;
        f.open = 0xFFFF;
      }
    }
  });
  return out;
}

}  // namespace lightpatch::cooker
