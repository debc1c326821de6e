// Rasterizes the layout into texels (seed 003): world position and normal at texel centres,
// pushed out of solid geometry (seed 004 §6.10.3); and the post-bake image passes: seam
// stitching and dilation of unused texels.
#pragma once

#include "lightpatch/cooker/layout.h"
#include "lightpatch/cooker/maps.h"
#include "lightpatch/cooker/progress.h"
#include "lightpatch/cooker/scene.h"
#include "lightpatch/cooker/texels.h"

namespace lightpatch::cooker {

class Tracer;

// `tracer` (may be null in tests that need no push-out) is used to move samples out of solid.
TexelSet build_texels(const Scene& scene, const Layout& layout, const Tracer* tracer);

// Fills invalid texels from their nearest valid neighbours (within the texel's region) so
// bilinear filtering shows no black seams, then makes texels on both sides of a chart cut agree.
// A linear map with non-negative weights: a map of non-negative irradiance stays non-negative,
// and finalizing each map of a recomposition equals finalizing the recomposed map.
void finalize_map(FloatImage& map, const Scene& scene, const Layout& layout,
                  const TexelSet& texels);

// finalize_map() on every map the bake made: base, contributions, shadows, pair corrections and
// static shadows (every map the pack recombines). `progress` (may be null) advances per map.
void finalize_maps(BakedMaps& maps, const Scene& scene, const Layout& layout,
                   const TexelSet& texels, Progress* progress = nullptr);

}  // namespace lightpatch::cooker
