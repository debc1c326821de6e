// Test helpers shared by the planner (CPU) and GLES tests: the recomposition formula evaluated
// from scratch in double precision (every active group added once, with the rules of
// group_rules.h and the drawing loop of patch_accumulate.h), per-texel magnitudes for rounding
// tolerances, and a DrawSink that executes a plan on the CPU, rounding every texel a draw writes
// like a half-float target (to nearest or toward zero) when asked to.
#pragma once

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <vector>

#include "lightpatch/group_rules.h"
#include "lightpatch/half_float.h"
#include "lightpatch/pack_view.h"
#include "lightpatch/patch_accumulate.h"
#include "lightpatch/planner.h"

namespace lightpatch::testing {

// Rounds to a half float: to nearest even, or toward zero (Mesa's llvmpipe).
inline float round_half(float v, bool toward_zero = false) {
  const float nearest = half_to_float(float_to_half(v));
  if (!toward_zero || std::fabs(nearest) <= std::fabs(v)) return nearest;
  // The nearest was away from zero: step one half ulp back toward zero.
  uint16_t h = float_to_half(v);
  return half_to_float(uint16_t(h - 1));
}

struct RefState {
  std::vector<float> factor;  // lights * 3
  std::vector<uint8_t> visible;
};

// L = sum over the groups the state draws of factor * group, in double. `magnitude` (optional)
// receives, per texel and channel, the planner's magnitude M = |B| + sum_l |f_l| A_l (planner.h:
// every group of every light, drawn or not), an upper bound of the sum of |terms|.
inline std::vector<double> reference_map(const PackView& pack, const RefState& s,
                                         std::vector<double>* magnitude = nullptr) {
  const size_t n = size_t(pack.lightmap_width()) * pack.lightmap_height() * 3;
  std::vector<double> map(n, 0.0);
  if (magnitude) magnitude->assign(n, 0.0);
  for (uint32_t g = 0; g < pack.group_count(); ++g) {
    const pack::GroupRecord& gr = pack.group(g);
    double f[3] = {1, 1, 1};
    if (group_has_light(gr.kind)) {
      for (int c = 0; c < 3; ++c) f[c] = s.factor[gr.light * 3 + c];
    }
    if (magnitude) add_patches(pack, gr.first_patch, gr.patch_count, f, magnitude->data(), true);
    const bool active = group_active(
        gr, [&](uint32_t) { return f[0] != 0.0 || f[1] != 0.0 || f[2] != 0.0; },
        [&](uint32_t o) { return s.visible[o] != 0; });
    if (active) add_patches(pack, gr.first_patch, gr.patch_count, f, map.data());
  }
  return map;
}

// What the game samples: the map clamped at zero.
inline std::vector<double> presented(std::vector<double> map) {
  for (double& v : map) v = std::max(v, 0.0);
  return map;
}

enum class Rounding { kNone, kHalfNearest, kHalfTowardZero };

// Executes a plan on an RGB float accumulator and an RGB presented map; records costs and steps.
class CpuMapSink final : public DrawSink {
 public:
  CpuMapSink(const PackView& pack, Rounding rounding) : pack_(pack), rounding_(rounding) {
    const size_t n = size_t(pack.lightmap_width()) * pack.lightmap_height() * 3;
    accumulator_.assign(n, 0.0f);
    presented_.assign(n, 0.0f);
  }
  void clear() override {
    std::fill(accumulator_.begin(), accumulator_.end(), 0.0f);
    texels += uint64_t(pack_.lightmap_width()) * pack_.lightmap_height();
  }
  void draw(uint32_t group, uint32_t first, uint32_t count, const float factor[3]) override {
    EXPECT_GE(first, pack_.group(group).first_patch);
    EXPECT_LE(first + count, pack_.group(group).first_patch + pack_.group(group).patch_count);
    if (rounding_ == Rounding::kNone) {
      add_patches(pack_, first, count, factor, accumulator_.data());
    } else {  // a half-float target rounds every texel a draw writes
      const uint32_t w = pack_.lightmap_width();
      for (uint32_t p = first; p < first + count; ++p) {
        const pack::PatchRecord& pr = pack_.patch(p);
        scratch_.assign(accumulator_.size(), 0.0f);
        add_patches(pack_, p, 1, factor, scratch_.data());
        for (uint32_t y = pr.dest_y; y < uint32_t(pr.dest_y + pr.height); ++y) {
          for (uint32_t x = pr.dest_x; x < uint32_t(pr.dest_x + pr.width); ++x) {
            for (int c = 0; c < 3; ++c) {
              float& v = accumulator_[(size_t(y) * w + x) * 3 + c];
              v = round_half(v + scratch_[(size_t(y) * w + x) * 3 + c],
                             rounding_ == Rounding::kHalfTowardZero);
            }
          }
        }
      }
    }
    for (uint32_t p = first; p < first + count; ++p) {
      texels += uint64_t(pack_.patch(p).width) * pack_.patch(p).height;
    }
    ++draws;
  }
  void present(uint32_t first, uint32_t count) override {
    const uint32_t w = pack_.lightmap_width();
    for (uint32_t p = first; p < first + count; ++p) {
      const pack::PatchRecord& pr = pack_.patch(p);
      for (uint32_t y = pr.dest_y; y < uint32_t(pr.dest_y + pr.height); ++y) {
        for (uint32_t x = pr.dest_x; x < uint32_t(pr.dest_x + pr.width); ++x) {
          for (int c = 0; c < 3; ++c) {
            const size_t i = (size_t(y) * w + x) * 3 + c;
            presented_[i] = std::max(accumulator_[i], 0.0f);
          }
        }
      }
      texels += uint64_t(pr.width) * pr.height;
    }
    ++presents;
  }
  void present_all() override {
    for (size_t i = 0; i < accumulator_.size(); ++i)
      presented_[i] = std::max(accumulator_[i], 0.0f);
    texels += uint64_t(pack_.lightmap_width()) * pack_.lightmap_height();
    ++presents;
    ++whole_presents;
  }
  const std::vector<float>& sampled() const { return presented_; }

  uint64_t texels = 0;
  uint32_t draws = 0, presents = 0, whole_presents = 0;

 private:
  const PackView& pack_;
  Rounding rounding_;
  std::vector<float> accumulator_, presented_, scratch_;
};

// The planner's wanted / presented state as a RefState.
inline RefState wanted_state(const Planner& p, const PackView& pack) {
  RefState s;
  for (uint32_t l = 0; l < pack.light_count(); ++l) {
    float c[3];
    p.light_color(l, c);
    for (int k = 0; k < 3; ++k)
      s.factor.push_back(p.light_on(l) ? c[k] * p.light_intensity(l) : 0.0f);
  }
  for (uint32_t o = 0; o < pack.object_count(); ++o) s.visible.push_back(p.object_visible(o));
  return s;
}
inline RefState shown_state(const Planner& p, const PackView& pack) {
  RefState s;
  for (uint32_t l = 0; l < pack.light_count(); ++l) {
    float c[3];
    p.shown_factor(l, c);
    s.factor.insert(s.factor.end(), c, c + 3);
  }
  for (uint32_t o = 0; o < pack.object_count(); ++o) s.visible.push_back(p.shown_visible(o));
  return s;
}

}  // namespace lightpatch::testing
