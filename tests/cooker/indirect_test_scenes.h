// Scenes for the indirect-light tests: a closed diffuse box (furnace) and its texels.
#pragma once

#include "test_scenes.h"

namespace lightpatch::test {

// A closed 2 x 2 x 2 m room centred at the origin, every wall of albedo `rho` (material 0).
cooker::Scene furnace_box(float rho);

// The furnace's lamp: 1 cd, a little off the box's centre (so no symmetry hides an error).
cooker::Light furnace_lamp(bool semi_dynamic = false);

// Texels on the six inner faces of the box [lo, hi], n x n per face, stacked vertically
// (width n, height 6n). `area` receives each texel's area per face (same for a cube).
cooker::TexelSet box_texels(const glm::vec3& lo, const glm::vec3& hi, int n);

// Area of texel t of box_texels(lo, hi, n).
float box_texel_area(const glm::vec3& lo, const glm::vec3& hi, int n, size_t t);

// A 10 x 10 m floor (material 0) under a 2 x 2 m panel 1 m above the origin, facing down, of
// radiance `radiance` and albedo `panel_albedo` (material 1). Over the origin its irradiance is
// pi L F, F = 4 (1/pi) (1/sqrt2) atan(1/sqrt2) (a parallel rectangle over a corner, four times):
// emissive_panel_irradiance().
cooker::Scene emissive_panel(const glm::vec3& radiance, float panel_albedo);
double emissive_panel_irradiance(double radiance);

}  // namespace lightpatch::test
