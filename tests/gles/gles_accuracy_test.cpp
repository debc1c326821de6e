// The GLES runtime against the CPU reference recomposer on a cooked room with bounce light (three
// coloured semi-dynamic lights, three semi-dynamic boxes): after the first build, after each of a
// run of single changes through the incremental path, and after 300 incremental states (random
// toggles, colours, intensities, lights off and on). Bars: relative RMSE <= 0.1 % and the median
// of got / want within +-0.05 % (tests/runtime/map_metrics.h). The same room cooked with an
// indirect map (bounce light at 1/4 resolution) is held to the same bars on L + magnified I.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstddef>
#include <cstdio>
#include <cstring>
#include <random>
#include <string>
#include <vector>

#include "cooked_pack.h"
#include "cooker/test_scenes.h"
#include "lightpatch/cpu_recomposer.h"
#include "lightpatch/platform/egl_context.h"
#include "lightpatch/runtime.h"
#include "lightpatch/scene_state.h"
#include "pack/pack_bytes.h"
#include "runtime/map_metrics.h"
#include "sampled_maps.h"

namespace lightpatch {
namespace {

using testing::compare_maps;
using testing::MapMetrics;

constexpr uint64_t kUnlimited = ~0ull >> 1;
constexpr double kMaxRelativeRmse = 1e-3;
constexpr double kMaxMedianBias = 5e-4;

// A 4 x 4 m floor with two walls (bounce), three coloured lights and three boxes.
void room_scene(testing::CookedPack& c) {
  cooker::Scene& s = c.scene;
  test::add_quad(s, {-2, 0, -2}, {-2, 0, 2}, {2, 0, 2}, {2, 0, -2}, "floor");
  test::add_quad(s, {-2, 0, -2}, {2, 0, -2}, {2, 2.5f, -2}, {-2, 2.5f, -2}, "back");
  test::add_quad(s, {-2, 0, 2}, {-2, 0, -2}, {-2, 2.5f, -2}, {-2, 2.5f, 2}, "left");
  test::add_object_box(s, {-1.2f, 0.0f, -1.2f}, {-0.6f, 0.6f, -0.6f}, "crate");
  test::add_object_box(s, {0.5f, 0.0f, -0.9f}, {1.0f, 0.9f, -0.4f}, "barrel");
  test::add_object_box(s, {-0.3f, 0.0f, 0.6f}, {0.3f, 0.4f, 1.2f}, "chest");
  cooker::Light red = test::point_light("red", {-1.0f, 1.8f, 0.2f}, 6.0f, true);
  red.color = {1.0f, 0.35f, 0.2f};
  cooker::Light green = test::point_light("green", {1.2f, 1.5f, 0.8f}, 5.0f, true);
  green.color = {0.3f, 1.0f, 0.4f};
  cooker::Light blue = test::point_light("blue", {0.2f, 2.0f, -1.4f}, 7.0f, true);
  blue.color = {0.35f, 0.5f, 1.0f};
  s.lights = {red, green, blue};
  test::finish(s);
}

class GlesAccuracy : public ::testing::Test {
 protected:
  static void SetUpTestSuite() {
    cooked_ = new testing::CookedPack;
    room_scene(*cooked_);
    testing::cook_draft(*cooked_, 12.0f);
    // The same room with its bounce light at a quarter of the resolution (an indirect map).
    cooked_indirect_ = new testing::CookedPack;
    room_scene(*cooked_indirect_);
    testing::cook_draft(*cooked_indirect_, 12.0f, 4);
  }
  static void TearDownTestSuite() {
    delete cooked_;
    delete cooked_indirect_;
    cooked_ = cooked_indirect_ = nullptr;
  }

  // Runs the sequence on a runtime opened with `limits`, checking every measured state against
  // the bars (relative RMSE, |median - 1|); prints the first build, the worst of the single
  // changes and the last state.
  void run(const RuntimeLimits& limits, const char* what, double max_rmse = kMaxRelativeRmse,
           double max_bias = kMaxMedianBias, const testing::CookedPack* cooked = cooked_) {
    ASSERT_FALSE(HasFatalFailure());
    const PackView& pack = cooked->pack;
    ASSERT_GE(pack.light_count(), 3u);
    ASSERT_GE(pack.object_count(), 3u);
    testing::Recomposers r;
    testing::open_recomposers(pack, limits, &r);
    ASSERT_FALSE(HasFatalFailure());
    Runtime& runtime = r.runtime;
    CpuRecomposer& cpu = r.cpu;
    Error error;
    SceneState state;
    ASSERT_EQ(state.init(pack, &error), Status::kOk);
    auto measure = [&]() {
      for (int frame = 0; frame < 100 && !runtime.idle(); ++frame)
        EXPECT_EQ(runtime.update(kUnlimited), Status::kOk);
      EXPECT_TRUE(runtime.idle());
      EXPECT_EQ(cpu.rebuild(state), Status::kOk);
      // What a game samples: L, plus the magnified indirect map where the pack has one.
      const std::vector<float> rgb = testing::read_sampled(runtime, pack);
      return compare_maps(rgb.data(), cpu.rgb(), rgb.size());
    };
    auto print = [&](const char* when, const MapMetrics& m) {
      std::printf("%s, %s: relative RMSE %.4f %%, median ratio %.5f, 1st percentile %.4f, min %g\n",
                  what, when, 100.0 * m.relative_rmse, m.median_ratio, m.p1_ratio, m.min_value);
    };
    auto check = [&](const MapMetrics& m, int step) {
      EXPECT_LE(m.relative_rmse, max_rmse) << what << ", state " << step;
      EXPECT_LE(std::fabs(m.median_ratio - 1.0), max_bias) << what << ", state " << step;
      EXPECT_GE(m.min_value, 0.0) << what << ", state " << step;
    };
    const MapMetrics first = measure();
    print("first build", first);
    check(first, 0);

    std::mt19937 rng(2024);
    std::uniform_real_distribution<float> u(0.0f, 1.0f);
    MapMetrics worst;
    worst.median_ratio = 1.0;
    worst.p1_ratio = 1.0;
    constexpr int kStates = 300, kSingles = 24;
    for (int step = 1; step <= kStates; ++step) {
      const float pick = u(rng);
      if (pick < 0.3f) {
        const uint32_t o = rng() % pack.object_count();
        const bool v = !state.object_visible(o);
        ASSERT_EQ(state.set_object_visible(o, v), Status::kOk);
        ASSERT_EQ(runtime.set_object_visible(o, v), Status::kOk);
      } else {
        const uint32_t l = rng() % pack.light_count();
        LightState ls = state.light(l);
        if (pick < 0.55f) {
          for (float& c : ls.color) c = 0.1f + 0.9f * u(rng);
        } else if (pick < 0.8f) {
          ls.intensity = pack.light(l).intensity * (0.1f + 2.9f * u(rng));
        } else {
          ls.on = !ls.on;
        }
        ASSERT_EQ(state.set_light(l, ls), Status::kOk);
        ASSERT_EQ(runtime.set_light(l, ls), Status::kOk);
      }
      if (step > kSingles && step < kStates) {
        for (int frame = 0; frame < 100 && !runtime.idle(); ++frame)
          ASSERT_EQ(runtime.update(kUnlimited), Status::kOk);
        continue;
      }
      const MapMetrics m = measure();
      check(m, step);
      if (step == kStates) {
        print("after 300 incremental states", m);
        continue;
      }
      worst.relative_rmse = std::max(worst.relative_rmse, m.relative_rmse);
      if (std::fabs(m.median_ratio - 1.0) > std::fabs(worst.median_ratio - 1.0))
        worst.median_ratio = m.median_ratio;
      worst.p1_ratio = std::min(worst.p1_ratio, m.p1_ratio);
      worst.min_value = std::min(worst.min_value, m.min_value);
    }
    print("worst of 24 single changes", worst);
  }

  static testing::CookedPack* cooked_;
  static testing::CookedPack* cooked_indirect_;
};
testing::CookedPack* GlesAccuracy::cooked_ = nullptr;
testing::CookedPack* GlesAccuracy::cooked_indirect_ = nullptr;

TEST_F(GlesAccuracy, GpuPathMatchesTheCpuReference) {
  run(RuntimeLimits{}, "gpu");
}

// Without float blending (forced here): an RGBA16F accumulator. On a target that truncates
// (llvmpipe) every draw loses up to an ulp, so even a rebuild is biased low by a few draws' worth
// of half ulps; the planner rebuilds instead of piling up incremental draws, which keeps the
// error at a rebuild's.
TEST_F(GlesAccuracy, HalfFloatPathStaysNearTheCpuReference) {
  RuntimeLimits limits;
  limits.force_half_accumulator = true;
  run(limits, "gpu half", 1.0e-2, 5.0e-3);
}

TEST_F(GlesAccuracy, CpuFallbackMatchesTheCpuReference) {
  RuntimeLimits limits;
  limits.force_cpu_fallback = true;
  run(limits, "cpu fallback");
}

// A cooked pack with an indirect map: what a game samples, L + the magnified I, on the float
// path and the CPU path, against the CPU reference's L + I.
TEST_F(GlesAccuracy, PackWithAnIndirectMapMatchesTheCpuReference) {
  const PackView& pack = cooked_indirect_->pack;
  ASSERT_TRUE(pack.has_indirect_map());
  ASSERT_EQ(pack.indirect_scale(), 4u);
  uint32_t indirect = 0;
  for (uint32_t p = 0; p < pack.patch_count(); ++p)
    indirect += pack.patch(p).target == pack::kTargetIndirectMap;
  std::printf("indirect map %ux%u, %u of %u patches\n", pack.indirect_width(),
              pack.indirect_height(), indirect, pack.patch_count());
  ASSERT_GT(indirect, 0u);
  run(RuntimeLimits{}, "gpu, indirect map", kMaxRelativeRmse, kMaxMedianBias, cooked_indirect_);
  RuntimeLimits cpu;
  cpu.force_cpu_fallback = true;
  run(cpu, "cpu fallback, indirect map", kMaxRelativeRmse, kMaxMedianBias, cooked_indirect_);
}

// 1-channel patches that draw into one map channel (pack::kFlagDestinationMask: the cooker
// stores tinted base patches as three of them where atlas alpha planes have room): the room's
// grey patches edited to draw into R, G or B in turn (the table checksum fixed), on GLES against
// the CPU reference of the same pack, under the same bars.
TEST_F(GlesAccuracy, OneChannelDestinationPatchesMatchTheCpuReference) {
  testing::CookedPack edited;
  edited.bytes = cooked_->bytes;
  Error error;
  ASSERT_EQ(PackView::open(edited.bytes.data(), edited.bytes.size(), &edited.pack, &error),
            Status::kOk);
  const uint64_t records =
      uint64_t(reinterpret_cast<const uint8_t*>(&edited.pack.patch(0)) - edited.bytes.data());
  uint32_t grey = 0;
  for (uint32_t p = 0; p < edited.pack.patch_count(); ++p) {
    if (edited.pack.patch(p).channel_count != 1) continue;
    const uint8_t flags = uint8_t(edited.pack.patch(p).flags |
                                  ((grey++ % 4) << pack::kFlagDestinationShift));  // 0: grey
    edited.bytes[records + p * sizeof(pack::PatchRecord) + offsetof(pack::PatchRecord, flags)] =
        flags;
  }
  test::fix_checksum(edited.bytes.data(), edited.bytes.size());
  ASSERT_EQ(PackView::open(edited.bytes.data(), edited.bytes.size(), &edited.pack, &error),
            Status::kOk)
      << error.message;
  std::printf("%u grey patches, three in four of them drawing one map channel\n", grey);
  ASSERT_GT(grey, 8u);
  run(RuntimeLimits{}, "gpu, one-channel destinations", kMaxRelativeRmse, kMaxMedianBias, &edited);
}

// Patches touch in the atlas (no gutter), so nothing around a patch may reach a map: the room
// with an indirect map, every atlas channel-texel no patch covers overwritten with garbage, on
// the float path, against the CPU reference of the clean pack (and the CPU reference of the
// garbage pack equal to it bit for bit), over a first build and a run of changes.
TEST_F(GlesAccuracy, UnusedAtlasTexelsNeverReachTheMap) {
  const testing::CookedPack& c = *cooked_indirect_;
  std::vector<uint64_t> words((c.bytes.size() + 7) / 8);
  uint8_t* copy = reinterpret_cast<uint8_t*>(words.data());
  std::memcpy(copy, c.bytes.data(), c.bytes.size());
  const uint64_t filled = test::fill_unused_atlas_texels(c.pack, c.bytes.data(), copy, 11u);
  std::printf("%llu unused atlas channel-texels filled with garbage\n",
              static_cast<unsigned long long>(filled));
  ASSERT_GT(filled, 0u);
  PackView garbage;
  Error error;
  ASSERT_EQ(PackView::open(copy, c.bytes.size(), &garbage, &error), Status::kOk) << error.message;
  testing::Recomposers r;
  testing::open_recomposers(garbage, RuntimeLimits{}, &r);
  ASSERT_FALSE(HasFatalFailure());
  CpuRecomposer reference;
  SceneState state;
  ASSERT_EQ(reference.init(c.pack, &error), Status::kOk);
  ASSERT_EQ(state.init(c.pack, &error), Status::kOk);
  for (int step = 0; step <= 2 * int(garbage.object_count() + garbage.light_count()); ++step) {
    const int k = (step - 1) / 2;  // hide each object, then turn each light off, and back
    if (step > 0 && k < int(garbage.object_count())) {
      const uint32_t o = uint32_t(k);
      ASSERT_EQ(state.set_object_visible(o, step % 2 == 0), Status::kOk);
      ASSERT_EQ(r.runtime.set_object_visible(o, step % 2 == 0), Status::kOk);
    } else if (step > 0) {
      const uint32_t l = uint32_t(k) - garbage.object_count();
      ASSERT_EQ(state.set_light_on(l, step % 2 == 0), Status::kOk);
      LightState ls = state.light(l);
      ASSERT_EQ(r.runtime.set_light(l, ls), Status::kOk);
    }
    for (int frame = 0; frame < 100 && !r.runtime.idle(); ++frame)
      ASSERT_EQ(r.runtime.update(kUnlimited), Status::kOk);
    ASSERT_EQ(reference.rebuild(state), Status::kOk);
    ASSERT_EQ(r.cpu.rebuild(state), Status::kOk);
    const std::vector<float> rgb = testing::read_sampled(r.runtime, garbage);
    ASSERT_EQ(rgb.size(), size_t(reference.width()) * reference.height() * 3);
    EXPECT_TRUE(std::equal(reference.rgb(), reference.rgb() + rgb.size(), r.cpu.rgb()))
        << "step " << step;
    const MapMetrics m = compare_maps(rgb.data(), reference.rgb(), rgb.size());
    EXPECT_LE(m.relative_rmse, kMaxRelativeRmse) << "step " << step;
    EXPECT_LE(std::fabs(m.median_ratio - 1.0), kMaxMedianBias) << "step " << step;
  }
}

// Sunlight at real values: a 100,000 lux directional light over a floor with a box, authored
// as intensity 100,000 or as colour 100,000 (packs carry either), recomposes on GLES as on the
// CPU (no clamp at the half-float maximum, no negative texel under the box), and a state beyond
// what the runtime's map can hold is refused.
TEST(Sunlight, RealLuxRecomposesTheSameOnGlesAndCpu) {
  for (int authored_as_colour = 0; authored_as_colour < 2; ++authored_as_colour) {
    testing::CookedPack c;
    cooker::Scene& s = c.scene;
    test::add_quad(s, {-3, 0, -3}, {-3, 0, 3}, {3, 0, 3}, {3, 0, -3}, "ground");
    test::add_object_box(s, {-0.5f, 0.0f, -0.5f}, {0.5f, 1.0f, 0.5f}, "crate");
    cooker::Light sun = test::directional_light("sun", {0.3f, -1.0f, -0.4f}, 1.0e5f, true);
    if (authored_as_colour) {
      sun.color = {1.0e5f, 1.0e5f, 1.0e5f};
      sun.intensity = 1.0f;
    }
    s.lights = {sun};
    test::finish(s);
    testing::cook_draft(c, 8.0f);
    ASSERT_FALSE(::testing::Test::HasFatalFailure());
    testing::Recomposers r;
    testing::open_recomposers(c.pack, RuntimeLimits{}, &r);
    ASSERT_FALSE(::testing::Test::HasFatalFailure());
    // The smallest power of two that brings the authored bound to 4096 or below.
    const float scaled = r.runtime.planner().wanted_map_bound() / r.runtime.light_map_scale();
    EXPECT_LE(scaled, 4096.0f);
    EXPECT_GT(scaled, 2048.0f);
    Error error;
    SceneState state;
    ASSERT_EQ(state.init(c.pack, &error), Status::kOk);
    const size_t n = size_t(r.runtime.width()) * r.runtime.height();
    for (int visible = 1; visible >= 0; --visible) {
      ASSERT_EQ(state.set_object_visible(0, visible != 0), Status::kOk);
      ASSERT_EQ(r.runtime.set_object_visible(0, visible != 0), Status::kOk);
      for (int frame = 0; frame < 100 && !r.runtime.idle(); ++frame)
        ASSERT_EQ(r.runtime.update(kUnlimited), Status::kOk);
      ASSERT_EQ(r.cpu.apply(state), Status::kOk);
      const std::vector<float> rgb = testing::read_sampled(r.runtime, c.pack);
      const MapMetrics m = compare_maps(rgb.data(), r.cpu.rgb(), n * 3);
      EXPECT_LE(m.relative_rmse, kMaxRelativeRmse);
      EXPECT_LE(std::fabs(m.median_ratio - 1.0), kMaxMedianBias);
      EXPECT_GE(m.min_value, 0.0);
      const float peak = *std::max_element(rgb.begin(), rgb.end());
      EXPECT_GT(peak, 80000.0f);  // lit ground near 100,000 * cos(25 deg), above 65,504
      EXPECT_NEAR(peak, *std::max_element(r.cpu.rgb(), r.cpu.rgb() + n * 3), 1e-3 * peak);
    }
    const float white[3] = {1.0f, 1.0f, 1.0f};
    EXPECT_EQ(r.runtime.set_light_color(0, white), Status::kOk);
    EXPECT_EQ(r.runtime.set_light_intensity(0, 1.0e9f), Status::kOutOfRange);
  }
}

}  // namespace
}  // namespace lightpatch
