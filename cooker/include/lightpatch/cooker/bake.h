// The baker: direct and indirect (bounce) light into the base, contribution and shadow maps, and
// single scene states for reference. A bake is a set of light groups (bake_plan.h), each a unit of
// work with deterministic inputs and outputs: BakeSession plans them and traces what they share
// once, bake_group() bakes one, assemble() puts them together.
#pragma once

#include <cstdint>
#include <memory>
#include <string>
#include <vector>

#include "lightpatch/cooker/layout.h"
#include "lightpatch/cooker/maps.h"
#include "lightpatch/cooker/probes.h"
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

// How light is integrated. kGather: the cook's integrator, final gathering on coarse texels with
// the light map as radiance cache, multiple bounces by iteration and a geometry-guided denoiser
// (src/indirect/gather.h). kReference: the independent path tracer (reference_integrator.h),
// which bakes single states only (bake-state, accuracy), never packs.
enum class Integrator { kGather, kReference };
const char* integrator_name(Integrator i);
Integrator parse_integrator(const std::string& name);  // throws CookError

// Panes of the moving lights by default (BakeOptions::panes; docs/moving_lights.md, "Pane patches
// at a coarser level", has the table this and kDefaultPaneLevel were chosen by).
constexpr int kDefaultPanes = 64;
// The most BakeOptions::panes may ask for (the refinement may make 4x as many; pack_format.h
// kMaxPanes).
constexpr int kMaxPaneOption = 1024;
// The panes' storage level by default (BakeOptions::pane_level).
constexpr int kDefaultPaneLevel = 1;
// The finest anchor lattice BakeOptions::anchor_spacing may ask for (metres).
constexpr float kMinAnchorSpacing = 0.05f;

struct BakeOptions {
  Quality quality = Quality::kPreview;
  // Samples per texel for lights with a radius and emissive surfaces; 0 = the preset (draft 4,
  // preview 16, production 64).
  int area_samples = 0;
  // Receiver points per texel. Above 1, direct light is the mean over the texel's surface patch
  // (texel_footprint.h), so a shadow edge thinner than a texel is not aliased into dots: lights
  // without a radius get this many samples, lights with one and emissive surfaces spread their
  // area samples over the patch at no extra cost. 1: every sample leaves the texel's sample
  // point. 0 = the preset (draft 1, preview 4, production 9).
  int texel_samples = 0;
  int threads = 0;  // 0 = all cores
  uint64_t seed = 1;
  bool indirect = true;
  Integrator integrator = Integrator::kGather;
  // Final gathering, per preset: draft level 4 / 64 rays / 2 denoise passes, preview 2 / 256 / 2,
  // production 1 / 256 / 2. The level is the size (texels per axis, 1, 2, 4 or 8) of the coarse
  // texels on which bounce light is computed; denoise passes step 1, 2 and 4 coarse texels.
  int gather_rays = 0;     // rays per coarse texel; 0 = preset
  int indirect_scale = 0;  // 1, 2, 4 or 8; 0 = preset
  int denoise = -1;        // a-trous passes, 0..3; < 0 = preset
  // A 2x2 block that touches other geometry (a crate's foot) gathers per texel, half the rays a
  // texel, denoised among such texels (docs/accuracy.md, section (m)): preview's contact detail,
  // for about 1.3x its CPU time on the small inn. Off: every block as the preset has it.
  bool contact_texels = false;
  // The effect plan (DESIGN.md, "Only what the scene calls for"). false forces everything on, to
  // measure what the plan saves: bounce light for every light group, every object's change to it
  // solved, every light-object pair traced and kept (no reach or cone culling, no peak
  // threshold), every measured overlap correction kept.
  bool plan_effects = true;
  // > 0: the output step (BakedMaps::output_step, irradiance) instead of the scene's own (its
  // authored state's 99th percentile / 255, rounded down to a quarter octave). A level's step
  // pinned keeps every job's hash through edits that move its percentile (cook_jobs.h).
  float output_step = 0.0f;
  // Moving lights (docs/moving_lights.md): panes their bounce light is made of, before the
  // line-of-sight refinement (which may make up to 4x as many); 0 = kDefaultPanes.
  int panes = 0;
  // The level the panes' patches are stored at on the indirect map (pack_format.h, "Magnified
  // patches": 1/2^level of its resolution per axis, magnified by the runtime); < 0 =
  // kDefaultPaneLevel.
  int pane_level = -1;
  // > 0: the moving lights' bounce light is baked at anchors, light positions on a lattice of
  // this spacing (metres) over the scene's free space, instead of on panes (pack_format.h,
  // "Anchors"; docs/moving_lights.md, "Anchors"). Needs the moving lights to be point lights of
  // one range and radius. 0: panes.
  float anchor_spacing = 0.0f;
  // Light-map patches each stored at the coarsest level up to max_patch_level whose bilinear
  // magnification stays within level_tolerance 8-bit output steps of the full-resolution patch
  // at every texel (PackOptions, pack_builder.h); max_patch_level 0 keeps them all texel for
  // texel, < 0 = kDefaultMaxPatchLevel; level_tolerance <= 0 = kDefaultLevelTolerance.
  int max_patch_level = -1;
  float level_tolerance = 0.0f;
  // Texels of bounce light alone take this tolerance instead, and maps may be stored as their
  // direct and bounce parts (PackOptions::bounce_tolerance); <= 0 = kDefaultBounceTolerance
  // (kProductionBounceTolerance at production), and never below level_tolerance.
  float bounce_tolerance = 0.0f;
  // bake_state: also the moving lights' direct light (for pictures; the runtime's maps hold only
  // their bounce light, the game draws their direct light).
  bool moving_direct = false;
  // Light probes for moving things (probes.h): placed and lit after the maps are finalized, from
  // them; they change no map. Its seed and threads are set from the ones above.
  ProbeOptions probes;
};

// Throws CookError when the texel set's arrays disagree with its size or a light has a negative
// or non-finite value: what every integrator checks before it lights texels.
void check_bake_inputs(const Scene& scene, const TexelSet& texels);

// The final-gathering preset after overrides.
struct GatherPreset {
  int rays = 0;
  int level = 1;
  int denoise = 0;
  bool contact_texels = false;  // BakeOptions::contact_texels
};
GatherPreset gather_preset(const BakeOptions& options);

struct BakePlan;
struct Decision;
class GatherStore;  // src/indirect/integrator.h: gather rays kept between processes (cook jobs)

// One light group's maps (BakePlan::groups[group]): the unit of work of a bake.
struct GroupBake {
  size_t group = 0;
  FloatImage map;                                   // B (group 0) or C_l
  FloatImage indirect;                              // its block image (BakedMaps), or empty
  FloatImage direct;                                // its direct part (ShadowMap), or empty
  std::vector<ShadowMap> shadows;                   // a light group's kept S_ol
  std::vector<PairCorrectionMap> pair_corrections;  // a light group's kept corrections
  std::vector<StaticShadowMap> static_shadows;      // group 0's kept static shadows
  std::vector<Decision> decisions;                  // made while baking the group
  double seconds = 0.0;
};

class BakeSession {
 public:
  // Plans the bake; the first bake_group() or bake_state() traces what the groups share (the
  // gather rays), or loads them from `store` if it has them. Decisions of the plan go into
  // `report`. Throws CookError on inconsistent input.
  BakeSession(const Scene& scene, const Layout& layout, const TexelSet& texels,
              const Tracer& tracer, const BakeOptions& options, Progress& progress, Report& report,
              GatherStore* store = nullptr);
  ~BakeSession();
  BakeSession(const BakeSession&) = delete;
  BakeSession& operator=(const BakeSession&) = delete;

  const BakePlan& plan() const;
  // Traces (or loads) what the groups share now; the first bake otherwise does.
  void trace_shared(Progress& progress, Report& report) const;
  float output_step() const;
  // Bakes group `group` of plan().groups. Its maps depend on the scene, options and seed only.
  GroupBake bake_group(size_t group, Progress& progress, Report& report) const;
  // bake_group() of each of `groups` (any order, each at most once), the same maps and decisions
  // as each baked alone, in that order. Up to kGroupBatch at a time have their bounce light and
  // their objects' changes to it solved together: lights of one room then share each pass over
  // the gather rays, for the memory of that many groups' direct light at once.
  std::vector<GroupBake> bake_groups(const std::vector<size_t>& groups, Progress& progress,
                                     Report& report) const;
  static constexpr size_t kGroupBatch = 4;
  // The groups' maps as one BakedMaps, in plan order (every group exactly once).
  BakedMaps assemble(std::vector<GroupBake> groups, Report& report) const;
  // The moving lights and their panes into `maps` (BakedMaps::moving_lights, ::panes): clusters
  // the static texels and solves each pane's bounce light for irradiance 1 on it. No panes
  // without bounce light or without a moving light.
  void bake_panes(BakedMaps& maps, Progress& progress, Report& report) const;
  // One state baked directly (3 channels): every light at its state, the visible objects
  // present, their bounce light included; a moving light at the state's pose, its bounce light
  // only (its direct light too with BakeOptions::moving_direct).
  FloatImage bake_state(const StateSpec& state, Progress& progress, Report& report) const;

  struct Impl;  // the session's state (src/bake/session.h)
  const Impl& impl() const;

 private:
  std::unique_ptr<Impl> impl_;
};

// Bakes B, every C_l and every interacting S_ol (all groups of one session). With indirect light,
// C_l and S_ol have 3 channels (bounce is tinted by the albedos it met; the pack builder stores 1
// where the tint is below the output step), S_ol may be negative (bounce the object adds).
BakedMaps bake_maps(const Scene& scene, const Layout& layout, const TexelSet& texels,
                    const Tracer& tracer, const BakeOptions& options, Progress& progress,
                    Report& report);

// Bakes one state directly, as a conventional light mapper would (BakeSession::bake_state).
// Throws CookError on names in `state` that the scene does not have.
FloatImage bake_state(const Scene& scene, const Layout& layout, const TexelSet& texels,
                      const Tracer& tracer, const StateSpec& state, const BakeOptions& options,
                      Progress& progress, Report& report);

}  // namespace lightpatch::cooker
