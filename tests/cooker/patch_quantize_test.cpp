// quantize_patch (quantize.h): a patch's 8-bit codes keep every significant texel within its
// quantization allowance where an encoding can, whatever the patch's brightest texel.
#include <gtest/gtest.h>

#include <cmath>
#include <random>
#include <vector>

#include "lightpatch/pack_format.h"
#include "lightpatch/patch_decode.h"
#include "quantize.h"

namespace lightpatch::cooker {
namespace {

// A 1-channel row of texels, all significant, at the threshold (half an output step) given.
SourcePatch row(const std::vector<float>& values, float threshold) {
  SourcePatch p;
  p.channels = 1;
  p.dest = Rect{0, 0, int(values.size()), 1};
  p.values = values;
  p.significant.assign(values.size(), 1);
  p.threshold = threshold;
  p.weight = 6.0f;  // a light of intensity 6: errors are measured in final-map units
  return p;
}

// The largest |decoded - value| over the texels' allowance, with the encoding `q` chose.
double worst_over_allowance(const SourcePatch& p, const QuantizedPatch& q) {
  double worst = 0.0;
  for (size_t i = 0; i < p.values.size(); ++i) {
    const double d = double(q.scale) * patch_decode_unit(q.codes[i], q.encoding);
    const double allowance = quantization_allowance(p.values[i], p.threshold, q.scale);
    worst = std::max(worst, std::fabs(d - p.values[i]) / allowance);
  }
  return worst;
}

// The small inn's torch: the end of its bracket, 3 cm from the light, gets 390 (at intensity 1),
// the wall beside it 0.47 and less, in one patch. Linear codes step by 390 / 255 = 1.5: every wall
// texel rounded to 0 (the wall 1.9 -> 0.13 in the recomposed map, where `bake-state` has 1.9).
TEST(PatchQuantize, ABracketBesideATorchKeepsTheWallsLight) {
  const float half_step = 0.0027f;  // the torch's half output step at intensity 1
  const SourcePatch p =
      row({389.4f, 375.7f, 182.9f, 0.47f, 0.3f, 0.12f, 0.05f, 0.02f, 0.006f}, half_step);
  const QuantizedPatch q = quantize_patch(p, EncodingPolicy::kAuto);
  EXPECT_EQ(q.encoding, pack::kEncodingSquare);
  // Linear would have lost the wall: its squared error is the smaller (the bracket's texels weigh
  // most), so the choice by squared error alone kept it.
  EXPECT_LT(q.error[0].sum_sq_error, q.error[1].sum_sq_error);
  EXPECT_GT(q.error[0].worst_over_allowance, 50.0);
  // No 8-bit code holds a range of 1e5 within a step everywhere (square codes step by about
  // 2 sqrt(v * scale) / 255 at v): the patch is reported (pack.encoding.patches_beyond_allowance)
  // and its wall is within a square code of its light (at most a quarter here) instead of lost.
  EXPECT_GT(q.error[1].worst_over_allowance, 1.0);
  EXPECT_LT(q.error[1].worst_over_allowance, q.error[0].worst_over_allowance / 10.0);
  EXPECT_NEAR(worst_over_allowance(p, q), q.error[1].worst_over_allowance, 1e-3);
  for (size_t i = 3; i < p.values.size(); ++i) {
    const double wall = double(q.scale) * patch_decode_unit(q.codes[i], q.encoding);
    EXPECT_NEAR(wall, p.values[i], 0.25 * p.values[i] + 2.0 * half_step) << i;
    EXPECT_GT(wall, 0.0) << i;
  }
}

// Where both encodings hold every texel (a patch within a few hundred steps, as nearly all are),
// the choice is the smaller squared error, as before; where neither does, the one that misses
// least. Random patches of every dynamic range, the two rules checked on each.
TEST(PatchQuantize, AutoHoldsEveryTexelWhereAnEncodingCanElseKeepsTheSmallerSquaredError) {
  std::mt19937 rng(7);
  std::uniform_real_distribution<float> unit(0.0f, 1.0f);
  int both_hold = 0, one_holds = 0, neither = 0;
  for (int trial = 0; trial < 400; ++trial) {
    const float half_step = 0.001f;
    // Peaks from 4 to 4e5 steps; values spread log-uniformly down to the threshold.
    const float peak = 2.0f * half_step * 4.0f * std::pow(10.0f, 5.0f * unit(rng));
    std::vector<float> v(64);
    for (float& x : v) x = std::max(1.01f * half_step, peak * std::pow(1e-6f, unit(rng)));
    v[0] = peak;
    const SourcePatch p = row(v, half_step);
    const QuantizedPatch q = quantize_patch(p, EncodingPolicy::kAuto);
    const double w0 = q.error[0].worst_over_allowance, w1 = q.error[1].worst_over_allowance;
    const double chosen = q.error[q.encoding].worst_over_allowance;
    EXPECT_NEAR(chosen, worst_over_allowance(p, q), 1e-4 * (1.0 + chosen));  // float codes
    if (w0 <= 1.0 && w1 <= 1.0) {
      ++both_hold;
      EXPECT_EQ(q.encoding, q.error[1].sum_sq_error < q.error[0].sum_sq_error
                                ? pack::kEncodingSquare
                                : pack::kEncodingLinear);
    } else {
      (w0 <= 1.0 || w1 <= 1.0) ? ++one_holds : ++neither;
      EXPECT_EQ(chosen, std::min(w0, w1));
    }
  }
  // The trials reach all three cases.
  EXPECT_GT(both_hold, 10);
  EXPECT_GT(one_holds, 10);
  EXPECT_GT(neither, 0);
}

}  // namespace
}  // namespace lightpatch::cooker
