// Scenes for the indirect-light tests: a closed diffuse box (furnace) and its texels.
#pragma once

#include "test_scenes.h"

namespace lightpatch::test {

// A closed 2 x 2 x 2 m room centred at the origin, every wall of albedo `rho` (material 0).
cooker::Scene furnace_box(float rho);

// Texels on the six inner faces of the box [lo, hi], n x n per face, stacked vertically
// (width n, height 6n). `area` receives each texel's area per face (same for a cube).
cooker::TexelSet box_texels(const glm::vec3& lo, const glm::vec3& hi, int n);

// Area of texel t of box_texels(lo, hi, n).
float box_texel_area(const glm::vec3& lo, const glm::vec3& hi, int n, size_t t);

}  // namespace lightpatch::test
