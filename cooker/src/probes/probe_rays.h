// The directions a probe gathers along: a spherical Fibonacci lattice, as evenly spread as n
// points on the sphere get, turned about the vertical axis by `turn` radians (per probe, so that
// neighbouring probes do not share their gaps).
#pragma once

#include <glm/glm.hpp>

#include <cmath>
#include <limits>

#include "lightpatch/cooker/tracer.h"

namespace lightpatch::cooker {

inline glm::vec3 sphere_direction(int i, int n, float turn) {
  const float y = 1.0f - (2.0f * float(i) + 1.0f) / float(n);
  const float r = std::sqrt(std::max(0.0f, 1.0f - y * y));
  const float phi = 2.39996322973f * float(i) + turn;  // the golden angle
  return {r * std::cos(phi), y, r * std::sin(phi)};
}

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
