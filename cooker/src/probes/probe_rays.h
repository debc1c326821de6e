// The directions a probe gathers along: a spherical Fibonacci lattice, as evenly spread as n
// points on the sphere get, turned about the vertical axis by `turn` radians (per probe, so that
// neighbouring probes do not share their gaps).
#pragma once

#include <glm/glm.hpp>

#include <cmath>

namespace lightpatch::cooker {

inline glm::vec3 sphere_direction(int i, int n, float turn) {
  const float y = 1.0f - (2.0f * float(i) + 1.0f) / float(n);
  const float r = std::sqrt(std::max(0.0f, 1.0f - y * y));
  const float phi = 2.39996322973f * float(i) + turn;  // the golden angle
  return {r * std::cos(phi), y, r * std::sin(phi)};
}

}  // namespace lightpatch::cooker
