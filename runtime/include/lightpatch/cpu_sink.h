// Executes the planner's steps on the CPU: a double-precision RGB accumulator and a presented map,
// either linear float RGB (the CPU reference recomposer) or half-float RGBA rounded to nearest
// (the runtime's CPU path, uploaded as the texture the game samples). Presenting multiplies by the
// presentation scale and clamps at zero, except for a pack whose maps are presented signed
// (PackView::presents_signed(): the game clamps L + I) (planner.h, runtime.h).
//
// Both targets: the buffers hold the pack's map set (pack_view.h: the light map, then the indirect
// map where the pack has one), so a pack with an indirect map has two accumulators and two
// presented maps, each drawn and presented in its own texels.
//
// The sink owns no memory: the caller sizes the buffers for the pack (map_texels()*3 doubles, and
// map_texels()*3 floats or map_texels()*4 halves) and keeps them alive.
#pragma once

#include <cstdint>

#include "lightpatch/pack_view.h"
#include "lightpatch/planner.h"

namespace lightpatch {

class CpuSink final : public DrawSink {
 public:
  // Exactly one of `rgb` and `half_rgba` is non-null. `scale` multiplies presented values.
  void bind(const PackView* pack, double* accumulator, float* rgb, uint16_t* half_rgba,
            float scale);

  void clear() override;
  void draw(uint32_t group, uint32_t first_patch, uint32_t patch_count,
            const float factor[3]) override;
  void present(uint32_t first_patch, uint32_t patch_count) override;
  void present_all() override;

  // Rows [dirty_begin(t), dirty_end(t)) of target t's presented map (pack::PatchTarget) changed
  // since the last clear_dirty() (empty when begin == end).
  uint32_t dirty_begin(uint8_t target = pack::kTargetLightMap) const {
    return dirty_begin_[target];
  }
  uint32_t dirty_end(uint8_t target = pack::kTargetLightMap) const { return dirty_end_[target]; }
  void clear_dirty();

 private:
  void present_rect(uint8_t target, uint32_t x, uint32_t y, uint32_t width, uint32_t height);

  const PackView* pack_ = nullptr;
  double* accumulator_ = nullptr;
  float* rgb_ = nullptr;
  uint16_t* half_rgba_ = nullptr;
  float scale_ = 1.0f;
  uint32_t dirty_begin_[2] = {0, 0}, dirty_end_[2] = {0, 0};
};

}  // namespace lightpatch
