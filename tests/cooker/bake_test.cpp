// The baker's maps: recomposition from B, C_l and S_ol equals a direct bake of the state, pair
// culling, determinism, and the state's names.
#include <gtest/gtest.h>

#include <cmath>
#include <cstring>
#include <random>

#include "lightpatch/cooker/bake.h"
#include "lightpatch/cooker/bake_plan.h"
#include "lightpatch/cooker/error.h"
#include "lightpatch/cooker/tracer.h"
#include "test_scenes.h"

namespace lightpatch::cooker {
namespace {

// Two boxes under two semi-dynamic lights (one hard, one soft spot), a third box out of the spot's
// cone, a static light in a corner whose range keeps it away from the objects. For each light,
// the shadows of different objects do not overlap.
struct Fixture {
  Scene scene;
  TexelSet texels;
  Fixture() {
    test::add_quad(scene, {-5, 0, -5}, {-5, 0, 5}, {5, 0, 5}, {5, 0, -5}, "floor");
    test::add_object_box(scene, {-2.3f, 0.5f, -0.3f}, {-1.7f, 1.0f, 0.3f}, "box_a");
    test::add_object_box(scene, {1.7f, 0.5f, -0.3f}, {2.3f, 1.0f, 0.3f}, "box_b");
    test::add_object_box(scene, {-3.5f, 0.2f, 3.0f}, {-3.0f, 0.6f, 3.5f}, "box_c");
    Light l1 = test::point_light("lamp", {-2.0f, 3.0f, 0.0f}, 10.0f, true);
    l1.color = {1.0f, 0.9f, 0.7f};
    Light l2 = test::spot_light("spot", {2.0f, 3.0f, 0.5f}, {0, -1, 0}, 30.0f, 0.5f, 0.9f, true);
    l2.radius = 0.2f;
    Light st = test::point_light("corner", {3.5f, 0.5f, -3.5f}, 2.0f, false);
    st.range = 1.0f;
    scene.lights = {l1, l2, st};
    test::finish(scene);
    texels = test::grid_texels(64, 64, {-4, 0, -4}, {8, 0, 0}, {0, 0, 8}, {0, 1, 0});
  }
};

// Direct light only: these tests check the direct transport exactly (indirect_test.cpp covers
// bounce light).
BakeOptions options(int threads = 0) {
  BakeOptions o;
  o.quality = Quality::kDraft;
  o.threads = threads;
  o.indirect = false;
  return o;
}

TEST(Bake, RecomposedStatesEqualDirectBakes) {
  Fixture f;
  auto tracer = make_embree_tracer(f.scene);
  Progress progress(true);
  Report report;
  const Layout layout = test::bare_layout(64, 64);
  const BakedMaps maps = bake_maps(f.scene, layout, f.texels, *tracer, options(), progress, report);
  ASSERT_EQ(maps.lights, (std::vector<int>{0, 1}));
  ASSERT_EQ(maps.contribution.size(), 2u);

  // Pair decisions: the two boxes under their lights are kept, box_c is out of the spot's cone.
  bool lamp_a = false, spot_b = false, spot_c_culled = false;
  for (const auto& p : report.root()["pairs"]) {
    const std::string l = p["light"], o = p["object"];
    if (l == "lamp" && o == "box_a") lamp_a = p["kept"];
    if (l == "spot" && o == "box_b") spot_b = p["kept"];
    if (l == "spot" && o == "box_c") {
      spot_c_culled = !p["kept"].get<bool>() &&
                      p["reason"].get<std::string>().find("cone") != std::string::npos;
    }
  }
  EXPECT_TRUE(lamp_a);
  EXPECT_TRUE(spot_b);
  EXPECT_TRUE(spot_c_culled);
  EXPECT_GT(report.root()["bake"]["rays"].get<uint64_t>(), 0u);

  std::mt19937 rng(7);
  std::uniform_real_distribution<float> unit(0.0f, 1.0f);
  float worst = 0.0f;
  for (int trial = 0; trial < 12; ++trial) {
    StateSpec state;
    std::vector<glm::vec3> radiant(2);
    for (int k = 0; k < 2; ++k) {
      const Light& l = f.scene.lights[static_cast<size_t>(k)];
      LightOverride o;
      o.has_on = true;
      o.on = unit(rng) < 0.75f;
      o.has_color = true;
      for (float& c : o.color) c = 1.5f * unit(rng);
      o.has_intensity = true;
      o.intensity = 40.0f * unit(rng);
      state.lights[l.name] = o;
      radiant[static_cast<size_t>(k)] =
          o.on ? glm::vec3(o.color[0], o.color[1], o.color[2]) * o.intensity : glm::vec3(0.0f);
    }
    std::vector<bool> visible(f.scene.objects.size());
    for (size_t o = 0; o < f.scene.objects.size(); ++o) {
      visible[o] = unit(rng) < 0.6f;
      state.objects[f.scene.objects[o].name] = visible[o];
    }
    const FloatImage direct =
        bake_state(f.scene, layout, f.texels, *tracer, state, options(), progress, report);
    // Pairs skipped after tracing may drop up to their peak.
    float tolerance = 0.0f;
    for (const auto& p : report.root()["pairs"]) {
      if (p["kept"].get<bool>() || !p.contains("peak")) continue;
      const int li = p["light"] == "lamp" ? 0 : 1;
      const float s = std::max({radiant[li].x, radiant[li].y, radiant[li].z});
      tolerance += p["peak"].get<float>() * s;
    }
    float peak = 0.0f;
    for (int y = 0; y < 64; ++y) {
      for (int x = 0; x < 64; ++x) {
        for (int c = 0; c < 3; ++c) {
          float v = maps.base.at(x, y, c);
          for (size_t k = 0; k < maps.lights.size(); ++k) {
            float t = maps.contribution[k].at(x, y, 0);
            for (const ShadowMap& s : maps.shadows) {
              if (s.light == static_cast<int>(k) && visible[static_cast<size_t>(s.object)]) {
                t -= s.map.at(x, y, 0);
              }
            }
            v += radiant[static_cast<size_t>(maps.lights[k])][c] * t;
          }
          peak = std::max(peak, direct.at(x, y, c));
          worst = std::max(worst, std::fabs(v - direct.at(x, y, c)) - tolerance);
        }
      }
    }
    EXPECT_LE(worst, 1e-4f * std::max(peak, 1.0f)) << "state " << trial;
  }
  std::printf("recompose vs bake-state: max excess error %.3g\n", worst);
}

TEST(Bake, ShadowMapCoversTheHardShadow) {
  Fixture f;
  auto tracer = make_embree_tracer(f.scene);
  Progress progress(true);
  Report report;
  const BakedMaps maps =
      bake_maps(f.scene, test::bare_layout(64, 64), f.texels, *tracer, options(), progress, report);
  const ShadowMap* lamp_a = nullptr;
  for (const ShadowMap& s : maps.shadows) {
    if (s.light == 0 && s.object == 0) lamp_a = &s;
  }
  ASSERT_NE(lamp_a, nullptr);
  // Right under box_a (and the lamp): T = C - S = 0, and S = C > 0.
  int under = 0;
  for (int y = 0; y < 64; ++y) {
    for (int x = 0; x < 64; ++x) {
      const glm::vec3 p = f.texels.position[f.texels.index(x, y)];
      if (std::fabs(p.x + 2.0f) < 0.3f && std::fabs(p.z) < 0.3f) {
        EXPECT_GT(lamp_a->map.at(x, y, 0), 0.0f);
        EXPECT_EQ(maps.contribution[0].at(x, y, 0) - lamp_a->map.at(x, y, 0), 0.0f);
        ++under;
      }
      if (std::fabs(p.x + 2.0f) > 1.5f) {
        EXPECT_EQ(lamp_a->map.at(x, y, 0), 0.0f);
      }
    }
  }
  EXPECT_GT(under, 10);
}

TEST(Bake, ResultsDoNotDependOnThreadCount) {
  Fixture f;
  auto tracer = make_embree_tracer(f.scene);
  Progress progress(true);
  Report r1, r2;
  const Layout layout = test::bare_layout(64, 64);
  const BakedMaps a = bake_maps(f.scene, layout, f.texels, *tracer, options(1), progress, r1);
  const BakedMaps b = bake_maps(f.scene, layout, f.texels, *tracer, options(2), progress, r2);
  EXPECT_EQ(a.output_step, b.output_step);
  EXPECT_EQ(a.base.data, b.base.data);
  ASSERT_EQ(a.contribution.size(), b.contribution.size());
  for (size_t k = 0; k < a.contribution.size(); ++k)
    EXPECT_EQ(a.contribution[k].data, b.contribution[k].data);
  ASSERT_EQ(a.shadows.size(), b.shadows.size());
  for (size_t k = 0; k < a.shadows.size(); ++k)
    EXPECT_EQ(a.shadows[k].map.data, b.shadows[k].map.data);
}

TEST(Bake, StaticLightBakesLikeItsContribution) {
  Fixture semi;
  semi.scene.objects.clear();
  for (MeshInstance& m : semi.scene.meshes) m.object = -1;  // boxes become static geometry
  Fixture stat = semi;
  for (Light& l : stat.scene.lights) l.semi_dynamic = false;
  Progress progress(true);
  Report report;
  const Layout layout = test::bare_layout(64, 64);
  auto t1 = make_embree_tracer(semi.scene);
  auto t2 = make_embree_tracer(stat.scene);
  const BakedMaps ms = bake_maps(semi.scene, layout, semi.texels, *t1, options(), progress, report);
  const BakedMaps mt = bake_maps(stat.scene, layout, stat.texels, *t2, options(), progress, report);
  ASSERT_EQ(ms.contribution.size(), 2u);
  EXPECT_TRUE(mt.contribution.empty());
  float worst = 0.0f, peak = 0.0f;
  for (int y = 0; y < 64; ++y) {
    for (int x = 0; x < 64; ++x) {
      for (int c = 0; c < 3; ++c) {
        float v = ms.base.at(x, y, c);
        for (int k = 0; k < 2; ++k) {
          const Light& l = semi.scene.lights[static_cast<size_t>(k)];
          v += l.color[c] * l.intensity * ms.contribution[static_cast<size_t>(k)].at(x, y, 0);
        }
        worst = std::max(worst, std::fabs(v - mt.base.at(x, y, c)));
        peak = std::max(peak, mt.base.at(x, y, c));
      }
    }
  }
  EXPECT_GT(peak, 0.0f);
  EXPECT_LE(worst, 1e-5f * peak);
}

TEST(Bake, OutOfReachPairIsCulledWithReason) {
  Scene scene;
  test::add_quad(scene, {-5, 0, -5}, {-5, 0, 5}, {5, 0, 5}, {5, 0, -5}, "floor");
  test::add_object_box(scene, {40.0f, 0.0f, 40.0f}, {41.0f, 1.0f, 41.0f}, "far_box");
  Light l = test::point_light("lamp", {0, 2, 0}, 1.0f, true);
  l.range = 5.0f;
  scene.lights = {l};
  test::finish(scene);
  const TexelSet texels = test::grid_texels(16, 16, {-4, 0, -4}, {8, 0, 0}, {0, 0, 8}, {0, 1, 0});
  auto tracer = make_embree_tracer(scene);
  Progress progress(true);
  Report report;
  const BakedMaps maps =
      bake_maps(scene, test::bare_layout(16, 16), texels, *tracer, options(), progress, report);
  EXPECT_TRUE(maps.shadows.empty());
  ASSERT_EQ(report.root()["pairs"].size(), 1u);
  EXPECT_FALSE(report.root()["pairs"][0]["kept"].get<bool>());
  EXPECT_NE(report.root()["pairs"][0]["reason"].get<std::string>().find("reach"),
            std::string::npos);
  EXPECT_EQ(report.root()["pairs_skipped"].get<int>(), 1);
}

TEST(Bake, BakeStateRejectsNamesTheSceneLacks) {
  Fixture f;
  auto tracer = make_embree_tracer(f.scene);
  Progress progress(true);
  Report report;
  const Layout layout = test::bare_layout(64, 64);
  StateSpec unknown_light;
  unknown_light.lights["candle_9"] = LightOverride{};
  EXPECT_THROW(
      bake_state(f.scene, layout, f.texels, *tracer, unknown_light, options(), progress, report),
      CookError);
  StateSpec unknown_object;
  unknown_object.objects["spell_book"] = false;
  try {
    bake_state(f.scene, layout, f.texels, *tracer, unknown_object, options(), progress, report);
    ADD_FAILURE() << "no error";
  } catch (const CookError& e) {
    EXPECT_NE(std::string(e.what()).find("spell_book"), std::string::npos);
  }
  StateSpec static_light;
  static_light.lights["corner"] = LightOverride{};
  EXPECT_THROW(
      bake_state(f.scene, layout, f.texels, *tracer, static_light, options(), progress, report),
      CookError);
}

TEST(Bake, OutputStepIsThePercentileOverTwoFiftyFive) {
  Scene scene;
  test::add_quad(scene, {-5, 0, -5}, {-5, 0, 5}, {5, 0, 5}, {5, 0, -5}, "floor");
  scene.lights = {test::directional_light("sun", {0, -1, 0}, 255.0f)};
  test::finish(scene);
  const TexelSet texels = test::grid_texels(8, 8, {-4, 0, -4}, {8, 0, 0}, {0, 0, 8}, {0, 1, 0});
  auto tracer = make_embree_tracer(scene);
  Progress progress(true);
  Report report;
  const BakedMaps maps =
      bake_maps(scene, test::bare_layout(8, 8), texels, *tracer, options(), progress, report);
  // 255 lux everywhere: the percentile's step is 1, rounded down to a quarter octave (of the
  // scene's own irradiance unit, 1 cd at its diagonal).
  EXPECT_LE(maps.output_step, 1.0f);
  EXPECT_GT(maps.output_step, 1.0f / 1.1893f);
  // Pinned, the step is the one given.
  BakeOptions pinned = options();
  pinned.output_step = 0.37f;
  EXPECT_EQ(bake_maps(scene, test::bare_layout(8, 8), texels, *tracer, pinned, progress, report)
                .output_step,
            0.37f);
  // A black scene still gets a positive step.
  scene.lights.clear();
  const BakedMaps dark =
      bake_maps(scene, test::bare_layout(8, 8), texels, *tracer, options(), progress, report);
  EXPECT_GT(dark.output_step, 0.0f);
}

// BakeSession::bake_groups solves several groups' bounce light, their objects' changes and their
// overlaps' joint changes together (`lightpatch cook`); a farm job bakes its one group with
// bake_group. Both must give the same maps and decisions, bit for bit: one room, five lights
// (two batches), a box on a table (an overlap), a stool outside a spot's cone (bounce only) and a
// static lamp.
TEST(Bake, GroupsBakedTogetherEqualEachBakedAlone) {
  Scene scene;
  test::add_closed_room(scene, {-3, 0, -3}, {3, 2.5f, 3}, 0.1f, "room");
  test::add_object_box(scene, {-1.0f, 0.0f, -0.5f}, {0.6f, 0.7f, 0.5f}, "table");
  test::add_object_box(scene, {-0.3f, 0.7f, -0.2f}, {0.1f, 1.0f, 0.2f}, "box");
  test::add_object_box(scene, {2.0f, 0.0f, 2.0f}, {2.5f, 0.5f, 2.5f}, "stool");
  Light soft = test::point_light("candle", {0.5f, 1.5f, 0.0f}, 2.0f, true);
  soft.radius = 0.05f;
  scene.lights = {
      test::point_light("lamp_a", {-2, 2.2f, -2}, 6.0f, true),
      test::point_light("lamp_b", {2, 2.2f, -2}, 6.0f, true),
      soft,
      test::spot_light("spot", {-2, 2.3f, 2}, {0.3f, -1, -0.3f}, 20.0f, 0.2f, 0.4f, true),
      test::point_light("lamp_c", {0, 2.2f, 2}, 4.0f, true),
      test::point_light("corner", {2.5f, 2.0f, 2.5f}, 3.0f, false)};
  test::finish(scene);
  const test::Prepared p = test::prepare(scene, 64);
  BakeOptions o;
  o.quality = Quality::kDraft;
  Progress progress(true);
  Report report;
  BakeSession session(scene, p.layout, p.texels, *p.tracer, o, progress, report);
  const size_t n = session.plan().groups.size();
  ASSERT_EQ(n, 6u);
  ASSERT_GT(n, BakeSession::kGroupBatch);  // two batches
  std::vector<size_t> all(n);
  for (size_t g = 0; g < n; ++g) all[g] = g;
  const std::vector<GroupBake> together = session.bake_groups(all, progress, report);
  ASSERT_EQ(together.size(), n);
  auto same = [](const FloatImage& a, const FloatImage& b) {
    return a.width == b.width && a.height == b.height && a.channels == b.channels &&
           a.data.size() == b.data.size() &&
           (a.data.empty() ||
            std::memcmp(a.data.data(), b.data.data(), a.data.size() * sizeof(float)) == 0);
  };
  size_t shadows = 0, corrections = 0, bounce_only = 0;
  for (size_t g = 0; g < n; ++g) {
    const GroupBake alone = session.bake_group(g, progress, report);
    const GroupBake& t = together[g];
    EXPECT_EQ(t.group, g);
    EXPECT_TRUE(same(alone.map, t.map)) << g;
    EXPECT_TRUE(same(alone.indirect, t.indirect)) << g;
    EXPECT_TRUE(same(alone.direct, t.direct)) << g;
    ASSERT_EQ(alone.shadows.size(), t.shadows.size()) << g;
    for (size_t k = 0; k < t.shadows.size(); ++k) {
      EXPECT_EQ(alone.shadows[k].object, t.shadows[k].object) << g;
      EXPECT_TRUE(same(alone.shadows[k].map, t.shadows[k].map)) << g << " " << k;
      EXPECT_TRUE(same(alone.shadows[k].indirect, t.shadows[k].indirect)) << g << " " << k;
    }
    ASSERT_EQ(alone.pair_corrections.size(), t.pair_corrections.size()) << g;
    for (size_t k = 0; k < t.pair_corrections.size(); ++k) {
      EXPECT_TRUE(same(alone.pair_corrections[k].map, t.pair_corrections[k].map)) << g;
      EXPECT_TRUE(same(alone.pair_corrections[k].indirect, t.pair_corrections[k].indirect)) << g;
    }
    ASSERT_EQ(alone.static_shadows.size(), t.static_shadows.size()) << g;
    for (size_t k = 0; k < t.static_shadows.size(); ++k)
      EXPECT_TRUE(same(alone.static_shadows[k].map, t.static_shadows[k].map)) << g;
    ASSERT_EQ(alone.decisions.size(), t.decisions.size()) << g;
    for (size_t k = 0; k < t.decisions.size(); ++k) {
      const Decision &a = alone.decisions[k], &b = t.decisions[k];
      EXPECT_EQ(int(a.kind), int(b.kind)) << g << " " << k;
      EXPECT_EQ(a.object, b.object) << g << " " << k;
      EXPECT_EQ(a.object_b, b.object_b) << g << " " << k;
      EXPECT_EQ(a.taken, b.taken) << g << " " << k;
      EXPECT_EQ(a.reason, b.reason) << g << " " << k;
      if (a.kind == DecisionKind::kObjectBounce && a.stage == DecisionStage::kBounce && a.taken)
        ++bounce_only;
    }
    shadows += t.shadows.size();
    corrections += t.pair_corrections.size();
  }
  // The scene exercises what is solved together: shadows with bounce light, overlaps, an object
  // that changes only bounce light.
  EXPECT_GT(shadows, 8u);
  EXPECT_GT(corrections, 0u);
  EXPECT_GT(bounce_only, 0u);
}

}  // namespace
}  // namespace lightpatch::cooker
