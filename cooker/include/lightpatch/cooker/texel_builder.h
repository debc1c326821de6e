// Rasterizes the layout into texels (seed 003): world position and normal at texel centres,
// pushed out of solid geometry (seed 004 §6.10.3); and the post-bake image passes: seam
// stitching and dilation of unused texels.
#pragma once

#include "lightpatch/cooker/layout.h"
#include "lightpatch/cooker/maps.h"
#include "lightpatch/cooker/scene.h"
#include "lightpatch/cooker/texels.h"

namespace lightpatch::cooker {

class Tracer;

// `tracer` (may be null in tests that need no push-out) is used to move samples out of solid.
TexelSet build_texels(const Scene& scene, const Layout& layout, const Tracer* tracer);

// Makes texels on both sides of a chart cut agree, then fills invalid texels from their nearest
// valid neighbours (within the texel's region) so bilinear filtering shows no black seams.
void finalize_map(FloatImage& map, const Scene& scene, const Layout& layout,
                  const TexelSet& texels);

}  // namespace lightpatch::cooker
