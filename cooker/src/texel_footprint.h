// What a light-map texel stands for: the patch of surface its light-map square covers, not only its
// sample point. Direct light is integrated over it (a shadow edge thinner than a texel comes out
// as the grey it covers, not as dots where it happens to cross texel centres), by the cook and the
// reference path tracer alike, so both define a texel's irradiance the same way.
#pragma once

#include <glm/glm.hpp>

#include <cmath>
#include <cstdint>
#include <vector>

#include "lightpatch/cooker/texels.h"
#include "sample_hash.h"

namespace lightpatch::cooker {

// Points of the texel's surface patch: sample point + a u + b v, (a, b) in [a0, a1] x [b0, b1].
// u and v step to the next texel along the page's x and y, in the surface's tangent plane; a
// side without a neighbouring texel of the same surface (a chart's edge, or a neighbour pushed
// out of solid geometry) is not entered (its bound is 0).
struct TexelFootprint {
  glm::vec3 u{0.0f}, v{0.0f};
  float a0 = 0.0f, a1 = 0.0f, b0 = 0.0f, b1 = 0.0f;
};

// One footprint per texel (zero for invalid texels).
std::vector<TexelFootprint> texel_footprints(const TexelSet& texels);

// Point k of a spread of points over a footprint (the R2 low-discrepancy sequence, rotated per
// texel by `rng`): the same points for the same (k, rng).
// Inline: a caller's loop over k hashes `rng` once.
inline glm::vec3 footprint_point(const TexelFootprint& f, const glm::vec3& centre, int k,
                                 uint64_t rng) {
  constexpr double kA1 = 0.7548776662466927, kA2 = 0.5698402909980532;
  double a = hash_to_unit(rng) + kA1 * double(k + 1);
  double b = hash_to_unit(sample_hash(rng, 1, 2, 3)) + kA2 * double(k + 1);
  a -= std::floor(a);
  b -= std::floor(b);
  return centre + f.u * (f.a0 + float(a) * (f.a1 - f.a0)) + f.v * (f.b0 + float(b) * (f.b1 - f.b0));
}

}  // namespace lightpatch::cooker
