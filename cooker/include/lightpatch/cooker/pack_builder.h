// From float maps to a pack: patches per map and region (paper Alg. 4), 8-bit quantization with
// a per-patch scale and encoding, RGBA channel atlases (thesis §4.1.5), and the pack bytes in the
// format of lightpatch/pack_format.h.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include "lightpatch/cooker/layout.h"
#include "lightpatch/cooker/maps.h"
#include "lightpatch/cooker/report.h"
#include "lightpatch/cooker/scene.h"
#include "lightpatch/pack_format.h"

namespace lightpatch::cooker {

enum class EncodingPolicy { kAuto, kLinear, kSquare };

// Light-map patches' coarsest level and its tolerance in 8-bit output steps by default
// (PackOptions::max_patch_level, level_tolerance; README, "Magnified light-map patches", has the
// table they were chosen by), and the largest tolerance an option may ask for.
constexpr int kDefaultMaxPatchLevel = int(pack::kMaxPatchLevel);
constexpr float kDefaultLevelTolerance = 1.0f;
constexpr float kMaxLevelTolerance = 16.0f;
// The same tolerance for texels that hold bounce light alone (PackOptions::bounce_tolerance; the
// README's "Direct and bounce parts" has the table it was chosen by).
constexpr float kDefaultBounceTolerance = 3.0f;
// Production's (the shipping preset): the level tolerance, so that the pack adds no more than the
// 8-bit rounding's own error to the bake. room_soft (128 page) against the path tracer: max error
// beyond its noise 21.9 % -> 11.1 %, the bake's own; the small inn (512 page) against
// `bake-state`: the 99.9th percentile of texels' relative error 29.1 % -> 14.9 %, for 5 % more
// atlas bytes (README, "8-bit codes that keep every texel, and each map's share of the bounce
// tolerance").
constexpr float kProductionBounceTolerance = 1.0f;

struct PackOptions {
  int max_atlas_size = 2048;  // a multiple of pack::kAtlasAlign
  // Largest patch side (texels). Smaller tiles skip more empty light map but add records; 32 gave
  // the fewest atlas bytes per scene in our measurements (README, Numbers).
  int tile_size = 32;
  EncodingPolicy encoding = EncodingPolicy::kAuto;
  // Keep every 3-channel patch at 3 channels, even where its tint stays below the output step or
  // one colour fits it (collapse_to_tint) (the effect plan forced on, `cook --no-plan`).
  bool keep_colour = false;
  // Store a piece still in 3 channels after the cut whose light has one colour as 1 channel and a
  // tint (collapse_to_tint; pack_format.h, PatchRecord::tint). Off: such pieces keep 3 channels
  // (the packs of format 5, for comparisons).
  bool tint_pieces = true;
  // Store every light group that has an indirect part split into its indirect-map and light-map
  // parts, whatever it costs (otherwise chosen per light group by atlas texels).
  bool always_split = false;
  // Store tinted patches as three 1-channel patches where the atlases' alpha planes have room for
  // them: those of the groups without a light, then light contributions within the costliest
  // light change and where that takes fewer atlas bytes (pack_builder.cpp, split_for_alpha).
  bool fill_alpha = true;
  // Moving lights' panes (bounce light only, stored on the indirect map) at this level
  // (pack_format.h, "Magnified patches"): 0 texel for texel, up to pack::kMaxPatchLevel.
  int pane_level = 0;
  // Light-map patches (light groups, not panes) each at the coarsest level up to this one whose
  // magnification stays within level_tolerance output steps of the patch at every texel
  // (patch_extract.h, coarsest_level; pack_format.h, "Magnified patches"); 0: all texel for
  // texel. Up to pack::kMaxPatchLevel.
  int max_patch_level = kDefaultMaxPatchLevel;
  // In 8-bit output steps of the final map at the authored state (twice the patches' threshold);
  // > 0.
  float level_tolerance = kDefaultLevelTolerance;
  // Direct and bounce parts. Where a map has a direct part (ShadowMap::direct) and no indirect
  // part, its texels without direct light (bounce light alone) take this tolerance instead of
  // level_tolerance, capped at the light the authored image shows at the texel (in output steps:
  // a blur lifts dark texels, and every map's error adds up there) and at half of the map's own
  // light there, and never below level_tolerance; and the map is stored as its direct part's
  // patches plus its bounce part's (the map less the direct part, significant from a fraction of
  // the map's threshold, within that tolerance at every texel) where that costs less: atlas bytes,
  // records, kPatchDrawBytes a patch and kDrawTexelBytes a texel drawn (patch_extract.h). A map
  // whose threshold is a step of its own peak (a light far dimmer than the authored exposure) keeps
  // level_tolerance. In output steps like level_tolerance; >= level_tolerance.
  float bounce_tolerance = kDefaultBounceTolerance;
  // Store every map that has a direct part as its two parts, whatever it costs (tests).
  bool always_parts = false;
};

struct ProbeBake;  // probes.h

// Builds the pack bytes. Statistics and the encoding decision go into `report` ("pack"; the light
// probes' counts and bytes under "pack"/"probes"). `probes` (optional) adds the light-probe
// sections: its sets are sorted by owner and empty ones dropped; a set's light and object are the
// pack's light (BakedMaps::lights index) and object indices. CookError for probes the format
// cannot hold (over pack::kMaxProbes, a grid index out of range, two sets of one owner).
std::vector<uint8_t> build_pack(const Scene& scene, const Layout& layout, const BakedMaps& maps,
                                const PackOptions& options, Report& report,
                                const ProbeBake* probes = nullptr);

}  // namespace lightpatch::cooker
