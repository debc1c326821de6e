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
  int channels = 1;    // 1 or 3
  Rect dest;           // in the target map
  // Level (pack_format.h, "Magnified patches"): stored at 1/2^level of the target map's
  // resolution per axis, stored_w() x stored_h() texels that the runtime magnifies into `dest`.
  int level = 0;
  // Magnitudes (sign removed, >= 0), stored_w() * stored_h() * channels, row-major from the top.
  std::vector<float> values;
  // Per stored texel: 1 where the value (of this patch's sign) is significant; errors are
  // measured there.
  std::vector<uint8_t> significant;
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
// Throws CookError on a non-finite value (naming `what` and the texel).
void extract_patches(const FloatImage& map, const std::vector<Region>& regions, float threshold,
                     int max_dim, const SourcePatch& prototype, const std::string& what,
                     std::vector<SourcePatch>& out);

// Stores a level-0 patch at `level` (1..pack::kMaxPatchLevel): each stored texel is the mean of
// its 2^level x 2^level block of the patch's texels (the blocks at the right and bottom edges
// may be partial), significant where any of them is. The runtime's bilinear magnification
// (pack_format.h) then gives back a linear ramp exactly inside the patch, and the patch costs
// 4^level times fewer atlas texels: for smooth light only (a moving light's pane).
void reduce_patch(SourcePatch& patch, int level);

// The largest max - min over a 3-channel patch's texels (its tint); 0 for other patches.
float colour_spread(const SourcePatch& patch);

// Colour decision for a 3-channel patch (bounce light tinted by albedos): where every texel's
// channels lie within `threshold` of each other (max - min), the tint is below the 8-bit step
// and the patch becomes one channel holding (max + min) / 2, within threshold / 2 of every
// channel. `spread` is colour_spread(patch). Returns true if it collapsed.
bool collapse_untinted(SourcePatch& patch, float spread);

}  // namespace lightpatch::cooker
