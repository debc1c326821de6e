// The CPU half of the GLES runtime: decides, frame by frame, which patch groups are drawn where
// and with which factor, within a budget of texels written. No GL here (cross-compiled for devices
// and unit-tested without a GPU); the runtime executes the plan through a DrawSink.
//
// Model (DESIGN.md, "The method in one screen"): the map is
//   L = B + sum_l f_l * (C_l - sum_{o visible} S_ol + sum_{a<b visible} P_lab)
// where every group's patches carry their own sign (shadows are subtracted, kFlagNegative flips).
// A draw of a group with factor f adds f * (signed decoded patch values) to a target.
//
// Targets: the light map the game samples (kLightMap) and one intermediate (kIntermediate).
//  * Full rebuild: clear the intermediate, draw every active group with the factors of a snapshot
//    of the wanted state, then present (the intermediate and the light map swap roles). Steps are
//    group draws (split into patch ranges when a group exceeds the budget); their cost in texels
//    (sum of patch areas, the clear: width*height) is known before they run. The game only ever
//    samples a complete map.
//  * Incremental change (paper Alg. 8-9): a light's factor changes by d -> draw its contribution,
//    visible-shadow and visible-pair groups with factor d into the light map; an object toggles ->
//    draw its shadow/pair groups of lit lights with +-f_l. All draws of one change run in the same
//    update, so a change is visible whole. The thesis's "2m < n" rule becomes: incremental when its
//    cost m (texels, one signed delta draw per group) is below the rebuild's cost n and fits in one
//    frame's budget; otherwise the change starts a rebuild.
//  * Changes made while a rebuild runs wait (they stay pending, nothing is lost) and are applied
//    incrementally against the presented state once the rebuild is presented.
//  * Drift: each incremental group draw can add half-float rounding (unit roundoff 2^-11) of the
//    map's magnitude bound M = |B| + sum_l max_c|f_l| * |groups of l|. The planner keeps that error
//    bound and starts a rebuild when it exceeds drift_tolerance_ulps * 2^-11 * M.
//
// Budget rule: update(budget) never writes more than `budget` texels, except that a single step
// that alone exceeds the whole budget (one patch larger than the budget, or the clear of a light
// map larger than the budget) runs alone in a frame of its own; such frames are counted in
// FrameStats::oversize_steps. Memory: everything is allocated in init(); update() allocates
// nothing.
#pragma once

#include <cstdint>

#include "lightpatch/pack_view.h"
#include "lightpatch/status.h"

namespace lightpatch {

enum class DrawTarget : uint8_t { kIntermediate, kLightMap };

// What the planner asks the GPU side to do. Calls come in execution order.
class DrawSink {
 public:
  virtual ~DrawSink() = default;
  virtual void clear_intermediate() = 0;
  // Draws patches [first_patch, first_patch + patch_count) (pack indices, all of one group) into
  // `target`, each multiplied by `factor` (linear RGB) and its own sign.
  virtual void draw(DrawTarget target, uint32_t group, uint32_t first_patch, uint32_t patch_count,
                    const float factor[3]) = 0;
  // The intermediate now holds a complete map: it becomes the light map (and the old light map the
  // next intermediate).
  virtual void present() = 0;
};

struct PlannerLimits {
  // Rebuild when the accumulated incremental error bound exceeds this many half-float ulps of the
  // map's magnitude bound.
  float drift_tolerance_ulps = 32.0f;
};

struct FrameStats {
  uint64_t frame = 0;                  // update() calls so far
  uint64_t texels = 0;                 // texels written this frame (clears included)
  uint32_t draws = 0;                  // draw calls this frame
  uint32_t pending_changes = 0;        // lights/objects whose wanted state is not yet presented
  uint32_t oldest_pending_frames = 0;  // age in frames of the oldest pending change
  uint32_t completed_changes = 0;      // changes that became visible this frame
  uint32_t max_latency_frames = 0;     // largest latency among them (1 = visible in the next frame)
  bool rebuild_active = false;         // a rebuild is in progress (after this frame)
  bool presented = false;              // a rebuild was presented this frame
  uint32_t oversize_steps = 0;         // 1 when this frame ran a single step larger than the budget
  uint64_t rebuild_remaining_texels = 0;  // cost left in the running rebuild
  float error_bound = 0.0f;               // accumulated incremental error bound (irradiance units)
};

class Planner {
 public:
  Planner() = default;
  ~Planner();
  Planner(const Planner&) = delete;
  Planner& operator=(const Planner&) = delete;

  // Precomputes per-group costs and per-light/per-object group indices. The wanted state starts at
  // the pack's authored defaults and nothing is presented: the first update()s run a full rebuild.
  Status init(const PackView& pack, const PlannerLimits& limits, Error* error);

  // Wanted state (validated: index in range, finite, >= 0). Takes effect in later update()s.
  Status set_light(uint32_t light, bool on, const float color[3], float intensity);
  Status set_object_visible(uint32_t object, bool visible);
  bool light_on(uint32_t light) const { return on_[light] != 0; }
  void light_color(uint32_t light, float out[3]) const;
  float light_intensity(uint32_t light) const { return intensity_[light]; }
  bool object_visible(uint32_t object) const { return want_visible_[object] != 0; }

  // Runs steps worth at most `budget_texels` (see the budget rule above) through `sink`.
  void update(uint64_t budget_texels, DrawSink& sink);
  // Forgets everything presented (context loss): the next update()s rebuild the wanted state.
  void invalidate();
  // Starts a rebuild now (a no-op while one is running).
  void request_rebuild();

  // The presented state: what the light map holds (valid once map_ready()).
  void shown_factor(uint32_t light, float out[3]) const;
  bool shown_visible(uint32_t object) const { return shown_visible_[object] != 0; }

  const FrameStats& stats() const { return stats_; }
  bool map_ready() const { return ready_; }
  bool idle() const;  // presented, nothing pending, no rebuild running

  // Costs in texels, known before anything runs.
  uint64_t group_texels(uint32_t group) const { return group_texels_[group]; }
  uint64_t clear_texels() const { return clear_texels_; }
  uint64_t rebuild_texels() const;  // the full rebuild of the wanted state, clear included
  uint64_t light_change_texels(uint32_t light) const;    // for the presented visibility
  uint64_t object_change_texels(uint32_t object) const;  // for the presented factors

 private:
  struct Factor {
    float rgb[3];
  };
  bool group_active(uint32_t group, const Factor* factors, const uint8_t* visible) const;
  float magnitude(const Factor* factors) const;
  void start_rebuild();
  bool run_rebuild(uint64_t budget, DrawSink& sink);
  bool apply_light_change(uint32_t light, uint64_t budget, DrawSink& sink, bool* started);
  bool apply_object_change(uint32_t object, uint64_t budget, DrawSink& sink, bool* started);
  void emit(DrawSink& sink, DrawTarget target, uint32_t group, uint32_t first, uint32_t count,
            const float factor[3], uint64_t texels);
  void complete(uint64_t* since);
  void want_factor(uint32_t light, float out[3]) const;

  const PackView* pack_ = nullptr;
  PlannerLimits limits_;
  uint32_t light_count_ = 0, object_count_ = 0, group_count_ = 0;
  uint64_t clear_texels_ = 0;
  uint64_t* group_texels_ = nullptr;  // [group]
  uint64_t* patch_prefix_ = nullptr;  // [patch + 1] prefix sums of patch areas
  float* group_max_ = nullptr;        // [group] max |decoded value|
  float base_max_ = 0.0f;
  float* light_max_ = nullptr;         // [light] sum of group_max_ of its groups
  int32_t* contribution_ = nullptr;    // [light] group or -1
  uint32_t* light_first_ = nullptr;    // [light + 1] range in light_groups_
  uint32_t* light_groups_ = nullptr;   // shadow/pair groups of each light
  uint32_t* object_first_ = nullptr;   // [object + 1] range in object_groups_
  uint32_t* object_groups_ = nullptr;  // shadow/pair groups naming each object

  // Wanted state.
  uint8_t* on_ = nullptr;
  Factor* color_ = nullptr;
  float* intensity_ = nullptr;
  uint8_t* want_visible_ = nullptr;
  // Presented state (what the light map holds) and the running rebuild's snapshot.
  Factor* shown_ = nullptr;
  uint8_t* shown_visible_ = nullptr;
  Factor* build_ = nullptr;
  uint8_t* build_visible_ = nullptr;
  // Frame at which each pending change was made (kNotPending when none).
  uint64_t* light_since_ = nullptr;
  uint64_t* object_since_ = nullptr;

  bool ready_ = false;
  bool rebuilding_ = false;
  bool rebuild_cleared_ = false;
  uint32_t rebuild_group_ = 0;  // next group to draw
  uint32_t rebuild_patch_ = 0;  // next patch within it (patch-range splitting)
  uint64_t rebuild_left_ = 0;
  float error_bound_ = 0.0f;
  uint64_t frame_ = 0;
  FrameStats stats_;
  void* block_ = nullptr;  // one allocation holding every array above
};

}  // namespace lightpatch
