// The CPU reference recomposer against a double-precision evaluation of the pack (every group
// kind, static shadows included), clamped at zero as presented, for rebuilds and for long runs of
// incremental changes (the planner's, paper Alg. 8-9) that must end where a rebuild ends.
#include "lightpatch/cpu_recomposer.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <functional>
#include <random>
#include <string>

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
    o.indirect_scale = seed == 1 ? 0 : 2 * (seed - 1);  // none, 1/2, 1/4 (a 6x5 indirect map)
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
      // Each presented map, and what a game samples: L + I magnified by the contract's formula.
      const std::vector<double> maps =
          testing::presented(pack, reference_map(pack, ref_of(state, pack)));
      for (size_t t = 0; t < maps.size(); ++t) {
        ASSERT_NEAR(cpu.presented_maps()[t], maps[t], 1e-4 * (1.0 + std::fabs(maps[t])))
            << "map-set texel " << t / 3;
      }
      const std::vector<double> want = testing::sampled_reference(pack, maps);
      for (size_t t = 0; t < want.size(); ++t)
        ASSERT_NEAR(cpu.rgb()[t], want[t], 1e-4 * (1.0 + std::fabs(want[t]))) << "texel " << t / 3;
    }
    EXPECT_TRUE(incremental);
    EXPECT_EQ(cpu.indirect_map() != nullptr, o.indirect_scale != 0);
  }
}

// A pack whose maps have a closed form: a 16x8 light map and a 4x2 indirect map (scale 4). The
// base and the light's contribution each cover the light map with 0.2; the light's indirect patch
// covers the indirect map with a ramp along x, 40 i / 255 at indirect column i. So a game samples
//   L + I = 0.2 + 0.2 f + f (40 / 255) clamp((x + 0.5) / 4 - 0.5, 0, 3)
// at light-map column x (every row alike): the ramp magnified bilinearly is the ramp, flat beyond
// the outer texel centres.
// The options of that pack; `tweak` edits each patch record after the common fields.
SyntheticOptions closed_form_options(std::function<void(pack::PatchRecord&)> tweak = {}) {
  SyntheticOptions o;
  o.width = 16;
  o.height = 8;
  o.lights = 1;
  o.objects = 0;
  o.atlas_size = 32;
  o.patches_per_group = 1;
  o.indirect_scale = 4;
  o.indirect_patches_per_group = 0;
  o.bounce_covers_map = true;  // the contribution's one indirect patch: the whole indirect map
  // Atlas rows 0..1: the ramp (columns 0..3); rows 16..23: 0.2 (51 / 255).
  o.atlas_byte = [](uint32_t x, uint32_t y, uint32_t) {
    return uint8_t(y < 16 ? 40 * std::min(x, 3u) : 51);
  };
  o.mutate = [tweak](pack::Header&, std::vector<pack::PatchRecord>& patches) {
    for (pack::PatchRecord& p : patches) {
      const bool indirect = p.target == pack::kTargetIndirectMap;
      p.atlas = 0;
      p.atlas_x = 0;
      p.atlas_y = indirect ? 0 : 16;
      p.dest_x = p.dest_y = 0;
      p.width = indirect ? 4 : 16;
      p.height = indirect ? 2 : 8;
      p.channel = 0;
      p.channel_count = 1;
      p.encoding = pack::kEncodingLinear;
      p.scale = 1.0f;
      p.flags = 0;
      if (tweak) tweak(p);
    }
  };
  return o;
}

// Opens the closed-form pack of `o` into *pack, turns its light on at colour (1, 0.5, 0.25),
// intensity 2 (f = (2, 1, 0.5)) and checks the rebuilt maps: the base drawing 0.2 into the map
// channels `base` marks, the contribution 0.2 f into those `light` marks, the ramp as above.
void expect_closed_form(const testing::SyntheticPack& bytes, PackView* pack, SceneState* state,
                        CpuRecomposer* cpu, const double base[3], const double light[3]) {
  Error error;
  ASSERT_TRUE(bytes.open(pack, &error)) << error.message;
  ASSERT_EQ(pack->patch_count(), 3u);  // base, contribution, its indirect patch
  ASSERT_EQ(pack->group(0).kind, pack::kGroupBase);
  ASSERT_EQ(state->init(*pack, &error), Status::kOk);
  ASSERT_EQ(cpu->init(*pack, &error), Status::kOk);
  ASSERT_EQ(state->set_light(0, LightState{true, {1.0f, 0.5f, 0.25f}, 2.0f}), Status::kOk);
  ASSERT_EQ(cpu->rebuild(*state), Status::kOk);
  const double f[3] = {2.0, 1.0, 0.5};
  for (uint32_t y = 0; y < 8; ++y) {
    for (uint32_t x = 0; x < 16; ++x) {
      const double u = std::min(std::max((x + 0.5) / 4.0 - 0.5, 0.0), 3.0);
      for (int c = 0; c < 3; ++c) {
        const double l = 0.2 * base[c] + 0.2 * f[c] * light[c];
        ASSERT_NEAR(cpu->light_map()[(y * 16 + x) * 3 + c], l, 1e-6) << x << "," << y << " " << c;
        ASSERT_NEAR(cpu->rgb()[(y * 16 + x) * 3 + c], l + f[c] * 40.0 / 255.0 * u, 1e-6);
      }
    }
  }
}

TEST(CpuRecomposer, APackWithAnIndirectMapRecomposesToItsClosedForm) {
  const testing::SyntheticPack bytes = make_synthetic_pack(closed_form_options());
  PackView pack;
  SceneState state;
  CpuRecomposer cpu;
  const double all[3] = {1, 1, 1};
  expect_closed_form(bytes, &pack, &state, &cpu, all, all);
  ASSERT_FALSE(HasFatalFailure());
  const double f[3] = {2.0, 1.0, 0.5};
  for (uint32_t i = 0; i < 4 * 2; ++i) {
    for (int c = 0; c < 3; ++c)
      ASSERT_NEAR(cpu.indirect_map()[i * 3 + c], f[c] * 40.0 * (i % 4) / 255.0, 1e-6);
  }
  // The light off through the incremental path: the base alone.
  ASSERT_EQ(state.set_light(0, LightState{false, {1.0f, 0.5f, 0.25f}, 2.0f}), Status::kOk);
  ASSERT_EQ(cpu.apply(state), Status::kOk);
  for (uint32_t t = 0; t < 16 * 8 * 3; ++t) ASSERT_NEAR(cpu.rgb()[t], 0.2, 1e-6);
  EXPECT_GT(cpu.stats().indirect_texels_drawn, 0u);
}

// The same pack with its two light-map patches drawing into one map channel each
// (pack::kFlagDestinationMask): the base into R, the contribution into B; the indirect patch
// stays grey. So L = (0.2, 0, 0.2 f_B) and I is as above.
TEST(CpuRecomposer, OneChannelPatchesDrawIntoTheirDestinationChannelOnly) {
  SyntheticOptions o = closed_form_options([](pack::PatchRecord& p) {
    if (p.target == pack::kTargetIndirectMap) return;
    p.channel = 3;
    const unsigned destination = p.group == 0 ? 1u : 3u;  // R, B
    p.flags = uint8_t(destination << pack::kFlagDestinationShift);
  });
  PackView pack;
  SceneState state;
  CpuRecomposer cpu;
  const double red[3] = {1, 0, 0}, blue[3] = {0, 0, 1};
  const testing::SyntheticPack bytes = make_synthetic_pack(o);
  expect_closed_form(bytes, &pack, &state, &cpu, red, blue);
  Error error;
  // A destination on a 3-channel patch is refused.
  o.mutate = [](pack::Header&, std::vector<pack::PatchRecord>& patches) {
    patches[0].channel_count = 3;
    patches[0].channel = 0;
    patches[0].flags = uint8_t(2u << pack::kFlagDestinationShift);
  };
  PackView bad;
  EXPECT_FALSE(make_synthetic_pack(o).open(&bad, &error));
  EXPECT_NE(std::string(error.message).find("destination"), std::string::npos) << error.message;
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
