// End to end on scenes cooked in-process (layout, texels, bake, pack): for random states the CPU
// reference recomposition matches a direct bake of the state (bake_state) within the pack's 1%
// bar (static lights shadowed by the objects included), the GLES runtime on llvmpipe matches the
// CPU reference, and overlapping shadows of two objects are exact.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <random>
#include <vector>

#include "cooked_pack.h"
#include "cooker/test_scenes.h"
#include "lightpatch/cooker/bake.h"
#include "lightpatch/cooker/texel_builder.h"
#include "lightpatch/cpu_recomposer.h"
#include "lightpatch/platform/egl_context.h"
#include "lightpatch/runtime.h"
#include "lightpatch/scene_state.h"
#include "runtime/map_reference.h"
#include "sampled_maps.h"

namespace lightpatch {
namespace {

using namespace cooker;

using Cooked = testing::CookedPack;

void cook(Cooked& c, float tpu) {
  testing::cook_draft(c, tpu);
}

BakeOptions draft() {
  BakeOptions o;
  o.quality = Quality::kDraft;
  return o;
}

// Boxes under a hard and a soft semi-dynamic light, a static light, a static pillar: for each
// semi-dynamic light the shadows of different objects do not overlap.
void boxes_scene(Cooked& c) {
  Scene& s = c.scene;
  test::add_quad(s, {-5, 0, -5}, {-5, 0, 5}, {5, 0, 5}, {5, 0, -5}, "floor");
  test::add_box(s, {-4.5f, 0, -4.5f}, {-4.0f, 2.0f, -4.0f}, "pillar");
  test::add_object_box(s, {-2.3f, 0.5f, -0.3f}, {-1.7f, 1.0f, 0.3f}, "box_a");
  test::add_object_box(s, {1.7f, 0.5f, -0.3f}, {2.3f, 1.0f, 0.3f}, "box_b");
  Light lamp = test::point_light("lamp", {-2.0f, 3.0f, 0.0f}, 10.0f, true);
  lamp.color = {1.0f, 0.9f, 0.7f};
  Light spot = test::spot_light("spot", {2.0f, 3.0f, 0.5f}, {0, -1, 0}, 30.0f, 0.5f, 0.9f, true);
  spot.radius = 0.2f;
  // A static light that reaches the objects: their static shadows (static-shadow groups).
  Light fill = test::point_light("fill", {3.0f, 2.0f, -3.0f}, 4.0f, false);
  s.lights = {lamp, spot, fill};
  test::finish(s);
}

// A room corner with a semi-dynamic directional light and a point light, one object each.
void corner_scene(Cooked& c) {
  Scene& s = c.scene;
  test::add_quad(s, {-3, 0, -3}, {-3, 0, 3}, {3, 0, 3}, {3, 0, -3}, "floor");
  test::add_quad(s, {-3, 0, -3}, {3, 0, -3}, {3, 3, -3}, {-3, 3, -3}, "back");
  test::add_object_box(s, {-1.0f, 0.0f, -1.0f}, {-0.5f, 0.8f, -0.5f}, "crate");
  Light sun = test::directional_light("sun", {0.3f, -1.0f, -0.4f}, 3.0f, true);
  Light candle = test::point_light("candle", {1.5f, 0.6f, 1.5f}, 2.0f, true);
  candle.radius = 0.05f;
  s.lights = {sun, candle};
  test::finish(s);
}

// The paper's Fig. 17: two objects in a row under one light, so that their shadows overlap, and
// a second light on the overlap.
void overlap_scene(Cooked& c) {
  Scene& s = c.scene;
  test::add_quad(s, {-3, 0, -3}, {-3, 0, 3}, {3, 0, 3}, {3, 0, -3}, "floor");
  test::add_object_box(s, {-0.4f, 1.6f, -0.4f}, {0.4f, 1.8f, 0.4f}, "upper");
  test::add_object_box(s, {-0.1f, 0.6f, -0.5f}, {0.7f, 0.8f, 0.3f}, "lower");
  Light top = test::point_light("top", {0.0f, 3.5f, 0.0f}, 20.0f, true);
  Light side = test::point_light("side", {2.5f, 1.5f, 1.5f}, 6.0f, true);
  s.lights = {top, side};
  test::finish(s);
}

struct RandomState {
  SceneState runtime;
  StateSpec spec;
};

void random_state(const Cooked& c, std::mt19937& rng, RandomState* out) {
  std::uniform_real_distribution<float> u(0.0f, 1.0f);
  Error error;
  ASSERT_EQ(out->runtime.init(c.pack, &error), Status::kOk);
  out->spec = StateSpec{};
  for (uint32_t l = 0; l < c.pack.light_count(); ++l) {
    LightState ls{u(rng) < 0.75f, {u(rng), u(rng), u(rng)}, 0.2f + 3.0f * u(rng)};
    ASSERT_EQ(out->runtime.set_light(l, ls), Status::kOk);
    const Name n = c.pack.light_name(l);
    LightOverride o;
    o.has_on = o.has_color = o.has_intensity = true;
    o.on = ls.on;
    for (int k = 0; k < 3; ++k) o.color[k] = ls.color[k];
    o.intensity = ls.intensity;
    out->spec.lights[std::string(n.data, n.length)] = o;
  }
  for (uint32_t ob = 0; ob < c.pack.object_count(); ++ob) {
    const bool visible = u(rng) < 0.5f;
    ASSERT_EQ(out->runtime.set_object_visible(ob, visible), Status::kOk);
    const Name n = c.pack.object_name(ob);
    out->spec.objects[std::string(n.data, n.length)] = visible;
  }
}

// Relative RMSE over valid texels.
double relative_rmse(const float* got_rgb, const FloatImage& want, const TexelSet& texels) {
  double err = 0.0, ref = 0.0;
  for (size_t t = 0; t < texels.valid.size(); ++t) {
    if (!texels.valid[t]) continue;
    for (int k = 0; k < 3; ++k) {
      const double w = want.data[t * 3 + size_t(k)], g = got_rgb[t * 3 + size_t(k)];
      err += (g - w) * (g - w);
      ref += w * w;
    }
  }
  return ref > 0.0 ? std::sqrt(err / ref) : std::sqrt(err);
}

class CookedScene : public ::testing::TestWithParam<int> {
 protected:
  void SetUp() override {
    if (GetParam() == 0) {
      boxes_scene(c_);
      cook(c_, 8.0f);
    } else {
      corner_scene(c_);
      cook(c_, 10.0f);
    }
  }
  Cooked c_;
};

TEST_P(CookedScene, CpuRecomposeMatchesBakeStateForRandomStates) {
  ASSERT_FALSE(HasFatalFailure());
  Error error;
  CpuRecomposer cpu;
  ASSERT_EQ(cpu.init(c_.pack, &error), Status::kOk) << error.message;
  std::mt19937 rng(11 + GetParam());
  for (int trial = 0; trial < 5; ++trial) {
    RandomState st;
    random_state(c_, rng, &st);
    ASSERT_EQ(cpu.rebuild(st.runtime), Status::kOk);
    Progress progress(true);
    Report report;
    FloatImage want =
        bake_state(c_.scene, c_.layout, c_.texels, *c_.tracer, st.spec, draft(), progress, report);
    finalize_map(want, c_.scene, c_.layout, c_.texels);
    const double e = relative_rmse(cpu.rgb(), want, c_.texels);
    EXPECT_LT(e, 0.01) << "trial " << trial;
  }
}

TEST_P(CookedScene, GlesRecomposeMatchesTheCpuReference) {
  ASSERT_FALSE(HasFatalFailure());
  testing::Recomposers r;
  testing::open_recomposers(c_.pack, RuntimeLimits{}, &r);
  ASSERT_FALSE(::testing::Test::HasFatalFailure());
  Runtime& runtime = r.runtime;
  CpuRecomposer& cpu = r.cpu;
  ASSERT_TRUE(runtime.gpu_path());
  std::mt19937 rng(23 + GetParam());
  const size_t n = size_t(c_.pack.map_texels());  // both maps where the pack has two
  for (int trial = 0; trial < 4; ++trial) {
    RandomState st;
    random_state(c_, rng, &st);
    for (uint32_t l = 0; l < c_.pack.light_count(); ++l)
      ASSERT_EQ(runtime.set_light(l, st.runtime.light(l)), Status::kOk);
    for (uint32_t o = 0; o < c_.pack.object_count(); ++o)
      ASSERT_EQ(runtime.set_object_visible(o, st.runtime.object_visible(o)), Status::kOk);
    for (int frame = 0; frame < 1000 && !runtime.idle(); ++frame)
      ASSERT_EQ(runtime.update(~0ull >> 1), Status::kOk);
    ASSERT_TRUE(runtime.idle());
    ASSERT_EQ(cpu.rebuild(st.runtime), Status::kOk);
    const std::vector<float> rgb = testing::read_map_set(runtime, c_.pack);
    // The accumulator's rounding (a float target here) and one half-float rounding of the
    // presented value: eight half-float steps of the texel's magnitude, plus the runtime's own
    // relative bound for the incremental updates since its last rebuild.
    std::vector<double> magnitude;
    testing::reference_map(c_.pack, testing::wanted_state(runtime.planner(), c_.pack), &magnitude);
    double worst = 0.0;
    for (size_t i = 0; i < n; ++i)
      for (int k = 0; k < 3; ++k) {
        const double want = cpu.presented_maps()[i * 3 + size_t(k)], got = rgb[i * 3 + size_t(k)];
        const double tol =
            (8.0 / 2048.0 + runtime.stats().error_bound) * magnitude[i * 3 + size_t(k)] + 1e-6;
        worst = std::max(worst, std::fabs(got - want) / tol);
      }
    EXPECT_LE(worst, 1.0) << "trial " << trial;
  }
}

INSTANTIATE_TEST_SUITE_P(Scenes, CookedScene, ::testing::Values(0, 1));

// A lit floor under a visible box: the 8-bit quantization of the contribution and of the box's
// shadow does not cancel under the box (a few steps of the light's scale of either sign where
// bake-state gives 0). The unclamped composition goes below zero there; what the runtime presents,
// on the CPU and on GLES, never does, for any state.
TEST(NegativeLight, NoNegativeTexelInAnyRecomposition) {
  Cooked c;
  Scene& s = c.scene;
  test::add_quad(s, {-3, 0, -3}, {-3, 0, 3}, {3, 0, 3}, {3, 0, -3}, "floor");
  test::add_object_box(s, {-0.6f, 0.0f, -0.6f}, {0.6f, 1.0f, 0.6f}, "box");
  test::add_object_box(s, {1.2f, 0.0f, 1.2f}, {1.8f, 0.5f, 1.8f}, "crate");
  Light lamp = test::point_light("lamp", {0.3f, 3.0f, 0.2f}, 3000.0f, true);
  lamp.color = {1.0f, 0.9f, 0.8f};
  Light side = test::point_light("side", {-2.0f, 1.5f, 2.0f}, 800.0f, true);
  s.lights = {lamp, side};
  test::finish(s);
  cook(c, 10.0f);
  ASSERT_FALSE(::testing::Test::HasFatalFailure());
  testing::Recomposers r;
  testing::open_recomposers(c.pack, RuntimeLimits{}, &r);
  ASSERT_FALSE(::testing::Test::HasFatalFailure());
  Runtime& runtime = r.runtime;
  CpuRecomposer& cpu = r.cpu;
  Error error;
  SceneState st;
  ASSERT_EQ(st.init(c.pack, &error), Status::kOk);
  const size_t n = size_t(c.pack.map_texels());  // both maps where the pack has two
  std::mt19937 rng(5);
  std::uniform_real_distribution<float> u(0.0f, 1.0f);
  double raw_min = 0.0, floor_peak = 0.0;
  for (int trial = 0; trial < 12; ++trial) {
    for (uint32_t l = 0; l < c.pack.light_count(); ++l) {
      LightState ls{trial < 2 || u(rng) < 0.8f,
                    {1.0f, 0.9f, 0.8f},
                    c.pack.light(l).intensity * (0.3f + 2.0f * u(rng))};
      ASSERT_EQ(st.set_light(l, ls), Status::kOk);
      ASSERT_EQ(runtime.set_light(l, ls), Status::kOk);
    }
    for (uint32_t o = 0; o < c.pack.object_count(); ++o) {
      const bool visible = trial < 2 || u(rng) < 0.6f;
      ASSERT_EQ(st.set_object_visible(o, visible), Status::kOk);
      ASSERT_EQ(runtime.set_object_visible(o, visible), Status::kOk);
    }
    ASSERT_EQ(cpu.apply(st), Status::kOk);
    for (int frame = 0; frame < 100 && !runtime.idle(); ++frame)
      ASSERT_EQ(runtime.update(~0ull >> 1), Status::kOk);
    const std::vector<float> rgb = testing::read_map_set(runtime, c.pack);
    const std::vector<double> raw =
        testing::reference_map(c.pack, testing::wanted_state(runtime.planner(), c.pack));
    for (size_t i = 0; i < n * 3; ++i) {
      raw_min = std::min(raw_min, raw[i]);
      floor_peak = std::max(floor_peak, raw[i]);
      ASSERT_GE(cpu.presented_maps()[i], 0.0f) << "cpu, trial " << trial << ", value " << i;
      ASSERT_GE(rgb[i], 0.0f) << "gles, trial " << trial << ", value " << i;
    }
  }
  std::printf("unclamped minimum %.3g where the floor peaks at %.4g\n", raw_min, floor_peak);
  // The case the clamp is for exists in this scene (well beyond float rounding of the sum).
  EXPECT_LT(raw_min, -1e-6 * floor_peak);
}

// Overlapping shadows are exact: all four visibility combinations of the two objects, CPU and
// GLES, within 1% of bake_state; and the cook made the pair's correction.
TEST(OverlappingShadows, FourVisibilityCombinationsMatchBakeStateOnCpuAndGles) {
  Cooked c;
  overlap_scene(c);
  cook(c, 10.0f);
  ASSERT_FALSE(::testing::Test::HasFatalFailure());
  bool has_pair = false;
  for (uint32_t g = 0; g < c.pack.group_count(); ++g)
    has_pair |= c.pack.group(g).kind == pack::kGroupPairCorrection;
  EXPECT_TRUE(has_pair);
  testing::Recomposers r;
  testing::open_recomposers(c.pack, RuntimeLimits{}, &r);
  ASSERT_FALSE(::testing::Test::HasFatalFailure());
  Runtime& runtime = r.runtime;
  CpuRecomposer& cpu = r.cpu;
  Error error;
  for (int combo = 0; combo < 4; ++combo) {
    SceneState st;
    ASSERT_EQ(st.init(c.pack, &error), Status::kOk);
    StateSpec spec;
    for (uint32_t o = 0; o < 2; ++o) {
      const bool visible = (combo >> o) & 1;
      ASSERT_EQ(st.set_object_visible(o, visible), Status::kOk);
      ASSERT_EQ(runtime.set_object_visible(o, visible), Status::kOk);
      const Name name = c.pack.object_name(o);
      spec.objects[std::string(name.data, name.length)] = visible;
    }
    ASSERT_EQ(cpu.rebuild(st), Status::kOk);
    for (int frame = 0; frame < 1000 && !runtime.idle(); ++frame)
      ASSERT_EQ(runtime.update(~0ull >> 1), Status::kOk);
    const std::vector<float> rgb = testing::read_sampled(runtime, c.pack);  // L + I
    Progress progress(true);
    Report report;
    FloatImage want =
        bake_state(c.scene, c.layout, c.texels, *c.tracer, spec, draft(), progress, report);
    finalize_map(want, c.scene, c.layout, c.texels);
    EXPECT_LT(relative_rmse(cpu.rgb(), want, c.texels), 0.01) << "cpu, combination " << combo;
    EXPECT_LT(relative_rmse(rgb.data(), want, c.texels), 0.01) << "gles, combination " << combo;
  }
}

}  // namespace
}  // namespace lightpatch
