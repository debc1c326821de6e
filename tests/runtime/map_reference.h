// Test helpers shared by the planner (CPU) and GLES tests: a double-precision evaluation of the
// recomposition formula straight from the pack, and a DrawSink that executes a plan on the CPU
// (optionally rounding to half floats after every draw, like an RGBA16F target).
#pragma once

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <vector>

#include "lightpatch/pack_view.h"
#include "lightpatch/patch_decode.h"
#include "lightpatch/planner.h"

namespace lightpatch::testing {

// Rounds to the nearest IEEE half float (normal range; tiny values flush like subnormals).
inline float round_half(float v) {
  if (v == 0.0f || !std::isfinite(v)) return v;
  int e = 0;
  const double m = std::frexp(double(v), &e);  // v = m * 2^e, 0.5 <= |m| < 1
  const int bits = e < -13 ? 11 - (-13 - e) : 11;
  if (bits <= 0) return 0.0f;
  return float(std::ldexp(std::nearbyint(std::ldexp(m, bits)), e - bits));
}

// Adds factor * decoded patch values of patches [first, first+count) to an RGB map.
template <typename T>
void add_patches(const PackView& pack, uint32_t first, uint32_t count, const double factor[3],
                 T* map) {
  const uint32_t w = pack.lightmap_width();
  for (uint32_t p = first; p < first + count; ++p) {
    const pack::PatchRecord& pr = pack.patch(p);
    const double sign = pack::group_subtracts(pack.group(pr.group).kind) ? -1.0 : 1.0;
    const uint8_t* atlas = pack.atlas_pixels(pr.atlas);
    const uint32_t aw = pack.atlas(pr.atlas).width;
    for (uint32_t y = 0; y < pr.height; ++y) {
      for (uint32_t x = 0; x < pr.width; ++x) {
        const uint8_t* q = atlas + (size_t(pr.atlas_y + y) * aw + pr.atlas_x + x) * 4;
        T* out = map + (size_t(pr.dest_y + y) * w + pr.dest_x + x) * 3;
        for (uint32_t c = 0; c < 3; ++c) {
          const uint8_t byte = q[pr.channel + (pr.channel_count == 3 ? c : 0)];
          out[c] += T(sign * double(patch_decode(pr, byte)) * factor[c]);
        }
      }
    }
  }
}

struct RefState {
  std::vector<float> factor;  // lights * 3
  std::vector<uint8_t> visible;
};

// L = sum over active groups of factor * group, in double. `magnitude` (optional) receives, per
// texel, the sum of absolute terms (for rounding tolerances).
inline std::vector<double> reference_map(const PackView& pack, const RefState& s,
                                         std::vector<double>* magnitude = nullptr) {
  const size_t n = size_t(pack.lightmap_width()) * pack.lightmap_height() * 3;
  std::vector<double> map(n, 0.0);
  if (magnitude) magnitude->assign(n, 0.0);
  for (uint32_t g = 0; g < pack.group_count(); ++g) {
    const pack::GroupRecord& gr = pack.group(g);
    double f[3] = {1, 1, 1};
    if (gr.kind == pack::kGroupStaticShadow && !s.visible[gr.object_a]) continue;
    if (gr.kind != pack::kGroupBase && gr.kind != pack::kGroupStaticShadow) {
      for (int c = 0; c < 3; ++c) f[c] = s.factor[gr.light * 3 + c];
      if (gr.kind != pack::kGroupContribution && !s.visible[gr.object_a]) continue;
      if (gr.kind == pack::kGroupPairCorrection && !s.visible[gr.object_b]) continue;
    }
    add_patches(pack, gr.first_patch, gr.patch_count, f, map.data());
    if (magnitude) {
      std::vector<double> one(n, 0.0);
      add_patches(pack, gr.first_patch, gr.patch_count, f, one.data());
      for (size_t i = 0; i < n; ++i) (*magnitude)[i] += std::fabs(one[i]);
    }
  }
  return map;
}

// Executes a plan on two RGB float maps; records costs and draws.
class CpuMapSink final : public DrawSink {
 public:
  CpuMapSink(const PackView& pack, bool half) : pack_(pack), half_(half) {
    const size_t n = size_t(pack.lightmap_width()) * pack.lightmap_height() * 3;
    maps_[0].assign(n, 0.0f);
    maps_[1].assign(n, 0.0f);
  }
  void clear_intermediate() override {
    std::fill(maps_[shown_ ^ 1].begin(), maps_[shown_ ^ 1].end(), 0.0f);
    texels += uint64_t(pack_.lightmap_width()) * pack_.lightmap_height();
  }
  void draw(DrawTarget target, uint32_t group, uint32_t first, uint32_t count,
            const float factor[3]) override {
    EXPECT_GE(first, pack_.group(group).first_patch);
    EXPECT_LE(first + count, pack_.group(group).first_patch + pack_.group(group).patch_count);
    std::vector<float>& m = maps_[target == DrawTarget::kLightMap ? shown_ : shown_ ^ 1];
    const double f[3] = {factor[0], factor[1], factor[2]};
    add_patches(pack_, first, count, f, m.data());
    if (half_) {  // an RGBA16F target rounds every texel a draw writes
      const uint32_t w = pack_.lightmap_width();
      for (uint32_t p = first; p < first + count; ++p) {
        const pack::PatchRecord& pr = pack_.patch(p);
        for (uint32_t y = pr.dest_y; y < uint32_t(pr.dest_y + pr.height); ++y) {
          for (uint32_t x = pr.dest_x; x < uint32_t(pr.dest_x + pr.width); ++x) {
            for (int c = 0; c < 3; ++c)
              m[(size_t(y) * w + x) * 3 + c] = round_half(m[(size_t(y) * w + x) * 3 + c]);
          }
        }
      }
    }
    for (uint32_t p = first; p < first + count; ++p) {
      texels += uint64_t(pack_.patch(p).width) * pack_.patch(p).height;
    }
    ++draws;
    if (target == DrawTarget::kLightMap) ++light_map_draws;
  }
  void present() override {
    shown_ ^= 1;
    ++presents;
  }
  const std::vector<float>& sampled() const { return maps_[shown_]; }

  uint64_t texels = 0;
  uint32_t draws = 0, light_map_draws = 0, presents = 0;

 private:
  const PackView& pack_;
  bool half_;
  std::vector<float> maps_[2];
  int shown_ = 0;
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
