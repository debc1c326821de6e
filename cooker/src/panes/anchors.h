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

}  // namespace lightpatch::cooker
