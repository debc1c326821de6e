// Semi-dynamic light probes (pack_format.h, "Light probes"): points in the free space of the
// scene, placed on a grid trimmed to where moving things can be plus the probes the scene places
// (a node with extras "lightProbe": true), each lit per owner exactly like the maps (base, a
// light's contribution, a light's shadow of an object, an object's static shadow), as order-2
// irradiance SH. The maps of every group, finalized, are the radiance cache a probe gathers from:
// a probe's value for a set is the direct light of the set's light(s) at the probe plus the light
// its surfaces reflect towards it (albedo / pi times the set's map at the surface seen). The
// moving lights' panes have a contribution set each, their bounce light only: the pane's members
// at irradiance 1 plus its map, reflected (a moving light's direct light is the game's).
#pragma once

#include <glm/glm.hpp>

#include <array>
#include <cstdint>
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
#include "lightpatch/pack_format.h"

namespace lightpatch::cooker {

struct ProbeOptions {
  bool enabled = true;
  // Grid spacing in metres; 0 = auto (1 m, coarser where the scene's bounds would need more than
  // kMaxAutoGridPoints grid points).
  float spacing = 0.0f;
  // Gather rays per probe; 0 = the preset (kProbePresetRays). bake_probes() needs it > 0.
  int rays = 0;
  // In BakeOptions::probes, the cook sets these two from the bake's own.
  uint64_t seed = 1;
  int threads = 0;  // 0 = all cores
};
constexpr uint32_t kMaxAutoGridPoints = 65536;

struct ProbeBake {
  struct Probe {
    glm::vec3 position{0.0f};
    float reach[6] = {0, 0, 0, 0, 0, 0};  // +X, -X, +Y, -Y, +Z, -Z (pack::ProbeRecord)
    std::string name;                     // node name of a placed probe, empty on the grid
  };
  std::vector<Probe> probes;
  bool has_grid = false;
  glm::vec3 grid_origin{0.0f};
  float grid_spacing = 0.0f;
  glm::ivec3 grid_size{0};
  std::vector<uint32_t> grid_index;  // per grid point, x fastest; pack::kNone32 where none
  struct Set {
    uint16_t kind = pack::kGroupBase;  // base, contribution, shadow or static shadow
    // The pack's light index, or -1: a BakedMaps::lights index, or for pane k of BakedMaps::panes
    // lights.size() + moving_lights.size() + k (pack_builder.cpp's light table).
    int light = -1;
    int object = -1;                        // Scene::objects index (the pack's object index), or -1
    std::vector<pack::ProbeEntry> entries;  // sorted by probe, each probe once
  };
  std::vector<Set> sets;  // at most one per owner, any order (the pack builder sorts)
  bool empty() const { return probes.empty(); }
};

// Gather rays per probe for a preset's ProbeOptions::rays = 0 (Quality as an int: draft 0,
// preview 1, production 2).
constexpr int kProbePresetRays[3] = {256, 512, 1024};

// The grid over the scene's bounds (ProbeOptions::spacing), less the points inside solid
// geometry (more than a quarter of 64 rays from the point meet the back of a surface), then the
// scene's placed probes (Scene::probes), each with its reach. Empty when !options.enabled.
// Throws CookError for a spacing that is not finite and >= 0, or that needs more grid points or
// probes than the pack holds (pack_format.h).
ProbeBake place_probes(const Scene& scene, const Tracer& tracer, const ProbeOptions& options,
                       Report& report);

// Lights every probe of `probes` per set from the finalized maps of the cook (options.rays > 0
// gather rays per probe), filling probes.sets. Deterministic for options.seed on any thread count.
void bake_probes(ProbeBake& probes, const Scene& scene, const Layout& layout,
                 const TexelSet& texels, const Tracer& tracer, const BakedMaps& maps,
                 const ProbeOptions& options, Progress& progress, Report& report);

// Every probe's irradiance SH for one state directly, from that state's finalized map (the map
// bake-state writes for it) and its lights, with the same rays as bake_probes: what the runtime's
// sum of the sets for that state must give. The moving lights have no direct samples here either
// (their direct light at a probe is the game's), but their first bounce from the surfaces the
// probe sees is in the probes: with a moving light on, `state_map` must hold its direct light on
// the surfaces too (BakeOptions::moving_direct, `bake-state --moving-direct`), at the state's pose;
// without it the probes miss the light the pane sets' members bring.
std::vector<std::array<float, pack::kProbeShCount * 3>> bake_state_probes(
    const ProbeBake& probes, const Scene& scene, const Layout& layout, const TexelSet& texels,
    const Tracer& tracer, const FloatImage& state_map, const StateSpec& state,
    const ProbeOptions& options);

}  // namespace lightpatch::cooker
