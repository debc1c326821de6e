// CPU reference recomposer (paper Alg. 5-9, thesis §4.2): rebuilds the light map of a scene state
// from a validated pack alone, and applies state changes incrementally.
//
//   L = B + sum_l f_l * SC_l,   SC_l = C_l - sum_{o visible} S_ol + sum_{a<b visible} P_lab
//
// with f_l = on * colour * intensity (SceneState::light_factor). apply() diffs the new state
// against the last applied one; m = lights whose term changes (factor changed, or an object they
// have shadow/pair patches for was toggled). If 2m < n (n = lights) it updates (Alg. 8 when only
// the factor changed: L += (f_new - f_old) SC_l; Alg. 7 otherwise: L -= f_old SC_l(old),
// L += f_new SC_l(new)); otherwise it rebuilds (thesis §4.2.4).
//
// Precision: the map is accumulated in double, so thousands of incremental updates do not drift
// (a float accumulator gathers one rounding per update per texel); rgb() is that map rounded to
// float after each rebuild/apply, and agrees with a fresh rebuild to float rounding.
//
// Memory: everything is allocated in init() (light map, last state, per-light scratch); rebuild()
// and apply() allocate nothing. The pack's bytes must outlive the recomposer.
#pragma once

#include <cstdint>

#include "lightpatch/pack_view.h"
#include "lightpatch/scene_state.h"
#include "lightpatch/status.h"

namespace lightpatch {

class CpuRecomposer {
 public:
  struct Stats {
    bool rebuilt = false;         // the last update was a full rebuild
    uint32_t lights_updated = 0;  // m of the 2m < n rule (0 after a rebuild with no diff)
    uint32_t patches_drawn = 0;   // patch passes of the last update
    uint64_t texels_drawn = 0;    // texel passes of the last update
  };

  CpuRecomposer() = default;
  ~CpuRecomposer();
  CpuRecomposer(const CpuRecomposer&) = delete;
  CpuRecomposer& operator=(const CpuRecomposer&) = delete;

  // Sizes the light map for `pack` (which must be valid and stay mapped) and allocates all memory.
  // The map is black until the first rebuild()/apply().
  Status init(const PackView& pack, Error* error);

  // Full reconstruction from `state` (a state of the same pack).
  Status rebuild(const SceneState& state);
  // Brings the map from the last applied state to `state` (a rebuild if none was applied yet).
  Status apply(const SceneState& state);

  // The light map: linear RGB floats, row 0 at the top, width*height*3.
  const float* rgb() const { return rgb_; }
  uint32_t width() const { return width_; }
  uint32_t height() const { return height_; }
  const Stats& stats() const { return stats_; }

 private:
  void draw_group(uint32_t group, const double factor[3]);
  // factor * SC_l for the visibility in `state`.
  void draw_light(uint32_t light, const SceneState& state, const double factor[3]);
  // Static-light shadows of the objects whose visibility differs between `from` (null: all
  // hidden) and `to`.
  void draw_static_shadows(const SceneState* from, const SceneState& to);
  bool light_touched_by_objects(uint32_t light, const SceneState& state) const;
  void publish();

  PackView pack_;  // a copy of the caller's view (pointers into the mapped pack)
  uint32_t width_ = 0, height_ = 0;
  double* accum_ = nullptr;  // width*height*3
  float* rgb_ = nullptr;     // width*height*3
  SceneState last_;
  bool has_last_ = false;
  // Per light: contribution group (or -1) and the [begin, end) ranges of its shadow and pair
  // groups in the sorted group table.
  int32_t* contribution_ = nullptr;
  uint32_t* shadow_begin_ = nullptr;
  uint32_t* shadow_end_ = nullptr;
  uint32_t* pair_begin_ = nullptr;
  uint32_t* pair_end_ = nullptr;
  uint8_t* affected_ = nullptr;  // per light, scratch of apply()
  int32_t base_ = -1;
  // [begin, end) of the static-shadow groups (the last kind in the sorted table).
  uint32_t static_begin_ = 0, static_end_ = 0;
  Stats stats_;
};

}  // namespace lightpatch
