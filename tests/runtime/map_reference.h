// Test helpers shared by the planner (CPU) and GLES tests: the recomposition formula evaluated
// from scratch in double precision (every active group added once, with the rules of
// group_rules.h and the drawing loop of patch_accumulate.h), per-texel magnitudes for rounding
// tolerances, and a DrawSink that executes a plan on the CPU, rounding every texel a draw writes
// like a half-float target (to nearest or toward zero) when asked to. Maps are the pack's map set
// (pack_view.h): the light map, then the indirect map where the pack has one.
#pragma once

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstddef>
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
  const size_t n = size_t(pack.map_texels()) * 3;
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

// The presented maps: clamped at zero, except in a pack with an indirect map, whose maps keep
// their sign (the light map corrects the indirect map; the game clamps L + I: pack_format.h,
// "Two target maps").
inline bool presents_signed(const PackView& pack) {
  return pack.indirect_scale() != 0;
}
inline std::vector<double> presented(const PackView& pack, std::vector<double> map) {
  if (!presents_signed(pack))
    for (double& v : map) v = std::max(v, 0.0);
  return map;
}

// The indirect map at the centre of light-map texel (x, y), channel c, by the contract's formula
// evaluated directly in double (pack_format.h, "Two target maps"; independent of indirect_map.h):
// bilinear at ((x + 0.5) / s - 0.5, (y + 0.5) / s - 0.5), clamped to the edge texels. `map`: w x h
// RGB texels.
inline double contract_indirect_at(const double* map, uint32_t w, uint32_t h, uint32_t s,
                                   uint32_t x, uint32_t y, int c) {
  const double u = (x + 0.5) / s - 0.5, v = (y + 0.5) / s - 0.5;
  const double u0 = std::floor(u), v0 = std::floor(v);
  auto at = [&](double i, double j) {
    const double ci = std::min(std::max(i, 0.0), double(w - 1));
    const double cj = std::min(std::max(j, 0.0), double(h - 1));
    return map[(size_t(cj) * w + size_t(ci)) * 3 + size_t(c)];
  };
  const double a = u - u0, b = v - v0;
  return (1 - a) * (1 - b) * at(u0, v0) + a * (1 - b) * at(u0 + 1, v0) +
         (1 - a) * b * at(u0, v0 + 1) + a * b * at(u0 + 1, v0 + 1);
}

// What a game samples from a map set (the light map, then the indirect map): max(L + I, 0) per
// light-map texel, width * height * 3 values.
inline std::vector<double> sampled_reference(const PackView& pack,
                                             const std::vector<double>& maps) {
  const uint32_t w = pack.lightmap_width(), h = pack.lightmap_height();
  std::vector<double> out(maps.begin(), maps.begin() + std::ptrdiff_t(size_t(w) * h * 3));
  if (!pack.has_indirect_map()) return out;
  const double* indirect = maps.data() + pack.map_offset(pack::kTargetIndirectMap) * 3;
  for (uint32_t y = 0; y < h; ++y) {
    for (uint32_t x = 0; x < w; ++x) {
      for (int c = 0; c < 3; ++c) {
        out[(size_t(y) * w + x) * 3 + size_t(c)] +=
            contract_indirect_at(indirect, pack.indirect_width(), pack.indirect_height(),
                                 pack.indirect_scale(), x, y, c);
      }
    }
  }
  for (double& v : out) v = std::max(v, 0.0);
  return out;
}

enum class Rounding { kNone, kHalfNearest, kHalfTowardZero };

// Executes a plan on an RGB float accumulator and an RGB presented map; records costs and steps.
class CpuMapSink final : public DrawSink {
 public:
  CpuMapSink(const PackView& pack, Rounding rounding) : pack_(pack), rounding_(rounding) {
    const size_t n = size_t(pack.map_texels()) * 3;
    accumulator_.assign(n, 0.0f);
    presented_.assign(n, 0.0f);
  }
  void clear() override {
    std::fill(accumulator_.begin(), accumulator_.end(), 0.0f);
    texels += pack_.map_texels();
    indirect_texels += indirect_map_texels();
  }
  void draw(uint32_t group, uint32_t first, uint32_t count, const float factor[3]) override {
    EXPECT_GE(first, pack_.group(group).first_patch);
    EXPECT_LE(first + count, pack_.group(group).first_patch + pack_.group(group).patch_count);
    check_one_target(first, count);
    if (rounding_ == Rounding::kNone) {
      add_patches(pack_, first, count, factor, accumulator_.data());
    } else {  // a half-float target rounds every texel a draw writes
      for (uint32_t p = first; p < first + count; ++p) {
        const pack::PatchRecord& pr = pack_.patch(p);
        scratch_.assign(accumulator_.size(), 0.0f);
        add_patches(pack_, p, 1, factor, scratch_.data());
        for_each_texel(pr, [&](size_t i) {
          for (int c = 0; c < 3; ++c) {
            float& v = accumulator_[i * 3 + c];
            v = round_half(v + scratch_[i * 3 + c], rounding_ == Rounding::kHalfTowardZero);
          }
        });
      }
    }
    count_texels(first, count);
    ++draws;
  }
  void present(uint32_t first, uint32_t count) override {
    check_one_target(first, count);
    for (uint32_t p = first; p < first + count; ++p) {
      for_each_texel(pack_.patch(p), [&](size_t i) {
        for (int c = 0; c < 3; ++c) presented_[i * 3 + c] = present_value(accumulator_[i * 3 + c]);
      });
    }
    count_texels(first, count);
    ++presents;
  }
  void present_all() override {
    for (size_t i = 0; i < accumulator_.size(); ++i) presented_[i] = present_value(accumulator_[i]);
    texels += pack_.map_texels();
    indirect_texels += indirect_map_texels();
    ++presents;
    ++whole_presents;
  }
  // The presented map set.
  const std::vector<float>& sampled() const { return presented_; }

  uint64_t texels = 0;
  uint64_t indirect_texels = 0;  // the part of `texels` written into the indirect map
  uint32_t draws = 0, presents = 0, whole_presents = 0;

 private:
  float present_value(float v) const { return presents_signed(pack_) ? v : std::max(v, 0.0f); }
  uint64_t indirect_map_texels() const {
    return uint64_t(pack_.indirect_width()) * pack_.indirect_height();
  }
  // Every step covers patches of one target.
  void check_one_target(uint32_t first, uint32_t count) const {
    for (uint32_t p = first; p < first + count; ++p)
      EXPECT_EQ(pack_.patch(p).target, pack_.patch(first).target) << "patch " << p;
  }
  void count_texels(uint32_t first, uint32_t count) {
    for (uint32_t p = first; p < first + count; ++p) {
      const uint64_t area = uint64_t(pack_.patch(p).width) * pack_.patch(p).height;
      texels += area;
      if (pack_.patch(p).target == pack::kTargetIndirectMap) indirect_texels += area;
    }
  }
  // Calls f(texel index in the map set) for every texel under the patch's destination.
  template <typename F>
  void for_each_texel(const pack::PatchRecord& pr, F&& f) const {
    const uint32_t w = pack_.map_width(pr.target);
    const size_t base = size_t(pack_.map_offset(pr.target));
    for (uint32_t y = pr.dest_y; y < uint32_t(pr.dest_y + pr.height); ++y) {
      for (uint32_t x = pr.dest_x; x < uint32_t(pr.dest_x + pr.width); ++x)
        f(base + size_t(y) * w + x);
    }
  }

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
