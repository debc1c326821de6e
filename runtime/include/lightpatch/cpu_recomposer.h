// CPU reference recomposer: the runtime's planner (planner.h) executed on the CPU in double
// precision (cpu_sink.h), driven with an unlimited budget, so that every state is recomposed
// exactly as a game's runtime would (incremental changes where the planner takes them, rebuilds
// otherwise) without any rounding a GPU target adds.
//
//   L = B + sum_l f_l * SC_l,   SC_l = C_l - sum_{o visible} S_ol + sum_{a<b visible} P_lab
//
// with f_l = on * colour * intensity (SceneState::light_factor); a pane's f_l is its factor from
// the state's moving lights (moving_lights.h), set in full on every rebuild()/apply(). light_map()
// is the presented map: the accumulator rounded to float and clamped at zero (light is never
// negative; planner.h says why quantization can leave a few steps below zero under a visible
// object). A pack with an indirect map has a second accumulator and presented map at its own
// resolution (indirect_map()); both are presented signed (PackView::presents_signed()), and rgb()
// is what a game lights with: max(L + I, 0), the indirect map magnified bilinearly
// (indirect_map.h), computed after each rebuild()/apply(); without an indirect map rgb() is the
// light map itself.
//
// Memory: everything is allocated in init(); rebuild() and apply() allocate nothing. The pack's
// bytes must outlive the recomposer.
#pragma once

#include <cstdint>

#include "lightpatch/cpu_sink.h"
#include "lightpatch/pack_view.h"
#include "lightpatch/planner.h"
#include "lightpatch/scene_state.h"
#include "lightpatch/status.h"

namespace lightpatch {

class CpuRecomposer {
 public:
  struct Stats {
    bool rebuilt = false;       // the last update presented a full rebuild
    uint64_t texels_drawn = 0;  // texels written by the last update (clears, presents included)
    uint64_t indirect_texels_drawn = 0;  // the part of texels_drawn written into the indirect map
  };

  CpuRecomposer() = default;
  ~CpuRecomposer();
  CpuRecomposer(const CpuRecomposer&) = delete;
  CpuRecomposer& operator=(const CpuRecomposer&) = delete;

  // Sizes the light map for `pack` (which must be valid and stay mapped) and allocates all memory.
  // The map is black until the first rebuild()/apply().
  Status init(const PackView& pack, Error* error);

  // Full reconstruction of `state` (a state of the same pack).
  Status rebuild(const SceneState& state);
  // Brings the map from the last state to `state` through the planner's incremental path.
  // kOutOfRange when the state's light map could exceed the float range.
  Status apply(const SceneState& state);

  // The light a game samples, L + I: linear RGB floats, >= 0, row 0 at the top, width*height*3.
  const float* rgb() const { return combined_ ? combined_ : rgb_; }
  // The presented light map alone (width*height*3), and the presented indirect map
  // (indirect_width()*indirect_height()*3 in the pack's indirect texels; null without one).
  // presented_maps() is both as the pack's map set (pack_view.h), map_texels()*3 values.
  const float* light_map() const { return rgb_; }
  const float* presented_maps() const { return rgb_; }
  const float* indirect_map() const {
    return pack_.has_indirect_map() ? rgb_ + size_t(width_) * height_ * 3 : nullptr;
  }
  uint32_t width() const { return width_; }
  uint32_t height() const { return height_; }
  const Stats& stats() const { return stats_; }

 private:
  Status push(const SceneState& state);
  Status settle();

  PackView pack_;  // a copy of the caller's view (pointers into the mapped pack)
  Planner planner_;
  CpuSink sink_;
  uint32_t width_ = 0, height_ = 0;
  double* accumulator_ = nullptr;  // the map set's texels * 3 (pack_view.h)
  float* rgb_ = nullptr;           // the map set's texels * 3: the presented maps
  float* combined_ = nullptr;      // width*height*3, L + magnified I (packs with an indirect map)
  Stats stats_;
};

}  // namespace lightpatch
