// reduce_patch (patch_extract.h): a patch stored at a coarser level for the runtime to magnify
// (pack_format.h, "Magnified patches").
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>

#include "lightpatch/cooker/error.h"
#include "lightpatch/pack_format.h"
#include "patch_extract.h"

namespace lightpatch::cooker {
namespace {

// A w x h patch of a linear ramp per channel, significant except at texel (0, 0).
SourcePatch ramp(int w, int h, int channels) {
  SourcePatch p;
  p.channels = channels;
  p.dest = Rect{10, 20, w, h};
  p.values.resize(size_t(w) * h * channels);
  p.significant.assign(size_t(w) * h, 1);
  p.significant[0] = 0;
  for (int y = 0; y < h; ++y)
    for (int x = 0; x < w; ++x)
      for (int c = 0; c < channels; ++c)
        p.values[(size_t(y) * w + x) * channels + c] = 1.0f + 0.5f * x + 0.25f * y + float(c);
  return p;
}

// The runtime's magnification (pack_format.h), written out here on its own, at destination texel
// (x, y) of the patch, channel c.
double magnified(const SourcePatch& p, int x, int y, int c) {
  const int sw = p.stored_w(), sh = p.stored_h();
  const double k = double(1 << p.level);
  const double sx = (x + 0.5) / k - 0.5, sy = (y + 0.5) / k - 0.5;
  const double fx0 = std::floor(sx), fy0 = std::floor(sy);
  const double fx = sx - fx0, fy = sy - fy0;
  auto at = [&](double i, double j) {
    const int xi = std::clamp(int(i), 0, sw - 1), yj = std::clamp(int(j), 0, sh - 1);
    return double(p.values[(size_t(yj) * sw + xi) * p.channels + c]);
  };
  const double top = at(fx0, fy0) * (1 - fx) + at(fx0 + 1, fy0) * fx;
  const double bottom = at(fx0, fy0 + 1) * (1 - fx) + at(fx0 + 1, fy0 + 1) * fx;
  return top * (1 - fy) + bottom * fy;
}

TEST(PatchReduce, BlockMeansWithPartialEdgeBlocks) {
  SourcePatch p = ramp(5, 3, 3);
  const SourcePatch full = p;
  reduce_patch(p, 1);
  EXPECT_EQ(p.level, 1);
  EXPECT_EQ(p.dest.x, 10);  // the destination is unchanged
  EXPECT_EQ(p.dest.w, 5);
  ASSERT_EQ(p.stored_w(), 3);
  ASSERT_EQ(p.stored_h(), 2);
  ASSERT_EQ(p.values.size(), size_t(3 * 2 * 3));
  ASSERT_EQ(p.significant.size(), size_t(3 * 2));
  EXPECT_EQ(pack::patch_atlas_side(5, 1), 3u);  // the format's rule agrees
  auto v = [&](const SourcePatch& q, int x, int y, int c) {
    return q.values[(size_t(y) * q.stored_w() + x) * q.channels + c];
  };
  for (int c = 0; c < 3; ++c) {
    // A full block, a block two texels wide and one high, and the one-texel corner block.
    EXPECT_FLOAT_EQ(
        v(p, 0, 0, c),
        (v(full, 0, 0, c) + v(full, 1, 0, c) + v(full, 0, 1, c) + v(full, 1, 1, c)) / 4.0f);
    EXPECT_FLOAT_EQ(v(p, 1, 1, c), (v(full, 2, 2, c) + v(full, 3, 2, c)) / 2.0f);
    EXPECT_FLOAT_EQ(v(p, 2, 1, c), v(full, 4, 2, c));
  }
  // Significant where any texel of the block is: (0, 0) of the full patch is not, but its block
  // has three that are.
  for (uint8_t s : p.significant) EXPECT_EQ(s, 1);
}

TEST(PatchReduce, MagnificationGivesALinearRampBackWhereBlocksAreWhole) {
  for (int level = 1; level <= 2; ++level) {
    SourcePatch p = ramp(16, 12, 1);
    const SourcePatch full = p;
    reduce_patch(p, level);
    const int b = 1 << level;
    double worst = 0.0, edge = 0.0;
    for (int y = 0; y < 12; ++y) {
      for (int x = 0; x < 16; ++x) {
        const double e = std::fabs(magnified(p, x, y, 0) - full.values[size_t(y) * 16 + x]);
        // Inside: the texel's sample point lies between stored texel centres on both axes.
        const bool inside = x >= b / 2 && x < 16 - b / 2 && y >= b / 2 && y < 12 - b / 2;
        (inside ? worst : edge) = std::max(inside ? worst : edge, e);
      }
    }
    EXPECT_LT(worst, 1e-5) << "level " << level;
    // At the edges the clamp holds the last block's mean: off by up to (2^level - 1) / 2 texels
    // of the ramp's slope (0.5 per texel in x), which a nearest-texel magnification would also
    // be inside.
    EXPECT_GT(edge, 0.0) << "level " << level;
    EXPECT_LE(edge, 0.5 * 0.5 * (b - 1) + 0.25 * 0.5 * (b - 1) + 1e-5) << "level " << level;
  }
}

// A w x h one-channel patch of slope g per texel along x.
SourcePatch ramp_x(int w, int h, float g) {
  SourcePatch p;
  p.dest = Rect{0, 0, w, h};
  p.values.resize(size_t(w) * h);
  p.significant.assign(size_t(w) * h, 1);
  for (int y = 0; y < h; ++y)
    for (int x = 0; x < w; ++x) p.values[size_t(y) * w + x] = 100.0f + g * float(x);
  return p;
}

// Worst error of a ramp's magnification at `level`, stored as coarsest_level() stores it (block
// means, then fit_patch), the runtime's magnification written out above.
double fitted_worst(const SourcePatch& p, int level) {
  SourcePatch r = p;
  reduce_patch(r, level);
  fit_patch(p, r);
  double worst = 0.0;
  for (int y = 0; y < p.dest.h; ++y)
    for (int x = 0; x < p.dest.w; ++x)
      worst =
          std::max(worst, std::fabs(magnified(r, x, y, 0) - p.values[size_t(y) * p.dest.w + x]));
  return worst;
}

TEST(CoarsestLevel, ARampKeepsTheLevelsWhoseEdgeErrorIsWithinTheTolerance) {
  // The error grows with the level (the clamped edges miss more of the ramp), and a level is kept
  // exactly when its error is within the tolerance.
  const SourcePatch p = ramp_x(32, 16, 1.0f);
  const double e1 = fitted_worst(p, 1), e2 = fitted_worst(p, 2), e3 = fitted_worst(p, 3);
  EXPECT_LT(e1, e2);
  EXPECT_LT(e2, e3);
  EXPECT_LT(e3, 3.5);  // block means: 3.5 at level 3 (FitPatch below)
  EXPECT_EQ(coarsest_level(p, 3, float(0.99 * e1)), 0);
  EXPECT_EQ(coarsest_level(p, 3, float(1.01 * e1)), 1);
  EXPECT_EQ(coarsest_level(p, 3, float(0.99 * e2)), 1);
  EXPECT_EQ(coarsest_level(p, 3, float(1.01 * e2)), 2);
  EXPECT_EQ(coarsest_level(p, 3, float(1.01 * e3)), 3);
  EXPECT_EQ(coarsest_level(p, 2, float(1.01 * e3)), 2);  // never above the maximum asked for
  EXPECT_EQ(coarsest_level(p, 0, 100.0f), 0);
}

// Worst and mean signed error of a reduced patch's magnification against its level-0 patch, over
// the texels where `where` holds (all by default).
struct MagnifyError {
  double worst = 0.0, mean = 0.0, rms = 0.0;
};
MagnifyError magnify_error(const SourcePatch& full, const SourcePatch& reduced,
                           bool (*where)(int x, int y, int w) = nullptr) {
  MagnifyError e;
  int n = 0;
  for (int y = 0; y < full.dest.h; ++y)
    for (int x = 0; x < full.dest.w; ++x) {
      if (where && !where(x, y, full.dest.w)) continue;
      for (int c = 0; c < full.channels; ++c) {
        const double d = magnified(reduced, x, y, c) -
                         full.values[(size_t(y) * full.dest.w + x) * full.channels + c];
        e.worst = std::max(e.worst, std::fabs(d));
        e.mean += d;
        e.rms += d * d;
        ++n;
      }
    }
  e.mean /= n;
  e.rms = std::sqrt(e.rms / n);
  return e;
}

// Block means miss a ramp by (2^L - 1) / 2 slopes at the clamped edges; the fit spreads that over
// the texels beside them (measured: 0.63x the worst and 0.71x the RMS error at level 3).
TEST(FitPatch, ARampsEdgeErrorFallsWellBelowTheBlockMeans) {
  const SourcePatch p = ramp_x(32, 16, 1.0f);
  for (int level = 1; level <= 3; ++level) {
    SourcePatch means = p;
    reduce_patch(means, level);
    SourcePatch fitted = means;
    fit_patch(p, fitted);
    const double block = 0.5 * ((1 << level) - 1);
    EXPECT_NEAR(magnify_error(p, means).worst, block, 1e-4) << "level " << level;
    EXPECT_LT(magnify_error(p, fitted).worst, 0.7 * block) << "level " << level;
    EXPECT_LT(magnify_error(p, fitted).rms, 0.8 * magnify_error(p, means).rms) << "level " << level;
  }
}

// A light's falloff (convex, 1 / (1 + d^2)): block means lift its dim side (the box and the tent
// both average over the curve's bend); the fit does not, and is closer everywhere in the mean.
TEST(FitPatch, AFalloffIsNotLiftedOnItsDimSide) {
  SourcePatch p = ramp_x(48, 8, 0.0f);
  for (int y = 0; y < 8; ++y)
    for (int x = 0; x < 48; ++x) {
      const double d = 0.25 * x;
      p.values[size_t(y) * 48 + x] = float(100.0 / (1.0 + d * d));
    }
  SourcePatch means = p;
  reduce_patch(means, 2);
  SourcePatch fitted = means;
  fit_patch(p, fitted);
  auto dim = [](int x, int, int) { return x >= 16; };  // under 6 % of the peak
  const MagnifyError m = magnify_error(p, means, dim), f = magnify_error(p, fitted, dim);
  EXPECT_GT(m.mean, 0.04);  // lifted
  EXPECT_LT(std::fabs(f.mean), 0.25 * m.mean);
  EXPECT_LT(f.rms, m.rms);
  EXPECT_LT(magnify_error(p, fitted).rms, magnify_error(p, means).rms);
  // Its level: the fit passes a tolerance the block means do not.
  const double tol = 0.5 * (magnify_error(p, fitted).worst + magnify_error(p, means).worst);
  ASSERT_GT(magnify_error(p, means).worst, magnify_error(p, fitted).worst);
  SourcePatch chosen;
  EXPECT_GE(coarsest_level(p, 2, float(tol), &chosen), 2);
  EXPECT_EQ(chosen.values, fitted.values);  // what coarsest_level checked is what it hands back
}

// Magnitudes stay >= 0 where light drops to nothing (a least-squares fit overshoots below zero
// beside a step), and every value stays finite.
TEST(FitPatch, StoredValuesStayNonNegativeBesideAStep) {
  SourcePatch p = ramp_x(16, 16, 0.0f);
  for (int y = 0; y < 16; ++y)
    for (int x = 0; x < 16; ++x) p.values[size_t(y) * 16 + x] = x < 7 ? 80.0f : 0.0f;
  for (int level = 1; level <= 3; ++level) {
    SourcePatch r = p;
    reduce_patch(r, level);
    fit_patch(p, r);
    for (float v : r.values) {
      EXPECT_TRUE(std::isfinite(v));
      EXPECT_GE(v, 0.0f);
    }
  }
}

// Each texel's error counts as a share of its own tolerance: texels with a tight one (scale 1,
// beside texels at scale 4) are matched closer than with one weight for all.
TEST(FitPatch, TexelsOfATightToleranceAreMatchedCloser) {
  SourcePatch p = ramp_x(16, 16, 0.0f);
  for (int y = 0; y < 16; ++y)
    for (int x = 0; x < 16; ++x) {
      const double d = 0.3 * (x - 3);
      p.values[size_t(y) * 16 + x] = float(50.0 * std::exp(-d * d));
    }
  SourcePatch even = p;
  reduce_patch(even, 2);
  SourcePatch weighted = even;
  fit_patch(p, even);
  p.tolerance_scale.assign(16 * 16, 4.0f);
  for (int y = 0; y < 16; ++y)
    for (int x = 8; x < 16; ++x) p.tolerance_scale[size_t(y) * 16 + x] = 1.0f;
  fit_patch(p, weighted);
  auto tight = [](int x, int, int) { return x >= 8; };
  EXPECT_LT(magnify_error(p, weighted, tight).rms, magnify_error(p, even, tight).rms);
}

TEST(FitPatch, RefusesAPatchThatIsNotTheReductionOfTheOther) {
  const SourcePatch p = ramp_x(16, 8, 1.0f);
  SourcePatch r = p;
  EXPECT_THROW(fit_patch(p, r), CookError);  // not reduced
  reduce_patch(r, 1);
  SourcePatch other = ramp_x(8, 8, 1.0f);
  EXPECT_THROW(fit_patch(other, r), CookError);  // another rectangle
  EXPECT_THROW(fit_patch(r, r), CookError);      // a reduced patch as the full one
}

TEST(CoarsestLevel, ASharpEdgeStaysAtFullResolutionAndAFlatPatchGoesToTheTop) {
  SourcePatch edge = ramp_x(16, 16, 0.0f);
  for (int y = 0; y < 16; ++y)
    for (int x = 9; x < 16; ++x) edge.values[size_t(y) * 16 + x] = 50.0f;  // a shadow's edge
  EXPECT_EQ(coarsest_level(edge, 3, 1.0f), 0);
  EXPECT_EQ(coarsest_level(ramp_x(16, 16, 0.0f), 3, 1e-6f), 3);
  // One texel: nothing to gain.
  EXPECT_EQ(coarsest_level(ramp_x(1, 1, 0.0f), 3, 1.0f), 0);
  // Three channels: one channel's edge is enough to keep the patch at level 0.
  SourcePatch tinted = ramp(16, 16, 3);
  for (float& v : tinted.values) v = 1.0f;
  EXPECT_EQ(coarsest_level(tinted, 2, 0.1f), 2);
  tinted.values[(size_t(5) * 16 + 5) * 3 + 2] = 3.0f;
  EXPECT_EQ(coarsest_level(tinted, 2, 0.1f), 0);
  // A patch already magnified is refused.
  SourcePatch reduced = ramp_x(8, 8, 0.0f);
  reduce_patch(reduced, 1);
  EXPECT_THROW(coarsest_level(reduced, 2, 1.0f), CookError);
}

// A texel's tolerance scale (the pack builder's looser tolerance where a map holds bounce light
// alone) lets the magnification blur there, and only there.
TEST(CoarsestLevel, ATexelsToleranceScaleLoosensItsBoundAlone) {
  SourcePatch edge = ramp_x(16, 16, 0.0f);
  for (int y = 0; y < 16; ++y)
    for (int x = 9; x < 16; ++x) edge.values[size_t(y) * 16 + x] = 102.0f;  // a 2-unit step
  EXPECT_EQ(coarsest_level(edge, 3, 0.5f), 0);
  // Loose (x8) everywhere: the step's blur (at most 2) is within 4.
  edge.tolerance_scale.assign(16 * 16, 8.0f);
  EXPECT_EQ(coarsest_level(edge, 1, 0.5f), 1);
  // Strict at the two texels each side of the step (one row): level 0 again. (One strict texel
  // alone is not enough: fit_patch bends the magnification to meet it.)
  for (int x = 7; x <= 10; ++x) edge.tolerance_scale[size_t(4) * 16 + x] = 1.0f;
  EXPECT_EQ(coarsest_level(edge, 1, 0.5f), 0);
  // Strict far from the step, where the magnification is exact: level 1 stays.
  for (int x = 7; x <= 10; ++x) edge.tolerance_scale[size_t(4) * 16 + x] = 8.0f;
  edge.tolerance_scale[size_t(4) * 16 + 2] = 1.0f;
  EXPECT_EQ(coarsest_level(edge, 1, 0.5f), 1);
  // Cut pieces keep their texels' scales; a reduced patch drops them (checked at level 0 only).
  edge.threshold = 1.0f;
  const std::vector<SourcePatch> cut = cut_patch(edge, {Rect{2, 3, 8, 4}});
  ASSERT_EQ(cut.size(), 1u);
  ASSERT_EQ(cut[0].tolerance_scale.size(), size_t(8 * 4));
  EXPECT_EQ(cut[0].tolerance_scale[size_t(1) * 8 + 0], 1.0f);  // texel (2, 4) of the patch
  EXPECT_EQ(cut[0].tolerance_scale[0], 8.0f);
  SourcePatch reduced = edge;
  reduce_patch(reduced, 1);
  EXPECT_TRUE(reduced.tolerance_scale.empty());
}

// Two charts side by side in one region (a 2-texel gap between them), lit 2 and 50: the step at
// their border keeps the whole patch at level 0, while each chart alone is flat.
TEST(SplitByCharts, EachChartIsCutOnItsOwnAndMagnifiedAlone) {
  SourcePatch p = ramp_x(40, 16, 0.0f);
  p.dest = Rect{10, 20, 40, 16};
  for (int y = 0; y < 16; ++y)
    for (int x = 0; x < 40; ++x) {
      const size_t t = size_t(y) * 40 + size_t(x);
      p.values[t] = x < 18 ? 2.0f : x < 20 ? 0.0f : 50.0f;
      p.significant[t] = x < 18 || x >= 20 ? 1 : 0;
    }
  EXPECT_EQ(coarsest_level(p, 3, 1.0f), 0);
  Region region;
  region.rect = Rect{10, 20, 40, 16};
  region.charts = {Rect{10, 20, 18, 16}, Rect{30, 20, 20, 16}};
  Region elsewhere;  // overlaps nothing of the patch: not read
  elsewhere.rect = Rect{100, 100, 8, 8};
  elsewhere.charts = {Rect{100, 100, 4, 8}, Rect{104, 100, 4, 8}};
  const std::vector<SourcePatch> pieces = split_by_charts(p, {elsewhere, region});
  ASSERT_EQ(pieces.size(), 2u);
  EXPECT_EQ(pieces[0].dest.x, 10);
  EXPECT_EQ(pieces[0].dest.w, 18);
  EXPECT_EQ(pieces[1].dest.x, 30);
  EXPECT_EQ(pieces[1].dest.w, 20);
  for (const SourcePatch& q : pieces) {
    EXPECT_EQ(q.dest.y, 20);
    EXPECT_EQ(q.dest.h, 16);
    const float want = q.dest.x == 10 ? 2.0f : 50.0f;
    for (float v : q.values) EXPECT_EQ(v, want);
    EXPECT_EQ(coarsest_level(q, 3, 1.0f), 3);
  }
  // Inset by a ring: each piece loses its chart rectangle's outer ring of texels.
  const std::vector<SourcePatch> inset = split_by_charts(p, {region}, 1);
  ASSERT_EQ(inset.size(), 2u);
  EXPECT_EQ(inset[0].dest.x, 11);
  EXPECT_EQ(inset[0].dest.y, 21);
  EXPECT_EQ(inset[0].dest.w, 16);
  EXPECT_EQ(inset[0].dest.h, 14);
  EXPECT_EQ(inset[1].dest.x, 31);
  EXPECT_EQ(inset[1].dest.w, 18);
  // One chart: nothing to cut.
  region.charts = {Rect{10, 20, 40, 16}};
  EXPECT_TRUE(split_by_charts(p, {region}).empty());
}

TEST(CutPatch, CellsAreClippedToThePatchAndShrunkToTheirSignificantTexels) {
  SourcePatch p = ramp_x(8, 8, 0.0f);  // 100 everywhere
  p.threshold = 1000.0f;               // so nothing is kept for its value alone
  for (int y = 0; y < 8; ++y)
    for (int x = 0; x < 8; ++x) p.significant[size_t(y) * 8 + x] = x >= 2 && y >= 3 ? 1 : 0;
  // Half outside, wholly outside (right and above), empty of significant texels.
  const std::vector<SourcePatch> cut =
      cut_patch(p, {Rect{-4, -4, 8, 10}, Rect{9, 0, 4, 4}, Rect{0, -6, 4, 4}, Rect{0, 0, 2, 8}});
  ASSERT_EQ(cut.size(), 1u);
  EXPECT_EQ(cut[0].dest.x, p.dest.x + 2);
  EXPECT_EQ(cut[0].dest.y, p.dest.y + 3);
  EXPECT_EQ(cut[0].dest.w, 2);
  EXPECT_EQ(cut[0].dest.h, 3);
  EXPECT_EQ(cut[0].values[0], p.values[size_t(3) * 8 + 2]);
  // Dim light beside the significant texels (above kCutKeepFraction of the threshold) stays in
  // the piece; below it, it is cut away.
  p.values[size_t(1) * 8 + 3] = kCutKeepFraction * p.threshold * 1.01f;
  p.values[size_t(3) * 8 + 0] = kCutKeepFraction * p.threshold * 0.99f;
  const std::vector<SourcePatch> dim = cut_patch(p, {Rect{0, 0, 4, 8}});
  ASSERT_EQ(dim.size(), 1u);
  EXPECT_EQ(dim[0].dest.x, p.dest.x + 2);
  EXPECT_EQ(dim[0].dest.y, p.dest.y + 1);
  EXPECT_EQ(dim[0].dest.w, 2);
  EXPECT_EQ(dim[0].dest.h, 7);
}

TEST(PatchReduce, RefusesALevelOutOfRangeOrTwice) {
  SourcePatch p = ramp(4, 4, 1);
  EXPECT_THROW(reduce_patch(p, 0), CookError);
  EXPECT_THROW(reduce_patch(p, int(pack::kMaxPatchLevel) + 1), CookError);
  reduce_patch(p, 1);
  EXPECT_THROW(reduce_patch(p, 1), CookError);
}

}  // namespace
}  // namespace lightpatch::cooker
