// The recomposition planner without GL: budgets, atomic changes, latency, changes during a
// rebuild, the clamp at zero of what is presented, the value limit, and drift under half-float
// rounding to nearest and toward zero (CpuMapSink rounds like an RGBA16F target).
#include "lightpatch/planner.h"

#include <gtest/gtest.h>

#include <memory>
#include <random>

#include "runtime/map_reference.h"
#include "runtime/synthetic_pack.h"

namespace lightpatch {
namespace {

using testing::CpuMapSink;
using testing::make_synthetic_pack;
using testing::presented;
using testing::reference_map;
using testing::Rounding;
using testing::SyntheticOptions;

constexpr uint64_t kUnlimited = ~0ull >> 1;

double max_abs_diff(const std::vector<float>& a, const std::vector<double>& b) {
  double m = 0;
  for (size_t i = 0; i < a.size(); ++i) m = std::max(m, std::fabs(double(a[i]) - b[i]));
  return m;
}

struct Fixture {
  explicit Fixture(const SyntheticOptions& o, Rounding rounding = Rounding::kNone)
      : bytes(make_synthetic_pack(o)) {
    Error error;
    EXPECT_TRUE(bytes.open(&pack, &error)) << error.message;
    EXPECT_EQ(planner.init(pack, PlannerLimits(), &error), Status::kOk) << error.message;
    // What the sink does: float rounding to nearest, or a half float (a full ulp per write where
    // it truncates).
    TargetPrecision precision;
    if (rounding == Rounding::kHalfNearest) precision = TargetPrecision{1.0f / 2048.0f, false};
    if (rounding == Rounding::kHalfTowardZero) precision = TargetPrecision{1.0f / 1024.0f, true};
    planner.set_precision(precision);
    sink = std::make_unique<CpuMapSink>(pack, rounding);
  }
  // Runs frames until idle; returns the frame count.
  int settle(uint64_t budget, int max_frames = 10000) {
    int frames = 0;
    while (!planner.idle() && frames < max_frames) {
      planner.update(budget, *sink);
      ++frames;
    }
    return frames;
  }
  void random_change(std::mt19937& rng) {
    std::uniform_real_distribution<float> u(0.0f, 1.0f);
    if (pack.object_count() > 0 && u(rng) < 0.4f) {
      const uint32_t o = rng() % pack.object_count();
      ASSERT_EQ(planner.set_object_visible(o, !planner.object_visible(o)), Status::kOk);
    } else {
      const uint32_t l = rng() % pack.light_count();
      const float c[3] = {u(rng), u(rng), u(rng)};
      ASSERT_EQ(planner.set_light(l, u(rng) < 0.8f, c, 4.0f * u(rng)), Status::kOk);
    }
  }
  testing::SyntheticPack bytes;
  PackView pack;
  Planner planner;
  std::unique_ptr<CpuMapSink> sink;
};

TEST(Planner, FirstBuildMatchesTheFormulaAndCostsWhatItSaid) {
  Fixture f(SyntheticOptions{});
  const uint64_t predicted = f.planner.rebuild_texels();
  EXPECT_FALSE(f.planner.map_ready());
  f.planner.update(kUnlimited, *f.sink);
  EXPECT_TRUE(f.planner.map_ready());
  EXPECT_TRUE(f.planner.idle());
  EXPECT_EQ(f.sink->texels, predicted);
  EXPECT_EQ(f.planner.stats().texels, predicted);
  EXPECT_EQ(f.sink->presents, 1u);
  const auto ref =
      presented(f.pack, reference_map(f.pack, testing::wanted_state(f.planner, f.pack)));
  EXPECT_LT(max_abs_diff(f.sink->sampled(), ref), 1e-4);
  EXPECT_EQ(f.sink->whole_presents, 1u);
}

TEST(Planner, BudgetNeverExceededAndNoPartialStateSampled) {
  for (uint32_t seed = 1; seed <= 4; ++seed) {
    SyntheticOptions o;
    o.seed = seed;
    o.indirect_scale = seed == 1 ? 0 : 1u << (seed - 1);  // none, then 1/2, 1/4, 1/8
    Fixture f(o);
    std::mt19937 rng(seed);
    const uint64_t budgets[] = {50, 300, 1000, 5000};
    for (int frame = 0; frame < 400; ++frame) {
      if (rng() % 3 == 0) f.random_change(rng);
      const uint64_t budget = budgets[rng() % 4];
      const uint64_t before = f.sink->texels, indirect_before = f.sink->indirect_texels;
      f.planner.update(budget, *f.sink);
      const FrameStats& s = f.planner.stats();
      ASSERT_EQ(f.sink->texels - before, s.texels);  // both targets, each in its own texels
      ASSERT_EQ(f.sink->indirect_texels - indirect_before, s.indirect_texels);
      if (s.oversize_steps == 0) {
        ASSERT_LE(s.texels, budget) << "frame " << frame;
      } else {
        ASSERT_LE(s.draws, 1u) << "frame " << frame << " budget " << budget << " texels "
                               << s.texels;  // an oversize step runs alone
      }
      if (f.planner.map_ready()) {
        // The sampled map is exactly the presented state: never half of a change.
        const auto ref =
            presented(f.pack, reference_map(f.pack, testing::shown_state(f.planner, f.pack)));
        ASSERT_LT(max_abs_diff(f.sink->sampled(), ref), 1e-3)
            << "seed " << seed << " frame " << frame;
      }
    }
  }
}

TEST(Planner, SmallChangeIsIncrementalAndLandsInOneFrame) {
  Fixture f(SyntheticOptions{});
  f.settle(kUnlimited);
  const uint32_t presents = f.sink->whole_presents;
  const float c[3] = {0.3f, 0.6f, 0.9f};
  ASSERT_EQ(f.planner.set_light(1, true, c, 2.0f), Status::kOk);
  const uint64_t cost = f.planner.light_change_texels(1);
  ASSERT_LT(cost, f.planner.rebuild_texels());
  f.planner.update(cost, *f.sink);  // exactly the change's cost fits
  EXPECT_TRUE(f.planner.idle());
  EXPECT_EQ(f.sink->whole_presents, presents);  // no rebuild
  EXPECT_EQ(f.planner.stats().texels, cost);
  EXPECT_EQ(f.planner.stats().completed_changes, 1u);
  EXPECT_EQ(f.planner.stats().max_latency_frames, 1u);
  // One draw and one present per group of the light (contribution + its visible shadow/pair
  // groups; every object is visible).
  uint32_t groups = 0;
  for (uint32_t g = 0; g < f.pack.group_count(); ++g) groups += f.pack.group(g).light == 1;
  EXPECT_EQ(f.planner.stats().draws, 2 * groups);
  const auto ref =
      presented(f.pack, reference_map(f.pack, testing::wanted_state(f.planner, f.pack)));
  EXPECT_LT(max_abs_diff(f.sink->sampled(), ref), 1e-4);

  // A light change and an object toggle in one frame whose budget is one texel short of both:
  // the light lands, the toggle waits whole for the next frame.
  const float c2[3] = {0.9f, 0.2f, 0.1f};
  ASSERT_EQ(f.planner.set_light(0, true, c2, 1.5f), Status::kOk);
  ASSERT_EQ(f.planner.set_object_visible(0, false), Status::kOk);
  const uint64_t light_cost = f.planner.light_change_texels(0);
  const uint64_t toggle = f.planner.object_change_texels(0);
  ASSERT_GT(toggle, 0u);
  f.planner.update(light_cost + toggle - 1, *f.sink);
  EXPECT_EQ(f.planner.stats().texels, light_cost);
  EXPECT_EQ(f.planner.stats().pending_changes, 1u);
  EXPECT_EQ(f.planner.stats().oldest_pending_frames, 1u);
  f.planner.update(toggle, *f.sink);
  EXPECT_TRUE(f.planner.idle());
  EXPECT_EQ(f.planner.stats().texels, toggle);
  EXPECT_EQ(f.planner.stats().max_latency_frames, 2u);
  EXPECT_EQ(f.sink->whole_presents, presents);
  const auto ref2 =
      presented(f.pack, reference_map(f.pack, testing::wanted_state(f.planner, f.pack)));
  EXPECT_LT(max_abs_diff(f.sink->sampled(), ref2), 1e-4);
}

// With an indirect map, a change's cost is exact in the texels of each target it writes: an
// indirect patch costs its own coarse texels, a group with patches in both maps is one draw and
// one present per target, and the clear and the whole-map present cover both maps.
TEST(Planner, CostsAreExactInTheTexelsOfEachTarget) {
  SyntheticOptions o;
  o.seed = 9;
  o.indirect_scale = 4;  // 12x10 indirect texels under the 48x40 light map
  o.indirect_patches_per_group = 3;
  o.bounce_covers_map = true;  // every contribution also covers the whole indirect map
  Fixture f(o);
  const uint64_t maps = 48 * 40 + 12 * 10;
  EXPECT_EQ(f.planner.clear_texels(), maps);
  // Sums over the pack's records, target by target.
  auto area = [&](uint32_t p) { return uint64_t(f.pack.patch(p).width) * f.pack.patch(p).height; };
  uint64_t all = 0;
  for (uint32_t p = 0; p < f.pack.patch_count(); ++p) all += area(p);
  EXPECT_EQ(f.planner.rebuild_texels(), 2 * maps + all);  // every group active at first
  f.settle(kUnlimited);

  const uint32_t l = 1;
  TargetTexels want;
  uint32_t steps = 0;
  for (uint32_t g = 0; g < f.pack.group_count(); ++g) {
    const pack::GroupRecord& gr = f.pack.group(g);
    if (gr.light != l) continue;  // every object is visible: all of the light's groups change
    bool target_seen[2] = {false, false};
    for (uint32_t p = gr.first_patch; p < gr.first_patch + gr.patch_count; ++p) {
      const uint8_t t = f.pack.patch(p).target;
      (t == pack::kTargetIndirectMap ? want.indirect_map : want.light_map) += 2 * area(p);
      target_seen[t] = true;
    }
    EXPECT_EQ(f.planner.group_indirect_first(g) - gr.first_patch, [&] {
      uint32_t n = 0;
      for (uint32_t p = gr.first_patch; p < gr.first_patch + gr.patch_count; ++p)
        n += f.pack.patch(p).target == pack::kTargetLightMap;
      return n;
    }());
    steps += 2 * (uint32_t(target_seen[0]) + uint32_t(target_seen[1]));
  }
  ASSERT_GT(want.indirect_map, 0u);
  const TargetTexels cost = f.planner.light_change_cost(l);
  EXPECT_EQ(cost.light_map, want.light_map);
  EXPECT_EQ(cost.indirect_map, want.indirect_map);
  EXPECT_EQ(f.planner.light_change_texels(l), want.total());
  const float c[3] = {0.3f, 0.6f, 0.9f};
  ASSERT_EQ(f.planner.set_light(l, true, c, 2.0f), Status::kOk);
  const uint64_t before = f.sink->indirect_texels;
  f.planner.update(want.total(), *f.sink);  // exactly the change's cost fits
  EXPECT_TRUE(f.planner.idle());
  EXPECT_EQ(f.planner.stats().texels, want.total());
  EXPECT_EQ(f.planner.stats().indirect_texels, want.indirect_map);
  EXPECT_EQ(f.sink->indirect_texels - before, want.indirect_map);
  EXPECT_EQ(f.planner.stats().draws, steps);
  const auto ref =
      presented(f.pack, reference_map(f.pack, testing::wanted_state(f.planner, f.pack)));
  EXPECT_LT(max_abs_diff(f.sink->sampled(), ref), 1e-4);

  // An object toggle: the split of its groups, as predicted.
  const TargetTexels toggle = f.planner.object_change_cost(0);
  ASSERT_EQ(f.planner.set_object_visible(0, false), Status::kOk);
  f.planner.update(toggle.total(), *f.sink);
  EXPECT_TRUE(f.planner.idle());
  EXPECT_EQ(f.planner.stats().texels, toggle.total());
  EXPECT_EQ(f.planner.stats().indirect_texels, toggle.indirect_map);

  // A full rebuild: both maps cleared and presented whole.
  f.planner.request_rebuild();
  const uint64_t rebuild = f.planner.rebuild_texels();
  uint64_t texels = 0, indirect = 0;
  while (!f.planner.idle()) {
    f.planner.update(kUnlimited, *f.sink);
    texels += f.planner.stats().texels;
    indirect += f.planner.stats().indirect_texels;
  }
  EXPECT_EQ(texels, rebuild);
  EXPECT_GE(indirect, 2u * 12u * 10u);
}

TEST(Planner, ChangesDuringARebuildAreNotLostAndLatencyIsBounded) {
  for (uint32_t seed = 1; seed <= 3; ++seed) {
    SyntheticOptions o;
    o.seed = seed;
    Fixture f(o);
    const uint64_t budget = 400;
    std::mt19937 rng(seed);
    // Mid first build: changes arrive every frame for a while.
    uint32_t worst = 0;
    for (int frame = 0; frame < 60; ++frame) {
      if (frame < 20) f.random_change(rng);
      f.planner.update(budget, *f.sink);
      worst = std::max(worst, f.planner.stats().max_latency_frames);
    }
    f.settle(budget);
    ASSERT_TRUE(f.planner.idle());
    const auto ref =
        presented(f.pack, reference_map(f.pack, testing::wanted_state(f.planner, f.pack)));
    EXPECT_LT(max_abs_diff(f.sink->sampled(), ref), 1e-3);
    // Bound: a change waits for at most the running rebuild and one more of its own.
    const uint64_t rebuild = f.planner.rebuild_texels();
    const uint32_t bound = uint32_t(2 * ((rebuild + budget - 1) / budget) + 3);
    EXPECT_LE(worst, bound);
  }
}

TEST(Planner, OversizeStepsRunAloneAndStillFinish) {
  SyntheticOptions o;
  o.max_patch = 12;
  Fixture f(o);
  const uint64_t budget = 20;  // smaller than many patches and than the clear
  int frames = f.settle(budget);
  EXPECT_TRUE(f.planner.idle());
  EXPECT_GT(frames, 1);
  const auto ref =
      presented(f.pack, reference_map(f.pack, testing::wanted_state(f.planner, f.pack)));
  EXPECT_LT(max_abs_diff(f.sink->sampled(), ref), 1e-4);
}

// Over 10,000 random changes on a half-float target (rounding to nearest, then truncating), the
// sampled map stays within the planner's relative bound plus one rebuild's rounding of each
// texel's magnitude; the bound forced rebuilds on the way.
void no_drift_on_a_half_float_target(Rounding rounding) {
  SyntheticOptions o;
  o.seed = 7;
  o.width = 24;
  o.height = 20;
  o.max_patch = 6;
  Fixture f(o, rounding);
  f.settle(kUnlimited);
  std::mt19937 rng(99);
  const uint32_t rebuilds_before = f.sink->whole_presents;
  for (int i = 0; i < 10000; ++i) {
    f.random_change(rng);
    f.planner.update(kUnlimited, *f.sink);
    ASSERT_TRUE(f.planner.idle());
    ASSERT_LE(f.planner.stats().error_bound, PlannerLimits().drift_tolerance);
  }
  EXPECT_GT(f.sink->whole_presents, rebuilds_before + 100);  // the drift bound forced rebuilds
  std::vector<double> magnitude;
  const auto ref = presented(
      f.pack, reference_map(f.pack, testing::wanted_state(f.planner, f.pack), &magnitude));
  const double u = rounding == Rounding::kHalfNearest ? 1.0 / 2048.0 : 1.0 / 1024.0;
  const double bound = f.planner.stats().error_bound;
  const auto& got = f.sink->sampled();
  for (size_t i = 0; i < got.size(); ++i) {
    const double rebuild_rounding = double(f.pack.group_count()) * u;
    ASSERT_LE(std::fabs(got[i] - ref[i]), (bound + rebuild_rounding) * magnitude[i] + 1e-6)
        << "texel " << i / 3;
  }
}

TEST(Planner, NoDriftAfterTenThousandChangesOnAHalfFloatTargetRoundingToNearest) {
  no_drift_on_a_half_float_target(Rounding::kHalfNearest);
}

TEST(Planner, NoDriftAfterTenThousandChangesOnAHalfFloatTargetThatTruncates) {
  no_drift_on_a_half_float_target(Rounding::kHalfTowardZero);
}

// The drift bound is relative to each texel: turning the brightest light off subtracts terms far
// larger than what remains. On a float target the change stays incremental; on a truncating
// half-float target (a full ulp lost per write, biased) the planner rebuilds instead.
TEST(Planner, TurningALightOffRebuildsOnATruncatingTargetOnly) {
  SyntheticOptions o;
  o.seed = 3;
  for (Rounding r : {Rounding::kNone, Rounding::kHalfTowardZero}) {
    Fixture f(o, r);
    f.settle(kUnlimited);
    const uint32_t before = f.sink->whole_presents;
    const float white[3] = {1.0f, 1.0f, 1.0f};
    ASSERT_EQ(f.planner.set_light(0, false, white, 1.0f), Status::kOk);
    f.planner.update(kUnlimited, *f.sink);
    EXPECT_TRUE(f.planner.idle());
    EXPECT_EQ(f.sink->whole_presents - before, r == Rounding::kNone ? 0u : 1u);
    const auto ref =
        presented(f.pack, reference_map(f.pack, testing::wanted_state(f.planner, f.pack)));
    EXPECT_LT(max_abs_diff(f.sink->sampled(), ref), r == Rounding::kNone ? 1e-4 : 0.05);
  }
}

// On a float target the bound grows with the draws and with the ratio by which a light dims.
TEST(Planner, DriftBoundCountsDrawsAndDimming) {
  Fixture f(SyntheticOptions{});
  f.settle(kUnlimited);
  EXPECT_EQ(f.planner.stats().error_bound, 0.0f);
  const float white[3] = {1.0f, 1.0f, 1.0f};
  ASSERT_EQ(f.planner.set_light(1, true, white, 4.0f), Status::kOk);
  f.planner.update(kUnlimited, *f.sink);
  const float after_one = f.planner.stats().error_bound;
  EXPECT_GT(after_one, 0.0f);
  ASSERT_EQ(f.planner.set_light(1, true, white, 0.04f), Status::kOk);  // dimmed 100x
  f.planner.update(kUnlimited, *f.sink);
  EXPECT_GT(f.planner.stats().error_bound, 50.0f * after_one);
  ASSERT_EQ(f.planner.set_light(1, true, white, 4.0f), Status::kOk);  // and back
  f.planner.update(kUnlimited, *f.sink);
  EXPECT_LT(f.planner.stats().error_bound, 5.0f * after_one);
}

// What the game samples is clamped at zero; the accumulator keeps the signed sum, so a later
// change that adds light back is exact.
TEST(Planner, PresentedMapIsClampedAtZero) {
  SyntheticOptions o;
  o.seed = 9;
  Fixture f(o);
  // Every light bright, every object visible: shadows subtract more than some texels hold.
  const float white[3] = {1.0f, 1.0f, 1.0f};
  for (uint32_t l = 0; l < f.pack.light_count(); ++l)
    ASSERT_EQ(f.planner.set_light(l, true, white, 4.0f), Status::kOk);
  f.settle(kUnlimited);
  const auto raw = reference_map(f.pack, testing::wanted_state(f.planner, f.pack));
  ASSERT_LT(*std::min_element(raw.begin(), raw.end()), -1e-3);  // the case exists
  const auto& got = f.sink->sampled();
  EXPECT_GE(*std::min_element(got.begin(), got.end()), 0.0f);
  EXPECT_LT(max_abs_diff(got, presented(f.pack, raw)), 1e-4);
  ASSERT_EQ(f.planner.set_object_visible(0, false), Status::kOk);
  f.planner.update(kUnlimited, *f.sink);
  EXPECT_LT(max_abs_diff(
                f.sink->sampled(),
                presented(f.pack, reference_map(f.pack, testing::wanted_state(f.planner, f.pack)))),
            1e-4);
}

// A state whose map could exceed the value limit is refused whole; the bound is what it says.
TEST(Planner, RefusesStatesBeyondTheValueLimit) {
  Fixture f(SyntheticOptions{});
  f.settle(kUnlimited);
  const float bound = f.planner.wanted_map_bound();
  const auto ref = reference_map(f.pack, testing::wanted_state(f.planner, f.pack));
  double peak = 0.0;
  for (double v : ref) peak = std::max(peak, std::fabs(v));
  EXPECT_GE(double(bound), peak);
  f.planner.set_value_limit(2.0f * bound);
  const float intensity = f.planner.light_intensity(0);
  const float white[3] = {1.0f, 1.0f, 1.0f};
  EXPECT_EQ(f.planner.set_light(0, true, white, 1.0e6f), Status::kOutOfRange);
  EXPECT_EQ(f.planner.light_intensity(0), intensity);
  EXPECT_TRUE(f.planner.idle());
  const float big[3] = {3.0e38f, 3.0e38f, 3.0e38f};
  EXPECT_EQ(f.planner.set_light(0, true, big, 10.0f), Status::kOutOfRange);  // overflows
}

TEST(Planner, RejectsBadValues) {
  Fixture f(SyntheticOptions{});
  const float nan3[3] = {NAN, 0, 0}, neg[3] = {-1, 0, 0}, ok[3] = {1, 1, 1};
  EXPECT_EQ(f.planner.set_light(0, true, nan3, 1), Status::kInvalidArgument);
  EXPECT_EQ(f.planner.set_light(0, true, neg, 1), Status::kInvalidArgument);
  EXPECT_EQ(f.planner.set_light(0, true, ok, INFINITY), Status::kInvalidArgument);
}

// An index out of range is a caller bug: it asserts (CODE_STYLE.md), and is refused where
// asserts are compiled out.
TEST(Planner, IndexOutOfRangeIsACallerBug) {
  Fixture f(SyntheticOptions{});
  const float ok[3] = {1, 1, 1};
#ifdef NDEBUG
  EXPECT_EQ(f.planner.set_light(99, true, ok, 1), Status::kInvalidArgument);
  EXPECT_EQ(f.planner.set_object_visible(99, true), Status::kInvalidArgument);
#else
  EXPECT_DEATH(f.planner.set_light(99, true, ok, 1), "out of range");
  EXPECT_DEATH(f.planner.set_object_visible(99, true), "out of range");
#endif
}

}  // namespace
}  // namespace lightpatch
