// Bounce light from the stored gather rays (gather.h): a light group's indirect irradiance, the
// change a set of present objects makes to it, and one scene state's, each a Neumann series of
// sparse gathers; a geometry-guided denoiser and the magnification of coarse maps into the light
// map. Everything here is linear in the light and independent of the values it filters, so the
// semi-dynamic decomposition (C_l, S_ol = C_l - T_ol, pair corrections) stays exact.
#pragma once

#include <glm/glm.hpp>

#include <cstdint>
#include <functional>
#include <vector>

#include "indirect/gather.h"
#include "lightpatch/cooker/maps.h"
#include "lightpatch/cooker/texels.h"

namespace lightpatch::cooker {

// Irradiance (or radiance source) per coarse texel, RGB.
using CoarseMap = std::vector<glm::vec3>;

// Per tile (GatherOperator::kTile), the receivers whose rays reach it, static or object hits,
// grouped by the shallowest level that leaves out their first ray there, so that a level's
// receivers of a tile are a prefix. A gather visits the receivers listed under the tiles that
// have light: finer than GatherOperator::sources, which answers for a whole tile of receivers;
// any other receiver's sum is exactly 0. Derived from the operator alone.
struct GatherReach {
  std::vector<uint32_t> offset;     // [tile * kLevels + class] -> into `receivers`
  std::vector<uint32_t> receivers;  // ascending within each (tile, class)
  // GatherOperator::sources inverted: per tile, the tiles whose rays reach it, so that a source
  // on a few tiles (a pane, a shadow) finds the tiles it lights without scanning every tile's
  // sources.
  std::vector<uint32_t> target_offset;  // [tile] -> into `targets`
  std::vector<uint32_t> targets;
};
GatherReach gather_reach(const GatherOperator& op, int threads);

// The near hits' first-bounce source (GatherOperator::near): (near hit index, the albedo where it
// lands times the direct light there), each index at most once, in any order; those not listed
// read 0.
using NearSource = std::vector<std::pair<uint32_t, glm::vec3>>;

// Derived from the operator for the near hits' sums, which then visit only the hits whose source
// or cache value is not 0: each near hit's receiver, and the near hits by the coarse texel they
// land on.
struct NearIndex {
  std::vector<uint32_t> receiver;       // near hit -> its coarse texel
  std::vector<uint32_t> by_hit_offset;  // coarse texel -> [offset, next) into by_hit
  std::vector<uint32_t> by_hit;         // near hits, by the coarse texel they land on
};
NearIndex near_index(const GatherOperator& op);

struct SolveOptions {
  // Bounce terms below this (irradiance, the map's units) are dropped: the series stops when a
  // bounce adds less everywhere. A fraction of the group's significance threshold.
  float tolerance = 0.0f;
  int max_bounces = 256;
  int threads = 1;
  const GatherReach* reach = nullptr;  // gather_reach(op): visit fewer receivers; null: tiles only
  const NearIndex* near = nullptr;     // near_index(op): required with a NearSource
};

struct SolveStats {
  int bounces = 0;
  uint64_t gathers = 0;  // stored rays read
};

// The radiance source of fine irradiance: per coarse texel, the mean of albedo * value(texel)
// over its members (value: fine texel index -> RGB irradiance).
template <typename Value>
CoarseMap coarse_source_of(const GatherOperator& op, const TexelSet& texels, const Value& value) {
  const CoarseGrid& g = op.grid;
  CoarseMap out(g.size(), glm::vec3(0.0f));
  for (uint32_t c = 0; c < g.size(); ++c) {
    glm::vec3 s(0.0f);
    for (uint32_t i = g.member_offset[c]; i < g.member_offset[c + 1]; ++i) {
      const uint32_t t = g.members[i];
      s += texels.albedo[t] * value(size_t(t));
    }
    out[c] = s / float(g.member_count(c));
  }
  return out;
}

// The same for a fine map (3 channels, or 1 for grey).
CoarseMap coarse_source(const GatherOperator& op, const TexelSet& texels, const FloatImage& d);

// A series' terms by the rays they read (GatherOperator::level_of): the first bounce, the second,
// and the rest together. Their sum is the indirect irradiance.
struct Bounces {
  CoarseMap first, second, rest;
  CoarseMap total() const;
};

// Indirect irradiance with the objects `present` (one byte per Scene object; empty: none) in
// place, the series of I = G_V (source + albedo * I) bounce by bounce. `near` (null: none) is
// what the near hits' first bounce reads instead of `source` at their texel.
Bounces solve_indirect(const GatherOperator& op, const std::vector<uint8_t>& present,
                       const CoarseMap& source, const SolveOptions& options,
                       SolveStats* stats = nullptr, const NearSource* near = nullptr);

// solve_indirect() of several sources with no object present, the same bits as each solved
// alone, `options.threads` wide: sources whose receivers overlap enough share each bounce's pass
// over the stored rays (gather_many), up to kChangeBatch. `near` (empty, or one per source, each
// may be null) as solve_indirect's. `tolerance` (empty: options.tolerance for every source) one
// per source, each as options.tolerance would be alone. `stats` (may be null) receives one entry
// per source.
std::vector<Bounces> solve_indirect_many(const GatherOperator& op,
                                         const std::vector<CoarseMap>& sources,
                                         const std::vector<const NearSource*>& near,
                                         const SolveOptions& options,
                                         std::vector<SolveStats>* stats = nullptr,
                                         const std::vector<float>& tolerance = {});

// What a group sends on with no object present, by the series term that reads it: its direct
// light's radiance source (read by the first bounce), albedo * its first bounce (read by the
// second), albedo * its later bounces (read by the rest).
struct EmptyRadiance {
  CoarseMap direct, first, later;
};
EmptyRadiance empty_radiance(const GatherOperator& op, const CoarseMap& source,
                             const Bounces& bounces);

// What the objects `present` change in a group's indirect light, I(none) - I(present), given what
// the group sends on with no object present and the radiance source of the direct light the
// objects block (`direct_change`, from the fine change D(none) - D(present); `near_change` the
// same at the near hits, or null). Term by term the same series as solve_indirect's, so the
// change is exact to the terms each drops. Only the receivers that can see a change are visited.
CoarseMap solve_change(const GatherOperator& op, const std::vector<uint8_t>& present,
                       const EmptyRadiance& empty, const CoarseMap& direct_change,
                       const SolveOptions& options, SolveStats* stats = nullptr,
                       const NearSource* near_change = nullptr);

// The most changes solve_changes() solves side by side.
constexpr size_t kChangeBatch = 8;

// One change for solve_changes(): solve_change()'s arguments, with the group it changes (`empty`,
// which must outlive the solve) and its series' tolerance (SolveOptions::tolerance).
struct ChangeJob {
  const std::vector<uint8_t>* present = nullptr;
  CoarseMap direct_change;
  const NearSource* near_change = nullptr;
  const EmptyRadiance* empty = nullptr;
  float tolerance = 0.0f;
};

// solve_change() of every job, the same bits as each solved alone, `options.threads` wide
// (`options.tolerance` is not read: each job has its own). Jobs may change different groups.
// Jobs whose receivers overlap enough are solved side by side, up to kChangeBatch, each bounce's
// gathers sharing one pass over the stored rays (a pass per job read them once for each); such
// batches run in parallel. Jobs with the same objects present (one object's change to several
// lights) share the rays those objects change. `stats` (may be null) receives one entry per job;
// `done` (may be empty) is called with the number of jobs each batch finished, from the thread
// that solved it.
std::vector<CoarseMap> solve_changes(const GatherOperator& op, const std::vector<ChangeJob>& jobs,
                                     const SolveOptions& options,
                                     std::vector<SolveStats>* stats = nullptr,
                                     const std::function<void(size_t)>& done = {});

// The largest first-order change that objects `present` make where they block no direct light:
// per receiver, what its rays that now end on them saw before against what they see now. A cheap
// bound on whether solve_change() is worth running.
float first_change_peak(const GatherOperator& op, const std::vector<uint8_t>& present,
                        const EmptyRadiance& empty);

// How much nearby geometry fills each coarse texel's hemisphere: the mean over its gather rays of
// exp(-d / (kNearFieldSpacings * the coarse texels' spacing)), d the distance to what the ray hits
// (0 for a miss or a back face). High where a surface meets another (a floor at a wall's foot,
// under a shelf, a wall behind a panel), where bounce light falls off within a few texels
// (ambient occlusion): the denoiser keeps such texels apart from open ones. From geometry only:
// what a ray meets first with every object present (an object in front of the static hit counts),
// the same guide for every map and every state, so the filter stays linear and the decomposition
// exact.
constexpr float kNearFieldSpacings = 4.0f;
// The denoiser's near-field scale: at least twice the worst-case standard error of a mean of N
// values in [0, 1] (0.5 / sqrt(N)), so that the guide's own noise does not stop the filter on open
// surfaces at low ray counts.
constexpr float kNearFieldSigma = 0.05f;
float near_field_sigma(int rays);
// Gathered per texel (level 1), the denoiser's passes after the first blend two texels by
// exp(-(near / kOpenNearField)^2) of the less open one: fully on open surfaces (a ceiling, the
// middle of a floor), hardly at contacts and creases (near 0.3 and more). Open surfaces are where
// bounce light is smooth and where a gather ray that lands on a small, very bright surface (a
// candle's top) makes a dot; contacts are where per-texel detail is real. On blocks (preview,
// draft) the near field spans several texels, most blocks of a small room count as contacts, and
// the magnification already spreads such hits: they filter as before. Chosen on the small inn, the
// room and the thin panel at production (docs/accuracy.md, section (h)): 0.10 to 0.25 gave the
// same.
constexpr float kOpenNearField = 0.15f;
std::vector<float> near_field(const GatherOperator& op);

// Edge-avoiding a-trous filter over `levels` passes (steps 1, 2, 4, ... blocks), weights from the
// coarse texels' charts, normals, planes and near field (`near`, near_field(); null: not used;
// per texel, passes after the first also by kOpenNearField) only, never from values: linear, so
// it commutes with the decomposition. 0 levels: no filtering. A coarse texel split from a block
// at a contact (CoarseGrid::fine) is filtered with other such texels only.
void denoise(const CoarseGrid& grid, int levels, CoarseMap& map,
             const std::vector<float>* near = nullptr, float near_sigma = kNearFieldSigma);

// denoise()'s weights, which depend on the grid only: computed once, they filter every map of
// a cook the same, bit for bit, without the exponentials each time.
struct DenoiseWeights {
  static constexpr int kTaps = 9;  // 3 x 3
  int levels = 0;
  std::vector<float> weight;  // [level][coarse texel][kTaps], row by row from (-1, -1)
  std::vector<float> total;   // [level][coarse texel]: the sum of its weights
};
DenoiseWeights denoise_weights(const CoarseGrid& grid, int levels,
                               const std::vector<float>* near = nullptr,
                               float near_sigma = kNearFieldSigma);
void denoise(const CoarseGrid& grid, const DenoiseWeights& weights, CoarseMap& map);

// Adds the coarse map, magnified bilinearly within each chart, to `fine` (3 channels), scaled.
void add_magnified(const CoarseGrid& grid, const TexelSet& texels, const CoarseMap& map,
                   FloatImage& fine, float scale = 1.0f);

// The largest finite value add_magnified() adds to a zero map at scale 1 (0 if none is larger),
// without the light-map-sized map.
float magnified_peak(const CoarseGrid& grid, const TexelSet& texels, const CoarseMap& map);

// The pack's indirect map of a coarse map, for a layout on s x s blocks (Layout::align = s > 1,
// pack_format.h "Two target maps"): each block holds the mean, over its valid texels, of their
// coarse texels' values; a block with none (a chart's ring) the mean of its filled 8-neighbours
// in the same region (any region for a block outside every region), two rings out, so that
// magnifying at a chart's edge reads that chart's own light. (width / s) x (height / s) blocks,
// 3 channels. Linear in the map.
FloatImage block_image(const CoarseGrid& grid, const TexelSet& texels, int s, const CoarseMap& map);

// Largest component of any coarse value.
float peak(const CoarseMap& map);

}  // namespace lightpatch::cooker
