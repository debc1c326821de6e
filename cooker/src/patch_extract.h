// Cutting float maps into light patches (paper Alg. 4): per map and per layout region, the
// bounding box of the texels whose value is significant at the output precision, one patch per
// sign (a shadow map may be negative where an object adds bounce light).
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include "lightpatch/cooker/layout.h"
#include "lightpatch/cooker/maps.h"

namespace lightpatch::cooker {

struct SourcePatch {
  uint16_t kind = 0;  // pack::GroupKind
  int light = -1;     // pack light index (BakedMaps::lights position) or -1
  int object = -1;    // pack object index or -1
  int object_b = -1;  // second object of a pair correction, or -1
  bool negative = false;
  uint8_t target = 0;  // pack::PatchTarget
  int channels = 1;    // 1, 2 (two tints: collapse_to_two_tints) or 3
  Rect dest;           // in the target map
  // Level (pack_format.h, "Magnified patches"): stored at 1/2^level of the target map's
  // resolution per axis, stored_w() x stored_h() texels that the runtime magnifies into `dest`.
  int level = 0;
  // Magnitudes (sign removed, >= 0), stored_w() * stored_h() * channels, row-major from the top.
  std::vector<float> values;
  // Per stored texel: 1 where the value (of this patch's sign) is significant; errors are
  // measured there.
  std::vector<uint8_t> significant;
  // Per texel of a level-0 patch, a factor on coarsest_level()'s tolerance (empty: 1 everywhere):
  // the pack builder's looser tolerance for texels that hold bounce light alone.
  std::vector<float> tolerance_scale;
  // A 1-channel patch's colour (pack::PatchRecord::tint): the runtime multiplies its value by
  // tint[c] / 255 in map channel c. 255, 255, 255: grey (and every 3-channel patch). A 2-channel
  // patch's first channel's colour, and tint_b its second's (0, 0, 0 for other patches).
  uint8_t tint[3] = {255, 255, 255};
  uint8_t tint_b[3] = {0, 0, 0};
  float weight = 1.0f;     // to final-map units at the authored state (a_l for C_l/S_ol, 1 for B)
  float threshold = 0.0f;  // significance threshold in this map's units (half an output step)

  int stored_w() const { return (dest.w + (1 << level) - 1) >> level; }
  int stored_h() const { return (dest.h + (1 << level) - 1) >> level; }
};

// Significance rule: a texel is significant for sign s when some channel has s * v > threshold,
// threshold = 0.5 * output_step / a (half an 8-bit step of the final map at the authored exposure;
// a = 1 for B, a = the light's authored max(colour) * intensity for C_l and S_ol, floored at 1/100
// of the brightest light's, as the baker does). Values below it round away in the 8-bit output.
// Patches larger than max_dim are cut into tiles; each tile is shrunk to its own significant box.
// `tolerance_scale` (optional, 1 channel, the map's size) gives each patch texel its
// SourcePatch::tolerance_scale. Throws CookError on a non-finite value (naming `what` and the
// texel).
void extract_patches(const FloatImage& map, const std::vector<Region>& regions, float threshold,
                     int max_dim, const SourcePatch& prototype, const std::string& what,
                     std::vector<SourcePatch>& out, const FloatImage* tolerance_scale = nullptr);

// Stores a level-0 patch at `level` (1..pack::kMaxPatchLevel): each stored texel is the mean of
// its 2^level x 2^level block of the patch's texels (the blocks at the right and bottom edges
// may be partial), significant where any of them is. The runtime's bilinear magnification
// (pack_format.h) then gives back a linear ramp exactly inside the patch, and the patch costs
// 4^level times fewer atlas texels: for smooth light only (a moving light's pane; a light-map
// patch where coarsest_level() says its magnification stays within a tolerance).
void reduce_patch(SourcePatch& patch, int level);

// Refits the stored values of `reduced` (reduce_patch() of `full`, same rectangle and channels)
// so that their magnification matches `full` in the least-squares sense, each texel's error
// weighted by the inverse square of its tolerance_scale (1 where `full` has none): kFitIterations
// conjugate-gradient steps from the block means, each stored value kept >= 0. Block means smooth
// twice (the box, then the magnification's tent): they lift the dim side of every curve, and at a
// patch's clamped edge miss a ramp by (2^level - 1) / 2 slopes. Throws CookError on a mismatch.
constexpr int kFitIterations = 4;
void fit_patch(const SourcePatch& full, SourcePatch& reduced);

// The coarsest level in [1, max_level] (at most pack::kMaxPatchLevel) at which `patch` (level 0),
// stored as reduce_patch() then fit_patch() store it and magnified by the runtime's rule
// (patch_accumulate.h, magnify_tap), stays within `tolerance` (this map's units; times the texel's
// tolerance_scale where the patch has one) of its own values at every texel and channel of its
// rectangle; levels are tried from 1 up and the first that fails ends the search. 0 when level 1
// fails (or max_level < 1). Quantization is not included: the 8-bit codes add their own half step
// either way. With `coarsest` and a level > 0, *coarsest is the patch stored at that level (what
// reduce_patch() and fit_patch() make of it), so a caller keeps what was checked.
int coarsest_level(const SourcePatch& patch, int max_level, float tolerance,
                   SourcePatch* coarsest = nullptr);

// The tiles a light-map patch that must keep level 0 is cut into before its tiles' levels are
// chosen again (pack_builder.cpp). 8 made 2.9x the patches of 16 on the inn (53,380 against
// 18,406 on the full inn) and drew its full rebuild at 1.7-1.8x the fill-rate floor on llvmpipe,
// 16 at 1.2-1.3x.
constexpr int kLevelTile = 16;
// A level-0 tile is cut again into tiles half as wide, down to this side, where that takes fewer
// bytes (counting kPatchDrawBytes a patch): the small inn 0.975x -> 0.853x a conventional map's
// bytes with 6,864 -> 7,943 patches, the full inn 1.616x -> 1.467x with 32,093 -> 38,273; down to
// 4 the small inn gained 0.4 % more (pieces shrunk to significant texels, before
// kCutKeepFraction).
constexpr int kMinLevelTile = 8;

// What a patch costs beyond its atlas texels and record when the pack builder weighs cutting one
// into tiles or charts, in atlas bytes: each patch is one more quad to draw. On the full inn
// (llvmpipe, `lightpatch bench`) a cut was worth 46 bytes per patch it added on average; cut
// wherever it saved bytes (77,773 patches) the full rebuild drew at 1.54-1.59x the fill-rate
// floor, at 16 bytes a patch 1.41x (47,729 patches), at 32 1.25-1.28x (31,707; the uncut pack
// 1.21-1.32x in the same session).
constexpr uint64_t kPatchDrawBytes = 32;
// What drawing one destination texel costs, in atlas bytes, where the pack builder weighs
// storing a map as one set of patches or as its direct and bounce parts (both parts draw the
// texels they share). kPatchDrawBytes over the texels of fill a quad costs on llvmpipe (some 60)
// would be 0.5. The full inn at preview: at 0, 1.262x a conventional map's bytes and 10.19 M
// texels a full rebuild; at 0.25, 1.296x and 10.03 M; at 0.5, 1.319x and 9.94 M (whole maps:
// 1.509x, 9.31 M); its costliest light change 614,778 texels at all three (611,432 whole).
constexpr double kDrawTexelBytes = 0.25;

// A cut piece keeps the box of its texels above this fraction of the patch's threshold (a tenth
// of an output step), not only of its significant ones: a patch's rectangle carried the dim light
// between its significant texels, and pieces shrunk to significant texels alone dropped it. On the
// small inn with every light off (the game's dark inn), texels under one output step lost 47.5 %
// of their light against `bake-state` that way, 44.7 % in the uncut pack, 40.0 % at this fraction
// (0.853x, 1.292x and 0.905x a conventional map's bytes); at 0.5, 0.879x.
constexpr float kCutKeepFraction = 0.2f;

// A level-0 patch cut into `cells` (rectangles in the patch's own texels, clipped to it), each
// shrunk to the box of its significant texels and of those above kCutKeepFraction of the threshold
// (cells with none are dropped); the same values, the same attributes otherwise. Texels outside
// every cell are dropped.
std::vector<SourcePatch> cut_patch(const SourcePatch& patch, const std::vector<Rect>& cells);

// cut_patch() into tiles of at most tile x tile texels.
std::vector<SourcePatch> split_patch(const SourcePatch& patch, int tile);

// cut_patch() into the charts (Region::charts, each with its border) of the regions the patch
// overlaps, each chart's rectangle inset by `inset` texels per side: no piece blends two charts
// when magnified. The texels outside every (inset) chart rectangle are dropped: the dilation's
// fill of a region's free space, and with inset = Layout::border - 1 the border's outer rings,
// which no bilinear read of a mesh reaches. Empty when the patch meets fewer than two charts.
std::vector<SourcePatch> split_by_charts(const SourcePatch& patch,
                                         const std::vector<Region>& regions, int inset = 0);

// The largest max - min over a 3-channel patch's texels (its tint); 0 for other patches.
float colour_spread(const SourcePatch& patch);

// Colour decision for a 3-channel patch (bounce light tinted by albedos): where every texel's
// channels lie within `threshold` of each other (max - min), the tint is below the 8-bit step
// and the patch becomes one channel holding (max + min) / 2, within threshold / 2 of every
// channel. `spread` is colour_spread(patch). Returns true if it collapsed.
bool collapse_untinted(SourcePatch& patch, float spread);

// Colour decision for a 3-channel patch that collapse_untinted() keeps: where its light has one
// colour throughout (bounce light off one albedo, one light's colour times one surface's), the
// patch becomes one channel v with a tint t (PatchRecord::tint, 8 bits a channel, its largest
// 255): t is the colours' principal direction (the least-squares rank-1 fit of the texels'
// colours), v = max(0, t.c / t.t) with the quantized t, and the patch collapses only where every
// texel and channel of its stored rectangle stays within `tolerance` (map units) of t_c v. A
// magnified patch's stored values are checked: its magnification is a convex blend of them, so
// the bound holds at every destination texel too. Returns true if it collapsed.
bool collapse_to_tint(SourcePatch& patch, float tolerance);

// Colour decision for a 3-channel patch that collapse_to_tint() keeps: where its colours lie,
// within `tolerance`, in the cone of two colours (two lights of different colours; one light's
// direct light and its bounce off a coloured wall), the patch becomes 2 channels, each with a tint
// (PatchRecord::tint and tint_b), whose blend the runtime adds in one quad. The plane is the
// colours' least-squares one (the moments' two largest eigenvectors), the tints its cone's extreme
// rays (8 bits, each channel's largest 255), each texel the non-negative least-squares blend of the
// quantized tints, and the patch collapses only where every texel and channel of its stored
// rectangle stays within `tolerance` (map units) of that blend: linear in the values, so a
// magnified patch holds the bound at every destination texel as collapse_to_tint's does. Returns
// true if it collapsed.
bool collapse_to_two_tints(SourcePatch& patch, float tolerance);

}  // namespace lightpatch::cooker
