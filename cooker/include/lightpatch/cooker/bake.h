// The baker: direct and indirect (bounce) light into the base, contribution and shadow maps, and
// single scene states for reference.
#pragma once

#include <cstdint>
#include <map>
#include <string>
#include <vector>

#include "lightpatch/cooker/layout.h"
#include "lightpatch/cooker/maps.h"
#include "lightpatch/cooker/progress.h"
#include "lightpatch/cooker/report.h"
#include "lightpatch/cooker/scene.h"
#include "lightpatch/cooker/state_spec.h"
#include "lightpatch/cooker/texels.h"
#include "lightpatch/cooker/tracer.h"

namespace lightpatch::cooker {

enum class Quality { kDraft, kPreview, kProduction };
const char* quality_name(Quality q);
Quality parse_quality(const std::string& name);  // throws CookError

// How bounce light is computed. kGather (default): final gathering on coarse texels with the
// light map as radiance cache, multiple bounces by iteration, a geometry-guided denoiser
// (gather.h). kPhotons: photons merged into virtual indirect lights (seed 004).
enum class Integrator { kGather, kPhotons };
const char* integrator_name(Integrator i);
Integrator parse_integrator(const std::string& name);  // throws CookError

struct BakeOptions {
  Quality quality = Quality::kPreview;
  int area_samples =
      0;            // samples per texel for lights with a radius / emissive surfaces; 0 = preset
  int threads = 0;  // 0 = all cores
  uint64_t seed = 1;
  // Indirect light (photons -> virtual indirect lights, seed 004). Presets per quality:
  //   draft 30k photons / 192 VPLs / bias 1, preview 120k / 512 / 1, production 500k / 2048 / 0.5.
  // Bias 1 with A the disc the merged photons cover gives a disc emitter's exact on-axis
  // irradiance, Phi / (pi r^2 + A); it darkens receivers within ~sqrt(bias A / pi) of a VPL
  // (near corners), so more, smaller VPLs lose less energy.
  bool indirect = true;
  Integrator integrator = Integrator::kGather;
  // Final gathering, per preset: draft level 4 / 64 rays / 2 denoise passes, preview 2 / 256 / 2,
  // production 2 / 1024 / 1 (at most 3 passes: steps of 1, 2 and 4 coarse texels). The level is the
  // coarse texel size (1, 2, 4 or 8 light-map texels per axis) at which bounce light is computed.
  int gather_rays = 0;      // rays per coarse texel; 0 = preset
  int indirect_level = 0;   // 1, 2, 4 or 8; 0 = preset
  int denoise = -1;         // a-trous passes, 0..3; < 0 = preset
  int photons = 0;          // photons emitted for the whole scene (split by power); 0 = preset
  int virtual_lights = 0;   // virtual indirect lights for the whole scene; 0 = preset
  float area_bias = -1.0f;  // cosA cosB / (pi r^2 + bias A); < 0 = preset
  // The effect plan (DESIGN.md, "Only what the scene calls for"). false forces everything on, to
  // measure what the plan saves: indirect light for every light group that emits photons with
  // every object's bounce traced, every light-object pair traced and kept (no reach or cone
  // culling, no peak threshold), every measured overlap correction kept.
  bool plan_effects = true;
};

// The preset's photons, virtual lights and area bias (after applying any overrides in `options`).
struct IndirectPreset {
  int photons = 0;
  int virtual_lights = 0;
  float area_bias = 0.0f;
};
IndirectPreset indirect_preset(const BakeOptions& options);

// The final-gathering preset after overrides.
struct GatherPreset {
  int rays = 0;
  int level = 1;
  int denoise = 0;
};
GatherPreset gather_preset(const BakeOptions& options);

// Bakes B, every C_l and every interacting S_ol. With indirect light, C_l and S_ol have 3 channels
// (bounce is tinted by the albedos it met; the pack builder stores 1 where the tint is below the
// output step), S_ol may be negative (bounce the object adds). Effect, light and pair decisions
// go into `report`.
BakedMaps bake_maps(const Scene& scene, const Layout& layout, const TexelSet& texels,
                    const Tracer& tracer, const BakeOptions& options, Progress& progress,
                    Report& report);

// Bakes one state directly, as a conventional light mapper would: all lights at their state
// (static ones as authored), visible objects present, bounce light through them (the same
// photons as bake_maps, so a single-object state equals B + sum f_l (C_l - S_ol) to rounding).
// 3 channels. Throws CookError on names
// in `state` that the scene does not have.
FloatImage bake_state(const Scene& scene, const Layout& layout, const TexelSet& texels,
                      const Tracer& tracer, const StateSpec& state, const BakeOptions& options,
                      Progress& progress, Report& report);

}  // namespace lightpatch::cooker
