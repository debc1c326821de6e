// Light-map parameterization: verbatim TEXCOORD_1 when every mesh has a valid one, otherwise an
// automatic unwrap (charts grown by normal similarity, planar projection, overlap rejection,
// borders, per-region packing; seed 004 §6.1-6.2, §6.9). Deterministic.
#pragma once

#include "lightpatch/cooker/layout.h"
#include "lightpatch/cooker/scene.h"

namespace lightpatch::cooker {

// Throws CookError (e.g. overlapping TEXCOORD_1 triangles, naming the mesh).
Layout build_layout(const Scene& scene, const LayoutOptions& options);

}  // namespace lightpatch::cooker
