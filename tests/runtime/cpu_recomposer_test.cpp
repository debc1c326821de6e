// The CPU reference recomposer against a double-precision evaluation of the pack (every group
// kind, static shadows included), clamped at zero as presented, for rebuilds and for long runs of
// incremental changes (the planner's, paper Alg. 8-9) that must end where a rebuild ends.
#include "lightpatch/cpu_recomposer.h"

#include <gtest/gtest.h>

#include <cmath>
#include <random>

#include "lightpatch/scene_state.h"
#include "runtime/map_reference.h"
#include "runtime/synthetic_pack.h"

namespace lightpatch {
namespace {

using testing::make_synthetic_pack;
using testing::reference_map;
using testing::SyntheticOptions;

testing::RefState ref_of(const SceneState& s, const PackView& pack) {
  testing::RefState r;
  for (uint32_t l = 0; l < pack.light_count(); ++l) {
    float f[3];
    s.light_factor(l, f);
    r.factor.insert(r.factor.end(), f, f + 3);
  }
  for (uint32_t o = 0; o < pack.object_count(); ++o)
    r.visible.push_back(s.object_visible(o) ? 1 : 0);
  return r;
}

void random_change(SceneState& s, const PackView& pack, std::mt19937& rng) {
  std::uniform_real_distribution<float> u(0.0f, 1.0f);
  if (pack.object_count() > 0 && u(rng) < 0.4f) {
    const uint32_t o = rng() % pack.object_count();
    ASSERT_EQ(s.set_object_visible(o, !s.object_visible(o)), Status::kOk);
  } else {
    const uint32_t l = rng() % pack.light_count();
    const LightState ls{u(rng) < 0.8f, {u(rng), u(rng), u(rng)}, 4.0f * u(rng)};
    ASSERT_EQ(s.set_light(l, ls), Status::kOk);
  }
}

TEST(CpuRecomposer, RebuildAndIncrementalChangesMatchTheReference) {
  for (uint32_t seed = 1; seed <= 3; ++seed) {
    SyntheticOptions o;
    o.seed = seed;
    o.lights = 3 + seed;
    o.objects = 2 + seed;
    o.static_shadow_probability = 1.0f;
    o.width = 24;
    o.height = 20;
    const testing::SyntheticPack bytes = make_synthetic_pack(o);
    PackView pack;
    Error error;
    ASSERT_TRUE(bytes.open(&pack, &error)) << error.message;
    bool has_static = false;
    for (uint32_t g = 0; g < pack.group_count(); ++g)
      has_static |= pack.group(g).kind == pack::kGroupStaticShadow;
    ASSERT_TRUE(has_static);

    SceneState state;
    ASSERT_EQ(state.init(pack, &error), Status::kOk);
    CpuRecomposer cpu;
    ASSERT_EQ(cpu.init(pack, &error), Status::kOk);
    ASSERT_EQ(cpu.rebuild(state), Status::kOk);
    std::mt19937 rng(seed);
    bool incremental = false;
    for (int i = 0; i < 2000; ++i) {
      random_change(state, pack, rng);
      ASSERT_EQ(cpu.apply(state), Status::kOk);
      incremental |= !cpu.stats().rebuilt;
      if (i % 250 != 249) continue;
      const std::vector<double> want = testing::presented(reference_map(pack, ref_of(state, pack)));
      for (size_t t = 0; t < want.size(); ++t)
        ASSERT_NEAR(cpu.rgb()[t], want[t], 1e-4 * (1.0 + std::fabs(want[t]))) << "texel " << t / 3;
    }
    EXPECT_TRUE(incremental);
  }
}

TEST(CpuRecomposer, TenThousandIncrementalChangesEndEqualToARebuild) {
  SyntheticOptions o;
  o.seed = 5;
  o.lights = 6;
  o.objects = 4;
  const testing::SyntheticPack bytes = make_synthetic_pack(o);
  PackView pack;
  Error error;
  ASSERT_TRUE(bytes.open(&pack, &error)) << error.message;
  SceneState state;
  ASSERT_EQ(state.init(pack, &error), Status::kOk);
  CpuRecomposer incremental, fresh;
  ASSERT_EQ(incremental.init(pack, &error), Status::kOk);
  ASSERT_EQ(fresh.init(pack, &error), Status::kOk);
  ASSERT_EQ(incremental.rebuild(state), Status::kOk);
  std::mt19937 rng(17);
  for (int i = 0; i < 10000; ++i) {
    random_change(state, pack, rng);
    ASSERT_EQ(incremental.apply(state), Status::kOk);
  }
  ASSERT_EQ(fresh.rebuild(state), Status::kOk);
  // Double accumulation: after 10^4 updates the difference is float rounding of the output.
  const size_t n = size_t(pack.lightmap_width()) * pack.lightmap_height() * 3;
  for (size_t t = 0; t < n; ++t)
    ASSERT_NEAR(incremental.rgb()[t], fresh.rgb()[t], 1e-5 * (1.0 + std::fabs(fresh.rgb()[t])));
}

}  // namespace
}  // namespace lightpatch
