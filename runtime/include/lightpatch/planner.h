// The CPU half of the runtime: decides, frame by frame, which patch groups are drawn with which
// factor, within a budget of texels written. No GL here (cross-compiled for devices and
// unit-tested without a GPU); a DrawSink executes the plan (GLES draws, or the CPU).
//
// Model (group_rules.h): the map is
//   L = B + sum_l f_l * (C_l - sum_{o visible} S_ol + sum_{a<b visible} P_lab)  (+ static shadows)
// and a draw of a group with factor f adds f * (signed decoded patch values) to the accumulator.
//
// Two stages: the accumulator, where every draw lands, and the presented map the game samples,
// which a sink writes from the accumulator only when a change or a rebuild is complete (present
// steps). Presenting clamps at zero: the 8-bit quantization of B, C and S does not cancel exactly
// where a visible object's shadow removes all of a light (a few steps of the light's scale, of
// either sign, where bake-state gives 0), and light is never negative.
// Two targets: a pack with an indirect map (pack_view.h) has an accumulator and a presented map
// for each of the light map and the indirect map. Every draw and present step covers patches of
// one group and one target (a group's draw is split into its light-map and its indirect-map
// range), and every cost is counted in texels of the target written: an indirect patch costs its
// own (coarse) texels. The clear and the whole-map present cover both maps (width * height plus
// indirect_width * indirect_height texels each).
//  * Full rebuild: clear the accumulator, draw every active group with the factors of a snapshot
//    of the wanted state, then present the whole map. Steps are group draws (split into patch
//    ranges when a group exceeds the budget); their cost in texels (sum of patch areas; the clear
//    and the whole-map present: the maps' texels each) is known before they run. The game only ever
//    samples a complete map: the presented map keeps the previous state until the present step.
//  * Incremental change (paper Alg. 8-9): a light's factor changes by d -> draw its contribution,
//    visible-shadow and visible-pair groups with factor d; an object toggles -> draw its
//    shadow/pair groups of lit lights with +-f_l; then present each drawn group's patches. All
//    steps of one change run in the same update, so a change is visible whole. Its cost m (texels
//    drawn and presented, twice the groups' areas) must fit in one frame's budget and be below the
//    rebuild's cost n (the thesis's "2m < n" rule, in texels); otherwise the change starts a
//    rebuild.
//  * Changes made while a rebuild runs wait (they stay pending, nothing is lost) and are applied
//    incrementally once the rebuild is presented.
//  * Drift: every draw into the accumulator rounds. With u the target's unit roundoff (a full ulp
//    where it truncates; set_precision()), a draw adds at most u times the texel's running
//    magnitude. The planner bounds the error of the incremental history relative to each texel's
//    magnitude M = |B| + sum_l |f_l| * A_l (A_l: the sum of |values| of all of light l's groups),
//    channel by channel: draws since the last rebuild are counted against the factors in force
//    when they ran, so a light dimmed or turned off after many draws raises the bound by the
//    ratio (a light below 1/256 of its peak since the last rebuild counts as 1/256 of it: there
//    its own 8-bit quantization step is larger than the rounding). A change that would take the
//    bound past drift_tolerance starts a rebuild instead; on a half-float target that truncates
//    this is what keeps large terms from being subtracted.
//
// Budget rule: update(budget) never writes more than `budget` texels, except that a single step
// that alone exceeds the whole budget (one patch larger than the budget, or the clear or present
// of a light map larger than the budget) runs alone in a frame of its own; such frames are counted
// in FrameStats::oversize_steps. Memory: everything is allocated in init(); update() allocates
// nothing.
#pragma once

#include <cstdint>

#include "lightpatch/pack_view.h"
#include "lightpatch/status.h"

namespace lightpatch {

// What the planner asks a sink to do. Calls come in execution order.
class DrawSink {
 public:
  virtual ~DrawSink() = default;
  // Clears the accumulator (the first step of a rebuild): both targets' where the pack has an
  // indirect map.
  virtual void clear() = 0;
  // Adds patches [first_patch, first_patch + patch_count) (pack indices, all of one group and one
  // target: PatchRecord::target of the first), each multiplied by `factor` (linear RGB) and its
  // own sign, to that target's accumulator.
  virtual void draw(uint32_t group, uint32_t first_patch, uint32_t patch_count,
                    const float factor[3]) = 0;
  // Writes the accumulator's texels under the destination rectangles of patches
  // [first_patch, first_patch + patch_count) (all of one target) into that target's presented
  // map, clamped at zero.
  virtual void present(uint32_t first_patch, uint32_t patch_count) = 0;
  // Writes every target's whole accumulator into its presented map, clamped at zero.
  virtual void present_all() = 0;
};

// A cost split by target: texels of the light map and texels of the indirect map.
struct TargetTexels {
  uint64_t light_map = 0;
  uint64_t indirect_map = 0;
  uint64_t total() const { return light_map + indirect_map; }
};

struct PlannerLimits {
  // Rebuild when the incremental error bound exceeds this fraction of a texel's magnitude
  // (2^-10: about a tenth of a percent, two ulps of a half float).
  float drift_tolerance = 1.0f / 1024.0f;
};

// How the accumulator rounds a blended write: its unit roundoff (2^-24 for float rounding to
// nearest, 2^-11 for half floats; a full ulp, 2^-23 or 2^-10, where the target truncates).
struct TargetPrecision {
  float unit_roundoff = 1.0f / 16777216.0f;
  bool truncates = false;
};

struct FrameStats {
  uint64_t frame = 0;                  // update() calls so far
  uint64_t texels = 0;                 // texels written this frame (clears and presents included)
  uint64_t indirect_texels = 0;        // the part of `texels` written into the indirect map
  uint32_t draws = 0;                  // draw and present steps this frame
  uint32_t pending_changes = 0;        // lights/objects whose wanted state is not yet presented
  uint32_t oldest_pending_frames = 0;  // age in frames of the oldest pending change
  uint32_t completed_changes = 0;      // changes that became visible this frame
  uint32_t max_latency_frames = 0;     // largest latency among them (1 = visible in the next frame)
  bool rebuild_active = false;         // a rebuild is in progress (after this frame)
  bool presented = false;              // a rebuild was presented this frame
  uint32_t oversize_steps = 0;         // 1 when this frame ran a single step larger than the budget
  uint64_t rebuild_remaining_texels = 0;  // cost left in the running rebuild
  // Error bound of the incremental history since the last rebuild, as a fraction of each texel's
  // magnitude M (see Drift above).
  float error_bound = 0.0f;
  // Moving lights (set by Runtime::update; runtime.h, "Moving lights"): pane factors pushed to the
  // planner this frame, panes still off their target beyond the tolerance in force after it, and
  // pushes the planner refused this frame (kOutOfRange: the pane keeps its old factor).
  uint32_t pane_changes = 0;
  uint32_t pane_pending = 0;
  uint32_t pane_refused = 0;
};

class Planner {
 public:
  Planner() = default;
  ~Planner();
  Planner(const Planner&) = delete;
  Planner& operator=(const Planner&) = delete;

  // Precomputes per-group costs, per-light/per-object group lists and the magnitude bounds (one
  // pass over every patch texel, with a width*height scratch map freed before returning). The
  // wanted state starts at the pack's authored defaults and nothing is presented: the first
  // update()s run a full rebuild.
  Status init(const PackView& pack, const PlannerLimits& limits, Error* error);
  // The accumulator's rounding (default: float rounding to nearest).
  void set_precision(const TargetPrecision& precision) { precision_ = precision; }
  // Largest |value| the maps can hold: set_light() refuses a state whose magnitude bound exceeds
  // it (default: 2^126).
  void set_value_limit(float limit) { value_limit_ = limit; }

  // Wanted state. kInvalidArgument for a value that is not finite and >= 0; kOutOfRange when the
  // light map of the wanted state could exceed the value limit (the state is left unchanged).
  // Index out of range: a caller bug (asserts; kInvalidArgument where asserts are off).
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

  uint32_t light_count() const { return light_count_; }
  uint32_t object_count() const { return object_count_; }
  // The presented state: what the light map holds (valid once map_ready()).
  void shown_factor(uint32_t light, float out[3]) const;
  bool shown_visible(uint32_t object) const { return shown_visible_[object] != 0; }

  const FrameStats& stats() const { return stats_; }
  bool map_ready() const { return ready_; }
  bool idle() const;  // presented, nothing pending, no rebuild running

  // Costs in texels of the targets written, known before anything runs (presents included).
  uint64_t group_texels(uint32_t group) const { return group_texels_[group]; }
  uint64_t clear_texels() const { return clear_texels_; }  // both maps
  uint64_t rebuild_texels() const;                         // the full rebuild of the wanted state
  uint64_t light_change_texels(uint32_t light) const { return light_change_cost(light).total(); }
  uint64_t object_change_texels(uint32_t object) const {
    return object_change_cost(object).total();
  }
  // The same split into light-map and indirect-map texels.
  TargetTexels group_cost(uint32_t group) const;
  TargetTexels light_change_cost(uint32_t light) const;    // for the presented visibility
  TargetTexels object_change_cost(uint32_t object) const;  // for the presented factors
  // First patch of the group that targets the indirect map (its end when none does).
  uint32_t group_indirect_first(uint32_t group) const { return group_split_[group]; }

  // An upper bound of |L| over the map for the wanted state: max |B| + sum_l max_c f_l * max A_l.
  float wanted_map_bound() const;
  // A_l's bound: max over texels of the sum of |values| of all of light l's groups (irradiance
  // per unit factor). What a change of l's factor by d can move any texel: at most |d| * this.
  float light_bound(uint32_t light) const { return light_bound_[light]; }

 private:
  struct Factor {
    float rgb[3];
  };
  float map_bound(const Factor* factors) const;
  bool lit(const Factor* factors, uint32_t light) const;
  void start_rebuild();
  bool run_rebuild(uint64_t budget, DrawSink& sink);
  bool apply_light_change(uint32_t light, uint64_t budget, DrawSink& sink, bool* started);
  bool apply_object_change(uint32_t object, uint64_t budget, DrawSink& sink, bool* started);
  // Draws patches [first, end) of `group` (split at its first indirect patch: one step per target).
  void emit(DrawSink& sink, uint32_t group, uint32_t first, uint32_t end, const float factor[3]);
  // Counts a step's texels of patches [first, end) in the frame's stats.
  void count_texels(uint32_t first, uint32_t end);
  void mark_for_present(uint32_t group);
  void present_marked(DrawSink& sink);
  void complete(uint64_t* since);
  void want_factor(uint32_t light, float out[3]) const;
  // Drift accounting (see Drift above).
  void count_draws(uint32_t draws, uint32_t light, const float from[3], const float to[3]);
  float drift() const;
  void reset_drift();

  const PackView* pack_ = nullptr;
  PlannerLimits limits_;
  TargetPrecision precision_;
  float value_limit_ = 8.5070592e37f;  // 2^126
  uint32_t light_count_ = 0, object_count_ = 0, group_count_ = 0;
  uint64_t clear_texels_ = 0;
  uint64_t indirect_clear_texels_ = 0;   // the indirect map's part of clear_texels_
  uint64_t* group_texels_ = nullptr;     // [group]
  uint64_t* patch_prefix_ = nullptr;     // [patch + 1] prefix sums of patch areas
  uint64_t* indirect_prefix_ = nullptr;  // [patch + 1] prefix sums of indirect patches' areas
  uint32_t* group_split_ = nullptr;      // [group] first patch targeting the indirect map
  float base_bound_ = 0.0f;              // max over texels of |B| + sum_o |static shadows of o|
  float* light_bound_ = nullptr;         // [light] max over texels of A_l
  uint32_t* light_first_ = nullptr;      // [light + 1] range in light_groups_
  uint32_t* light_groups_ = nullptr;     // every group of each light
  uint32_t* object_first_ = nullptr;     // [object + 1] range in object_groups_
  uint32_t* object_groups_ = nullptr;    // groups naming each object

  // Wanted state.
  uint8_t* on_ = nullptr;
  Factor* color_ = nullptr;
  float* intensity_ = nullptr;
  uint8_t* want_visible_ = nullptr;
  // Presented state (what the presented map holds) and the running rebuild's snapshot.
  Factor* shown_ = nullptr;
  uint8_t* shown_visible_ = nullptr;
  Factor* build_ = nullptr;
  uint8_t* build_visible_ = nullptr;
  // Frame at which each pending change was made (kNotPending when none).
  uint64_t* light_since_ = nullptr;
  uint64_t* object_since_ = nullptr;
  // Groups drawn by this frame's incremental changes, to present at the end of the frame.
  uint64_t* marked_frame_ = nullptr;  // [group] frame of the last mark
  uint32_t* marked_ = nullptr;        // [group] marked groups of this frame
  uint32_t marked_count_ = 0;
  uint64_t marked_texels_ = 0;  // their present cost
  // Drift: draws since the last rebuild, and per light and channel the sum over those draws of
  // the factor in force (the changed light: the larger of its old and new factor), its peak.
  float drift_draws_ = 0.0f;
  Factor* drift_weight_ = nullptr;  // [light]
  Factor* drift_peak_ = nullptr;    // [light]
  Factor* drift_saved_ = nullptr;   // [2 * light] scratch: weights and peaks before a change

  bool ready_ = false;
  bool rebuilding_ = false;
  bool rebuild_cleared_ = false;
  uint32_t rebuild_group_ = 0;  // next group to draw
  uint32_t rebuild_patch_ = 0;  // next patch within it (patch-range splitting)
  uint64_t rebuild_left_ = 0;
  uint64_t frame_ = 0;
  FrameStats stats_;
  void* block_ = nullptr;  // one allocation holding every array above
};

// The largest bound of the authored state's light map (Planner::wanted_map_bound) a runtime
// opens: the float sums of its patches then stay finite with 300x headroom. Runtime::open refuses
// a pack above it (kOutOfRange); no limit raises it.
constexpr float kMaxAuthoredMapBound = 1.0e36f;

// kOutOfRange, with a message giving the bound, when `pack`'s authored light map could exceed
// kMaxAuthoredMapBound: what `lightpatch verify` checks beyond PackView::open. Allocates a
// Planner (a light map of scratch) for the call.
Status check_authored_map_bound(const PackView& pack, Error* error);

}  // namespace lightpatch
