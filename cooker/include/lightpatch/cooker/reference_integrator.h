// The reference integrator (DESIGN.md, Command line: `bake-state --integrator reference`): the
// independent judge of every accuracy claim. Unbiased Monte Carlo path tracing of the irradiance
// at every valid texel of a TexelSet (the baker's texel positions and normals): cosine-weighted
// hemisphere sampling, next-event estimation to every light at every vertex with multiple
// importance sampling (power heuristic) for lights with a size (the sphere of a light with a
// lightRadius, direct_light.h's SphereView) and emissive triangles, Lambertian surfaces with the
// baker's albedo (base colour factor x texture at TEXCOORD_0), Russian roulette on the albedo.
// Every path's random numbers are hashed from (seed, texel, sample, bounce), so the result is the
// same on any thread count. Samples run in passes of 16, progressively: progress reports the
// convergence after each power of two, where an optional noise target can stop it. The
// per-texel spread of the samples gives a standard-error map beside the irradiance map. A texel's
// irradiance is the mean over the visible part of its patch: a path whose first ray meets the back
// of a static surface started inside solid geometry and is dropped (ReferenceBake).
#pragma once

#include <cstdint>
#include <vector>

#include "lightpatch/cooker/maps.h"
#include "lightpatch/cooker/progress.h"
#include "lightpatch/cooker/report.h"
#include "lightpatch/cooker/scene.h"
#include "lightpatch/cooker/state_spec.h"
#include "lightpatch/cooker/texels.h"
#include "lightpatch/cooker/tracer.h"

namespace lightpatch::cooker {

constexpr int kDefaultReferenceSamples = 256;
// Bounces after which a path stops even if Russian roulette has not ended it (only walls of
// albedo ~1 get there: at albedo 0.99 a path outlives 1024 bounces with probability 3e-5).
constexpr int kReferenceMaxBounces = 1024;

struct ReferenceOptions {
  int samples = kDefaultReferenceSamples;  // paths per texel, >= 2 (the spread needs two)
  // > 0: stop early, at the first power of two of samples from 64 on at which the noise's
  // relative RMSE (ReferenceBake::rel_rmse_noise) is at most this; `samples` is then the cap.
  double target_noise = 0.0;
  uint64_t seed = 1;
  int threads = 0;  // 0 = all cores
  // A texel's irradiance is its mean over its surface patch (texel_footprint.h: each path leaves
  // its own point of it), as the cook's preview and production presets define it; false: at its
  // sample point, as a cook with one texel sample (draft) does.
  bool texel_patch = true;
  // Empty: every valid texel. Otherwise one flag per texel of the set: only the valid texels
  // flagged are traced (a region's reference at a fraction of the cost; the others stay 0 and are
  // left out of the noise figures). Footprints still come from the whole set, so a flagged texel
  // is defined as in a full bake.
  std::vector<uint8_t> region;
  // A moving light (at the state's pose) lights the texels through bounces only, as a pack holds
  // it (its direct light is the game's); true: its direct light too (BakeOptions::moving_direct).
  bool moving_direct = false;
};

struct ReferenceBake {
  FloatImage map;        // irradiance (RGB, the lights' units), valid texels only
  FloatImage std_error;  // per texel and channel: the standard error of `map`, same units
  int samples = 0;       // traced per texel (fewer than asked when the noise target stopped it)
  uint64_t rays = 0;
  double seconds = 0.0;
  // Mean over the texels that matter (max channel at least 1 % of its 99th percentile over valid
  // texels) of |std_error| / |map| (RGB norms).
  double mean_rel_std_error = 0.0;
  // sqrt(sum std_error^2 / sum map^2) over valid texels and channels: the relative RMSE that the
  // reference's own noise alone gives (the accuracy sweep's rel_rmse floor).
  double rel_rmse_noise = 0.0;
  // Paths whose first ray met the back of a static surface started inside solid geometry and are
  // not samples (the texel's value is the mean of its others): their share of all paths, and the
  // texels with none left (never seen: under a wall, inside a table top), which stay 0.
  double inside_path_fraction = 0.0;
  uint64_t inside_texels = 0;
};

// Bakes one scene state (lights on/off/colour/intensity and objects visible or not, resolved by
// resolve_state(): the same rules and errors as bake_state) by path tracing. Throws CookError on
// names the scene lacks. Fills report["reference"] (samples, rays, seconds, rays per second, the
// two noise figures) and the stage time "bake.reference".
ReferenceBake bake_reference(const Scene& scene, const TexelSet& texels, const Tracer& tracer,
                             const StateSpec& state, const ReferenceOptions& options,
                             Progress& progress, Report& report);

}  // namespace lightpatch::cooker
