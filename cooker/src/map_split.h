// Two-level storage of a map (pack_format.h, "Two target maps"): its bounce part on the indirect
// map, 1/s of the light map's resolution per axis (the block image of its bounce light), and on
// the light map the rest: the map less the indirect map's magnification (direct light, and
// wherever the magnification differs from the finalized map: creases and contacts inside a chart,
// chart edges, seams; negative where the magnification is too bright). The light-map part is
// taken against the quantized indirect part, so light map + magnified indirect map gives back
// the baked map to the light map's own 8-bit rounding.
#pragma once

#include <vector>

#include "lightpatch/cooker/layout.h"
#include "lightpatch/cooker/maps.h"
#include "patch_extract.h"
#include "quantize.h"

namespace lightpatch::cooker {

// The regions' rectangles in indirect-map texels (rounded outwards), overlapping ones merged into
// one, so that every indirect texel is cut into patches at most once. `charts` are dropped.
std::vector<Region> coarse_regions(const std::vector<Region>& regions, int scale, int width,
                                   int height);

// Adds a quantized patch's signed values, as the runtime decodes them, to `map` (3 channels; a
// 1-channel patch adds its grey value to all three), at the patch's destination.
void add_decoded(const SourcePatch& patch, const QuantizedPatch& q, FloatImage& map);

// The light-map part of a map whose indirect part is `coarse` (3 channels, map size / s): the
// (finalized) map less the magnified indirect part (indirect_map.h), at every texel, so that
// light map + magnified indirect map is the finalized map wherever the runtime filters, chart
// edges and seams included. A 1-channel map takes the coarse map's first channel.
FloatImage light_map_part(const FloatImage& map, const FloatImage& coarse, int scale);

}  // namespace lightpatch::cooker
