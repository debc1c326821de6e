// Semi-dynamic light probes on the CPU (pack_format.h, "Light probes"): each probe's irradiance
// SH for the current SceneState, kept incrementally, and a query for the SH at a world position.
//
// A probe's SH is the sum over the pack's probe sets of sign * factor * entry, with the sign,
// factor (f_l or 1) and activity of the set's owner from group_rules.h, exactly as the light map
// sums its groups; a moving light's panes are lights like the others, so their sets follow its
// pose through the pane factors (SceneState::light_factor, or the planner's presented ones).
// LightProbes keeps per probe a double-precision accumulator and per set the factor it last
// applied; update() visits every set (a few thousand comparisons at most) and, where a set's
// factor changed, adds (new - old) * its entries. Its cost is counted in entries (one entry: 27
// multiply-adds into one probe): stats() gives the last update's, the total and the most sets any
// one probe has (what a full evaluation of that probe costs).
//
// Probes are evaluated on the CPU whatever path the GLES Runtime takes; the game samples the SH
// where a moving thing is (sample()) and uploads it as uniforms (27 floats, or the 3 x 9 of its
// shader), typically once a frame per lit object: probes.update(runtime.planner()) after
// runtime.update(), then sample().
//
// Memory: init() allocates everything (216 bytes a probe, 12 bytes a set, 4 bytes a probe for its
// cost); update(), rebuild(), probe_sh(), sample() and find_probe() allocate nothing. No
// exceptions. The pack's bytes must outlive the object.
#pragma once

#include <cstdint>

#include "lightpatch/pack_format.h"
#include "lightpatch/pack_view.h"
#include "lightpatch/planner.h"
#include "lightpatch/scene_state.h"
#include "lightpatch/status.h"

namespace lightpatch {

constexpr uint32_t kProbeShFloats = pack::kProbeShCount * 3;  // sh[k * 3 + c]

class LightProbes {
 public:
  struct Stats {
    uint64_t entries_last_update = 0;  // entries added by the last update()/rebuild()
    uint32_t sets_changed_last_update = 0;
    uint64_t entries_total = 0;          // since init()
    uint32_t max_entries_per_probe = 0;  // the most sets reaching one probe
    uint64_t rebuild_entries = 0;        // a rebuild's upper bound: every entry of the pack
  };

  LightProbes() = default;
  ~LightProbes();
  LightProbes(const LightProbes&) = delete;
  LightProbes& operator=(const LightProbes&) = delete;

  // Sizes everything for `pack` (valid, and kept mapped). A pack without probes gives an empty,
  // usable object (probe_count() 0, sample() false). Every probe starts at zero (no set applied):
  // the first update() adds every active set.
  Status init(const PackView& pack, Error* error);

  // Brings every probe to `state` (a state of the same pack: kInvalidArgument otherwise, nothing
  // changed), touching only the sets whose factor changed.
  Status update(const SceneState& state);
  // The same from zero: every active set added again (drops any rounding that updates piled up;
  // in double precision that stays below 1e-12 relative over millions of changes).
  Status rebuild(const SceneState& state);
  // Brings every probe to the state `planner` has presented (Planner::shown_factor,
  // shown_visible: what the light map the game samples holds), so that a thing lit by the probes
  // changes in the same frame as the light map around it, not the frames of a change's latency
  // ahead of it. A game with a Runtime calls update(runtime.planner()) after runtime.update().
  // kInvalidArgument for a planner of another pack; before the planner's map_ready() nothing is
  // presented and the probes stay as they are (zero after init()).
  Status update(const Planner& planner);

  uint32_t probe_count() const { return pack_.probe_count(); }
  // Probe i's irradiance SH, out[k * 3 + c] (spherical_harmonics.h's basis and order; units of
  // the light map). i < probe_count().
  void probe_sh(uint32_t i, float out[kProbeShFloats]) const;
  // Index of the probe placed by the scene node with this name (NUL-terminated), or -1.
  int32_t find_probe(const char* name) const;
  // Sets reaching probe i: its cost in entries when evaluated from scratch.
  uint32_t probe_entries(uint32_t i) const { return per_probe_[i]; }

  // The SH at world position `pos` (metres) from the probe grid, into out[27]. The 8 corner
  // probes of the grid cell holding `pos` are blended trilinearly (outside the grid, the nearest
  // cell, with the weights clamped to its faces). A corner is left out when it has no probe
  // (kNone32) or when `pos` lies farther from its probe along some axis than the probe's reach in
  // that direction (a wall between them); the weights of the corners kept are renormalised. If no
  // corner with a positive weight is left, the result is the SH of the nearest (to `pos`) corner
  // probe that passes the reach test, else of the nearest corner probe at all. Returns false (out
  // untouched) when the pack has no grid or the cell has no probe at all. A non-finite coordinate
  // counts as the grid's first cell along its axis and reaches no probe.
  bool sample(const float pos[3], float out[kProbeShFloats]) const;

  // E(n) = sum_k sh[k * 3 + c] Y_k(n) per channel, clamped at 0 (what a surface facing the unit
  // normal n receives).
  static void irradiance(const float sh[kProbeShFloats], const float n[3], float rgb[3]);

  const Stats& stats() const { return stats_; }
  // Bytes init() allocated.
  uint64_t memory_bytes() const { return memory_; }

 private:
  // Factor(l, rgb) gives light l's factor, Visible(o) object o's visibility.
  template <typename Factor, typename Visible>
  Status apply(Factor&& factor, Visible&& visible, bool from_zero);
  Status apply_state(const SceneState& state, bool from_zero);

  PackView pack_;
  double* accumulator_ = nullptr;  // [probe * 27 + k * 3 + c]
  float* applied_ = nullptr;       // [set * 3 + c]: the factor (sign included) in the accumulator
  uint32_t* per_probe_ = nullptr;  // [probe]: sets reaching it
  Stats stats_;
  uint64_t memory_ = 0;
};

}  // namespace lightpatch
