// What a light-map texel stands for: the patch of surface its light-map square covers, not only its
// sample point. Direct light is integrated over it (a shadow edge thinner than a texel comes out
// as the grey it covers, not as dots where it happens to cross texel centres) and the cook's
// gather rays leave from it, as the reference path tracer's paths do, so both define a texel's
// irradiance the same way.
#pragma once

#include <glm/glm.hpp>

#include <algorithm>
#include <bit>
#include <cmath>
#include <cstdint>
#include <vector>

#include "lightpatch/cooker/texels.h"
#include "lightpatch/cooker/tracer.h"
#include "sample_hash.h"

namespace lightpatch::cooker {

// Points of the texel's surface patch: sample point + a u + b v, (a, b) in [a0, a1] x [b0, b1]. u
// and v step to the next texel along the page's x and y, in the surface's tangent plane; a side
// without a neighbouring texel of the same surface (a chart's edge, or a neighbour pushed out of
// solid geometry) is not entered (its bound is 0). The patch is cut in kFootprintCells x
// kFootprintCells cells; `open` flags those in the open (bit i + kFootprintCells * j: cell i along
// a, j along b): a cell behind static geometry standing on the surface (the part of a wall's texel
// under a table, of a floor's under a wall), wholly or in part, is never sampled: some of its
// points would lie inside that geometry. The cook's direct light and gathering and the reference
// path tracer all sample the same open cells, so they define a texel's light the same way.
constexpr int kFootprintCells = 4;
struct TexelFootprint {
  glm::vec3 u{0.0f}, v{0.0f};
  float a0 = 0.0f, a1 = 0.0f, b0 = 0.0f, b1 = 0.0f;
  uint16_t open = 0xFFFF;
};

// One footprint per texel (zero for invalid texels). With `tracer`, a cell is closed when a
// static surface stands between the texel's sample point and the cell's centre or one of its
// corners (along the surface, just above it: a wall standing on the floor, a table against the
// wall), so that no point of an open cell lies inside a wall; semi-dynamic objects do not close
// cells, so every state samples the same points. A texel with no open cell is its sample point
// alone (a0 = a1 = b0 = b1 = 0; the point is in the open: texel_builder.cpp pushes it out).
std::vector<TexelFootprint> texel_footprints(const TexelSet& texels, const Tracer* tracer = nullptr,
                                             int threads = 1);

// The point of a footprint's open part at (a, b) in [0, 1)^2: uniform (a, b) give points uniform
// over the open cells.
inline glm::vec3 footprint_point_at(const TexelFootprint& f, const glm::vec3& centre, double a,
                                    double b) {
  if (f.open != 0xFFFF) {
    // a picks one of the open cells and its place along a within it: uniform over the open part.
    const int count = std::popcount(f.open);
    const double scaled = a * count;
    int pick = std::min(count - 1, int(scaled)), cell = 0;
    for (; cell < kFootprintCells * kFootprintCells; ++cell)
      if ((f.open >> cell & 1u) && pick-- == 0) break;
    a = (double(cell % kFootprintCells) + (scaled - std::floor(scaled))) / kFootprintCells;
    b = (double(cell / kFootprintCells) + b) / kFootprintCells;
  }
  return centre + f.u * (f.a0 + float(a) * (f.a1 - f.a0)) + f.v * (f.b0 + float(b) * (f.b1 - f.b0));
}

// Point k of a spread of points over a footprint's open cells (the R2 low-discrepancy sequence,
// rotated per texel by `rng`): the same points for the same (k, rng). Inline: a caller's loop
// over k hashes `rng` once. A caller that also draws a direction per point takes both from one
// sequence of four dimensions instead (gather.cpp): this point's R2 and a direction's R2 of the
// same k would tie each point to one direction.
inline glm::vec3 footprint_point(const TexelFootprint& f, const glm::vec3& centre, int k,
                                 uint64_t rng) {
  const auto [a0, b0] = rotation_of(rng);
  return footprint_point_at(f, centre, kronecker(a0, kR2[0], k), kronecker(b0, kR2[1], k));
}

}  // namespace lightpatch::cooker
