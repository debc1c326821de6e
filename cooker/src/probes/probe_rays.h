// The directions a probe gathers along: a spherical Fibonacci lattice, as evenly spread as n
// points on the sphere get, turned about the vertical axis by `turn` radians (per probe, so that
// neighbouring probes do not share their gaps).
#pragma once

#include <glm/glm.hpp>

#include <algorithm>
#include <cmath>
#include <cstddef>
#include <limits>

#include "lightpatch/cooker/tracer.h"

namespace lightpatch::cooker {

inline glm::vec3 sphere_direction(int i, int n, float turn) {
  const float y = 1.0f - (2.0f * float(i) + 1.0f) / float(n);
  const float r = std::sqrt(std::max(0.0f, 1.0f - y * y));
  const float phi = 2.39996322973f * float(i) + turn;  // the golden angle
  return {r * std::cos(phi), y, r * std::sin(phi)};
}

// Points `spacing` apart over a box from `lo` across `extent`, centred in it (equal margins on both
// sides), point i with x fastest, then y, then z (pack::ProbeGridRecord's order): the probes' grid
// and the anchors' lattice.
struct CentredGrid {
  static int points_along(float extent, float spacing) {
    return int(std::floor(std::max(0.0f, extent) / spacing)) + 1;
  }
  CentredGrid(const glm::vec3& lo, const glm::vec3& extent, float spacing_m)
      : size(points_along(extent.x, spacing_m), points_along(extent.y, spacing_m),
             points_along(extent.z, spacing_m)),
        origin(lo + 0.5f * (extent - spacing_m * glm::vec3(size - glm::ivec3(1)))),
        spacing(spacing_m) {}
  size_t count() const { return size_t(size.x) * size_t(size.y) * size_t(size.z); }
  glm::vec3 point(size_t i) const {
    const glm::ivec3 g(int(i % size_t(size.x)), int(i / size_t(size.x) % size_t(size.y)),
                       int(i / (size_t(size.x) * size_t(size.y))));
    return origin + spacing * glm::vec3(g);
  }
  glm::ivec3 size;
  glm::vec3 origin;
  float spacing;
};

// Whether `p` lies inside solid static geometry (in a wall, under the floor, inside a closed
// box): more than a quarter of 64 rays from it, evenly spread, meet the back of a surface first.
// Nothing moves there: no probe (probe_placement.cpp) and no anchor (anchors.cpp) stands there.
inline bool inside_solid(const Tracer& tracer, const glm::vec3& p) {
  constexpr int kRays = 64;
  constexpr int kMaxBack = kRays / 4;
  int back = 0;
  for (int r = 0; r < kRays; ++r) {
    const glm::vec3 dir = sphere_direction(r, kRays, 0.0f);
    const Hit h = tracer.intersect(p, dir, 0.0f, std::numeric_limits<float>::max(), false);
    if (h.hit && glm::dot(dir, h.geometric_normal) > 0.0f) ++back;
  }
  return back > kMaxBack;
}

}  // namespace lightpatch::cooker
