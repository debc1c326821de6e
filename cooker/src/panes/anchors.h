// The moving lights' anchors (pack_format.h, "Anchors"; docs/moving_lights.md, "Anchors"): light
// positions on a lattice over the scene's free space, each with the spherical depth map the
// runtime reads its visibility of a moving light from.
#pragma once

#include <vector>

#include "lightpatch/cooker/maps.h"
#include "lightpatch/cooker/scene.h"
#include "lightpatch/cooker/tracer.h"

namespace lightpatch::cooker {

// The lattice points origin + spacing * (i, j, k) over the scene's bounds (centred in them, as the
// probes' grid) that do not lie inside solid static geometry, x fastest, then y, then z. Each is a
// PaneMap with record (light 0, eye, normal (0, 0, 1), radius = spacing, depth_range, point_count
// 0, the depth map) and no texels or maps. Throws CookError when the lattice would hold more than
// pack::kMaxPanes anchors, or for a spacing that is not finite and > 0. Deterministic.
std::vector<PaneMap> place_anchors(const Scene& scene, const Tracer& tracer, float spacing,
                                   int threads);

// The irradiance at a receiver at `x` with unit normal `n` from moving light `light` (a point
// light, intensity 1, white) standing at `eye`: cos / max(d^2, r^2), r its radius (at least a
// scene-scaled floor), times its range window; 0 where static geometry blocks the segment (one
// shadow ray) or the receiver faces away. An anchor's map draws its direct light so beyond its
// near field (panes.cpp), its probe sets at every texel a probe sees (probe_bake.cpp).
float anchor_irradiance(const Scene& scene, const Tracer& tracer, const Light& light,
                        const glm::vec3& eye, const glm::vec3& x, const glm::vec3& n);

}  // namespace lightpatch::cooker
