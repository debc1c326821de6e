// Indirect light with small, fast settings (unit tests, also run under ASan): energy in a closed
// box, stability at albedo near 1, an open scene, colour bleeding, and recomposition
// against bake-state for one object at a time. indirect_quality_test.cpp has the production runs.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <random>

#include "indirect/gather.h"
#include "indirect/solve.h"
#include "indirect_test_scenes.h"
#include "lightpatch/cooker/bake.h"
#include "lightpatch/cooker/tracer.h"
#include "texel_footprint.h"

namespace lightpatch::cooker {
namespace {

constexpr float kPi = 3.14159265358979f;

struct FurnaceResult {
  double flux = 0.0;
  bool finite = true;
};

// Total incident flux sum(E * area) over the inner faces of the closed box, light of 1 cd.
FurnaceResult furnace(float rho, const BakeOptions& o, int n, bool semi = false) {
  Scene s = test::furnace_box(rho);
  s.lights = {test::furnace_lamp(semi)};
  TexelSet texels = test::box_texels({-1, -1, -1}, {1, 1, 1}, n);
  texels.albedo.assign(texels.albedo.size(), glm::vec3(rho));  // gathering reads texel albedo
  auto tracer = make_embree_tracer(s);
  Progress progress(true);
  Report report;
  const BakedMaps maps = bake_maps(s, test::bare_layout(texels.width, texels.height), texels,
                                   *tracer, o, progress, report);
  FurnaceResult r;
  for (size_t t = 0; t < texels.position.size(); ++t) {
    const int x = int(t % size_t(texels.width)), y = int(t / size_t(texels.width));
    for (int c = 0; c < 3; ++c) {
      const float e = semi ? maps.contribution[0].at(x, y, c) : maps.base.at(x, y, c);
      r.finite = r.finite && std::isfinite(e);
      if (c == 0) r.flux += double(e) * test::box_texel_area({-1, -1, -1}, {1, 1, 1}, n, t);
    }
  }
  return r;
}

// Final gathering conserves energy in the furnace: what is left is the gather noise, the texel
// grid and the bounces the tolerance drops.
TEST(Indirect, FurnaceConservesEnergy) {
  BakeOptions o;
  o.quality = Quality::kDraft;
  o.indirect_scale = 2;
  for (bool semi : {false, true}) {
    const FurnaceResult r = furnace(0.5f, o, 12, semi);
    const double expected = 4.0 * kPi / (1.0 - 0.5);
    std::printf("furnace rho 0.5 (gather), %s: %.4f vs %.4f (%+.2f%%)\n", semi ? "C_l" : "B",
                r.flux, expected, 100.0 * (r.flux / expected - 1.0));
    EXPECT_TRUE(r.finite);
    EXPECT_NEAR(r.flux / expected, 1.0, 0.01);
  }
}

TEST(Indirect, AlbedoNearOneStaysFinite) {
  BakeOptions o;
  o.quality = Quality::kDraft;
  const FurnaceResult r = furnace(0.99f, o, 6);
  EXPECT_TRUE(r.finite);
  const double expected = 4.0 * kPi / (1.0 - 0.99);
  std::printf("furnace rho 0.99 (draft): %.2f vs %.2f\n", r.flux, expected);
  EXPECT_GT(r.flux, 0.8 * expected);
  EXPECT_LT(r.flux, 1.1 * expected);
}

// A candle inside its closed flame mesh (albedo 1, extras castShadows: false) lights and bounces
// exactly like the same candle without the mesh; the same mesh casting shadows swallows it.
TEST(Indirect, LightInsideItsOwnFlameMeshIsNotSwallowed) {
  BakeOptions o;
  o.quality = Quality::kDraft;
  const glm::vec3 lamp{0.13f, 0.21f, -0.17f};
  auto bake = [&](int flame) {  // 0: no flame mesh, 1: flame casting no shadows, 2: casting
    Scene s = test::furnace_box(0.5f);
    s.materials.push_back({"flame", glm::vec3(1.0f), -1, glm::vec3(0.0f)});
    if (flame > 0) {
      const int m = test::add_box(s, lamp - glm::vec3(0.02f), lamp + glm::vec3(0.02f), "flame", -1,
                                  int(s.materials.size()) - 1);
      s.meshes[size_t(m)].cast_shadows = flame == 2;
    }
    test::finish(s);
    s.lights = {test::point_light("candle", lamp, 1.0f)};
    const TexelSet texels = test::box_texels({-1, -1, -1}, {1, 1, 1}, 8);
    auto tracer = make_embree_tracer(s);
    Progress progress(true);
    Report report;
    return bake_maps(s, test::bare_layout(texels.width, texels.height), texels, *tracer, o,
                     progress, report)
        .base;
  };
  const FloatImage bare = bake(0), flame = bake(1), shut = bake(2);
  double sum_bare = 0.0, sum_shut = 0.0;
  for (size_t i = 0; i < bare.data.size(); ++i) {
    EXPECT_FLOAT_EQ(flame.data[i], bare.data[i]) << "texel component " << i;
    sum_bare += bare.data[i];
    sum_shut += shut.data[i];
  }
  EXPECT_GT(sum_bare, 0.0);
  EXPECT_LT(sum_shut, 0.01 * sum_bare);  // a flame that casts shadows would swallow the candle
}

// A decision of `kind` about light (or group) `light`, taken or not.
bool has_decision(Report& report, const std::string& kind, const std::string& light, bool taken) {
  for (const auto& d : report.root()["decisions"]) {
    const std::string l = d.contains("light") ? d["light"].get<std::string>() : "static lights";
    if (d["kind"] == kind && l == light && d["taken"].get<bool>() == taken) return true;
  }
  return false;
}

// Light that leaves an open scene bounces nowhere: the groups' bounce light is dropped.
TEST(Indirect, OpenSceneGetsNoBounce) {
  Scene s;
  test::add_quad(s, {-5, 0, -5}, {-5, 0, 5}, {5, 0, 5}, {5, 0, -5}, "floor");
  // Two spots above an open floor, shining up: all their light leaves the scene.
  s.lights = {test::spot_light("sky", {1, 1, 0}, {0, 1, 0}, 10.0f, 0.2f, 0.4f),
              test::spot_light("up", {0, 1, 0}, {0, 1, 0}, 10.0f, 0.2f, 0.4f, true)};
  test::finish(s);
  const TexelSet texels = test::grid_texels(8, 8, {-4, 0, -4}, {8, 0, 0}, {0, 0, 8}, {0, 1, 0});
  auto tracer = make_embree_tracer(s);
  Progress progress(true);
  BakeOptions o;
  o.quality = Quality::kDraft;
  Report report;
  const BakedMaps maps =
      bake_maps(s, test::bare_layout(8, 8), texels, *tracer, o, progress, report);
  EXPECT_TRUE(has_decision(report, "group_bounce", "static lights", false));
  EXPECT_TRUE(has_decision(report, "group_bounce", "up", false));
  ASSERT_EQ(maps.contribution.size(), 1u);
  EXPECT_EQ(maps.contribution[0].channels, 1);  // no bounce: one channel
}

// A red wall and a white wall meeting at a corner on a grey floor; a semi-dynamic spot lights the
// red wall only. The white wall gets red-tinted bounce, carried by C_l's three channels, and the
// recomposed tint follows the light's colour and intensity.
struct ColourScene {
  Scene scene;
  int white_mesh = -1;  // the white wall's mesh
  ColourScene() {
    Material grey;
    grey.albedo = glm::vec3(0.5f);
    Material red;
    red.albedo = glm::vec3(0.9f, 0.1f, 0.1f);
    Material white;
    white.albedo = glm::vec3(0.9f);
    scene.materials = {grey, red, white};
    test::add_quad(scene, {-2, 0, -2}, {-2, 0, 2}, {2, 0, 2}, {2, 0, -2}, "floor", -1, 0);
    // Red wall at x = -2 facing +x; white wall at z = -2 facing +z.
    test::add_quad(scene, {-2, 0, -2}, {-2, 2, -2}, {-2, 2, 2}, {-2, 0, 2}, "red", -1, 1);
    white_mesh =
        test::add_quad(scene, {-2, 0, -2}, {2, 0, -2}, {2, 2, -2}, {-2, 2, -2}, "white", -1, 2);
    scene.lights = {
        test::spot_light("spot", {0.0f, 1.0f, 0.5f}, {-1, 0, 0}, 20.0f, 0.2f, 0.35f, true)};
    test::finish(scene);
  }
};

TEST(Indirect, ColourBleedingFollowsTheLight) {
  ColourScene f;
  const test::Prepared p = test::prepare(f.scene, 64);
  const TexelSet& texels = p.texels;
  const Layout& layout = p.layout;
  const Tracer* tracer = p.tracer.get();
  Progress progress(true);
  Report report;
  BakeOptions o;
  o.quality = Quality::kDraft;
  const BakedMaps maps = bake_maps(f.scene, layout, texels, *tracer, o, progress, report);
  ASSERT_EQ(maps.contribution.size(), 1u);
  const FloatImage& c = maps.contribution[0];
  ASSERT_EQ(c.channels, 3);
  // Near the corner with the red wall (x < -1) the white wall's light is red.
  auto near_red = [&](int x, int y) {
    const size_t t = texels.index(x, y);
    return texels.valid[t] && texels.mesh[t] == f.white_mesh && texels.position[t].x < -1.0f;
  };
  double r = 0.0, g = 0.0;
  for (int y = 0; y < texels.height; ++y) {
    for (int x = 0; x < texels.width; ++x) {
      if (!near_red(x, y)) continue;
      r += c.at(x, y, 0);
      g += c.at(x, y, 1);
      EXPECT_NEAR(c.at(x, y, 1), c.at(x, y, 2), 1e-6f * std::max(1.0f, c.at(x, y, 1)));
    }
  }
  EXPECT_GT(g, 0.0);
  EXPECT_GT(r, 2.0 * g);
  // Recomposition B + colour * intensity * C_l against direct bakes of two states.
  struct St {
    glm::vec3 color;
    float intensity;
  };
  for (const St& st : {St{{1.0f, 1.0f, 1.0f}, 20.0f}, St{{0.3f, 0.6f, 1.0f}, 45.0f}}) {
    StateSpec state;
    LightOverride lo;
    lo.has_color = true;
    lo.color[0] = st.color.x;
    lo.color[1] = st.color.y;
    lo.color[2] = st.color.z;
    lo.has_intensity = true;
    lo.intensity = st.intensity;
    state.lights["spot"] = lo;
    const FloatImage direct =
        bake_state(f.scene, layout, texels, *tracer, state, o, progress, report);
    double rr = 0.0, gg = 0.0;
    for (int y = 0; y < texels.height; ++y) {
      for (int x = 0; x < texels.width; ++x) {
        if (!texels.valid[texels.index(x, y)]) continue;
        for (int k = 0; k < 3; ++k) {
          const float v = maps.base.at(x, y, k) + st.color[k] * st.intensity * c.at(x, y, k);
          // Float rounding, and the bounce terms each solve drops below 2 % of an output step
          // (bake_state solves at its state's brightness, the maps at the authored one).
          EXPECT_NEAR(v, direct.at(x, y, k),
                      1e-5f * std::max(1.0f, direct.at(x, y, k)) + 0.01f * maps.output_step);
        }
        if (near_red(x, y)) {
          rr += direct.at(x, y, 0);
          gg += direct.at(x, y, 1);
        }
      }
    }
    // The tint is the walls' times the light's.
    EXPECT_NEAR(rr / gg, (r / g) * (st.color.x / st.color.y), 3e-3 * rr / gg);
  }
}

// A room with a box, a semi-dynamic light; the box blocks bounce light and adds its own (a red
// box: S_ol is negative where its bounce lands). Recomposition equals bake-state for each
// single-object state, and one cook does not depend on the thread count.
struct BoxRoom {
  Scene scene;
  BoxRoom() {
    Material wall;
    wall.albedo = glm::vec3(0.7f);
    Material red;
    red.albedo = glm::vec3(0.9f, 0.2f, 0.1f);
    scene.materials = {wall, red};
    test::add_closed_room(scene, {-2, 0, -2}, {2, 2.5f, 2}, 0.1f, "room");
    Object o;
    o.name = "crate";
    scene.objects.push_back(o);
    test::add_box(scene, {-0.4f, 0.0f, -0.4f}, {0.4f, 0.8f, 0.4f}, "crate", 0, 1);
    Object o2;
    o2.name = "stool";
    scene.objects.push_back(o2);
    test::add_box(scene, {1.0f, 0.0f, 1.0f}, {1.4f, 0.5f, 1.4f}, "stool", 1, 0);
    scene.lights = {test::point_light("lamp", {0.3f, 2.0f, -0.6f}, 5.0f, true)};
    test::finish(scene);
  }
};

TEST(Indirect, SingleObjectRecompositionEqualsBakeState) {
  BoxRoom box;
  const test::Prepared f = test::prepare(box.scene, 96);
  const Layout& layout = f.layout;
  const Tracer* tracer = f.tracer.get();
  Progress progress(true);
  Report report;
  BakeOptions o;
  o.quality = Quality::kDraft;
  const BakedMaps maps = bake_maps(box.scene, layout, f.texels, *tracer, o, progress, report);
  ASSERT_EQ(maps.contribution.size(), 1u);
  ASSERT_EQ(maps.contribution[0].channels, 3);
  const ShadowMap* crate = nullptr;
  for (const ShadowMap& s : maps.shadows) {
    if (s.object == 0) crate = &s;
  }
  ASSERT_NE(crate, nullptr);
  float most_negative = 0.0f;
  for (float v : crate->map.data) most_negative = std::min(most_negative, v);
  EXPECT_LT(most_negative, 0.0f) << "the crate's bounce should add light somewhere";

  for (int visible = 0; visible < 4; ++visible) {
    const bool crate_on = visible & 1, stool_on = visible & 2;
    if (crate_on && stool_on) continue;  // two objects: the paper's overlap approximation
    StateSpec state;
    state.objects["crate"] = crate_on;
    state.objects["stool"] = stool_on;
    LightOverride lo;
    lo.has_color = true;
    lo.color[0] = 1.0f;
    lo.color[1] = 0.7f;
    lo.color[2] = 0.4f;
    state.lights["lamp"] = lo;
    const FloatImage direct =
        bake_state(box.scene, layout, f.texels, *tracer, state, o, progress, report);
    float worst = 0.0f, peak = 0.0f;
    for (int y = 0; y < f.texels.height; ++y) {
      for (int x = 0; x < f.texels.width; ++x) {
        for (int k = 0; k < 3; ++k) {
          float t = maps.contribution[0].at(x, y, k);
          for (const ShadowMap& s : maps.shadows) {
            if ((s.object == 0 && crate_on) || (s.object == 1 && stool_on)) t -= s.map.at(x, y, k);
          }
          const float v = maps.base.at(x, y, k) + lo.color[size_t(k)] * 5.0f * t;
          worst = std::max(worst, std::fabs(v - direct.at(x, y, k)));
          peak = std::max(peak, direct.at(x, y, k));
        }
      }
    }
    EXPECT_LE(worst, 1e-4f * peak) << "crate " << crate_on << " stool " << stool_on;
  }

  BakeOptions one = o, two = o;
  one.threads = 1;
  two.threads = 2;
  Report r1, r2;
  const BakedMaps a = bake_maps(box.scene, layout, f.texels, *tracer, one, progress, r1);
  const BakedMaps b = bake_maps(box.scene, layout, f.texels, *tracer, two, progress, r2);
  EXPECT_EQ(a.base.data, b.base.data);
  EXPECT_EQ(a.contribution[0].data, b.contribution[0].data);
  ASSERT_EQ(a.shadows.size(), b.shadows.size());
  for (size_t k = 0; k < a.shadows.size(); ++k)
    EXPECT_EQ(a.shadows[k].map.data, b.shadows[k].map.data);
}

// The box room's gather rays (64 per coarse texel, indirect level 2) and their reach.
struct BoxRoomGather {
  BoxRoom box;
  test::Prepared f = test::prepare(box.scene, 64);
  GatherOperator op;
  GatherReach reach;
  // near_hits: with the texels' footprints, so that rays into the corners are near hits.
  explicit BoxRoomGather(bool near_hits = false) {
    GatherOptions go;
    go.rays = 64;
    go.threads = 2;
    std::vector<TexelFootprint> footprints;
    if (near_hits) {
      footprints = texel_footprints(f.texels, f.tracer.get(), 2);
      go.footprints = &footprints;
    }
    op = build_gather(box.scene, f.layout, f.texels, *f.tracer, 2, go);
    reach = gather_reach(op, 2);
  }
};

// GatherReach (solve.h) only spares the gathers whose sum is 0: with it the series visit fewer
// receivers of a sparse source and give the same bits, objects present or not.
TEST(Indirect, ReachVisitsFewerReceiversAndGivesTheSameBits) {
  const BoxRoomGather box;
  const GatherOperator& op = box.op;
  const GatherReach& reach = box.reach;
  const size_t nc = op.grid.size();
  // Light on one tile only (an object's shadow), and light everywhere.
  CoarseMap sparse(nc, glm::vec3(0.0f)), dense(nc);
  for (size_t c = 0; c < nc; ++c) {
    dense[c] = glm::vec3(0.5f + 0.01f * float(c % 7), 0.3f, 0.1f);
    if (op.tile_of[c] == op.tile_of[nc / 2]) sparse[c] = glm::vec3(1.0f, 0.5f, 0.25f);
  }
  SolveOptions plain;
  plain.tolerance = 1e-6f;
  plain.max_bounces = 8;
  plain.threads = 2;
  SolveOptions fast = plain;
  fast.reach = &reach;
  auto same = [](const CoarseMap& a, const CoarseMap& b) {
    return a.size() == b.size() && std::memcmp(a.data(), b.data(), a.size() * sizeof(a[0])) == 0;
  };
  for (const std::vector<uint8_t>& present :
       {std::vector<uint8_t>{}, std::vector<uint8_t>{1, 0}, std::vector<uint8_t>{1, 1}}) {
    for (const CoarseMap* src : {&sparse, &dense}) {
      SolveStats s_plain, s_fast;
      const Bounces a = solve_indirect(op, present, *src, plain, &s_plain);
      const Bounces b = solve_indirect(op, present, *src, fast, &s_fast);
      EXPECT_TRUE(same(a.first, b.first) && same(a.second, b.second) && same(a.rest, b.rest));
      EXPECT_LE(s_fast.gathers, s_plain.gathers);
      if (src == &sparse) {
        EXPECT_LT(s_fast.gathers, s_plain.gathers);
      }
      if (present.empty()) continue;
      const EmptyRadiance e = empty_radiance(op, *src, a);
      EXPECT_TRUE(same(solve_change(op, present, e, sparse, plain),
                       solve_change(op, present, e, sparse, fast)));
    }
  }
}

// A batched solve `solve(options, first)` as asked (first = true) and one thread wide: a batch's
// results must not depend on the thread count.
template <typename Solve>
auto two_ways(const SolveOptions& so, Solve&& solve) {
  SolveOptions one = so;
  one.threads = 1;
  auto asked = solve(so, true);
  return std::make_pair(std::move(asked), solve(one, false));
}

// solve_changes (solve.h) runs several changes side by side, each bounce's gathers sharing one
// pass over the stored rays: each job must get the bits it gets alone, whatever its batch (more
// jobs than kChangeBatch, sparse and dense sources, one object, both, none, changes of two
// groups with their own tolerances), on any thread count.
TEST(Indirect, BatchedChangesEqualEachChangeSolvedAlone) {
  const BoxRoomGather box;
  const GatherOperator& op = box.op;
  const GatherReach& reach = box.reach;
  const size_t nc = op.grid.size();
  CoarseMap light(nc);
  for (size_t c = 0; c < nc; ++c) light[c] = glm::vec3(0.5f + 0.01f * float(c % 7), 0.3f, 0.1f);
  SolveOptions so;
  so.tolerance = 1e-5f;
  so.max_bounces = 12;
  so.threads = 2;
  so.reach = &reach;
  CoarseMap other(nc, glm::vec3(0.0f));  // a second group: a light on a third of the tiles
  for (size_t c = 0; c < nc; ++c)
    if (op.tile_of[c] % 3 == 0) other[c] = glm::vec3(0.1f, 0.4f, 0.9f);
  const EmptyRadiance e = empty_radiance(op, light, solve_indirect(op, {}, light, so));
  const EmptyRadiance e2 = empty_radiance(op, other, solve_indirect(op, {}, other, so));
  const std::vector<std::vector<uint8_t>> presents = {{1, 0}, {0, 1}, {1, 1}, {0, 0}};
  std::vector<ChangeJob> jobs;
  for (size_t j = 0; j < kChangeBatch + 3; ++j) {
    ChangeJob job;
    job.present = &presents[j % presents.size()];
    job.empty = j % 3 == 1 ? &e2 : &e;
    job.tolerance = j % 2 == 1 ? 3e-5f : 1e-5f;
    job.direct_change.assign(nc, glm::vec3(0.0f));
    // A source on a few tiles (an object's shadow), a different one each job; every fifth dense.
    for (size_t c = 0; c < nc; ++c)
      if (j % 5 == 4 || op.tile_of[c] % (j + 2) == 0)
        job.direct_change[c] = glm::vec3(0.2f * float(j + 1), 0.1f, 0.05f * float(c % 3));
    jobs.push_back(std::move(job));
  }
  std::vector<SolveStats> stats;
  const auto [together, single_thread] = two_ways(so, [&](const SolveOptions& o, bool first) {
    return solve_changes(op, jobs, o, first ? &stats : nullptr);
  });
  ASSERT_EQ(together.size(), jobs.size());
  ASSERT_EQ(stats.size(), jobs.size());
  bool some_differ = false;
  for (size_t j = 0; j < jobs.size(); ++j) {
    SolveStats alone_stats;
    SolveOptions own = so;
    own.tolerance = jobs[j].tolerance;
    const CoarseMap alone = solve_change(op, *jobs[j].present, *jobs[j].empty,
                                         jobs[j].direct_change, own, &alone_stats);
    ASSERT_EQ(alone.size(), nc);
    EXPECT_EQ(std::memcmp(alone.data(), together[j].data(), nc * sizeof(alone[0])), 0) << j;
    EXPECT_EQ(std::memcmp(alone.data(), single_thread[j].data(), nc * sizeof(alone[0])), 0) << j;
    EXPECT_EQ(alone_stats.bounces, stats[j].bounces) << j;
    EXPECT_EQ(alone_stats.gathers, stats[j].gathers) << j;
    if (j > 0 && std::memcmp(together[j].data(), together[0].data(), nc * sizeof(alone[0])) != 0)
      some_differ = true;
  }
  EXPECT_TRUE(some_differ) << "the jobs should not all give one map";
}

// solve_indirect_many (solve.h) solves several group sources side by side (the moving lights'
// panes), each bounce's gathers sharing one pass over the stored rays: each source must get the
// bits solve_indirect gives it alone, whatever its batch (more than kChangeBatch, sources on a
// few tiles and dense ones, with and without near sources), on any thread count.
TEST(Indirect, SourcesSolvedSideBySideEqualEachSolvedAlone) {
  const BoxRoomGather box(/*near_hits=*/true);
  const GatherOperator& op = box.op;
  ASSERT_GT(op.near.size(), 0u);
  const size_t nc = op.grid.size();
  SolveOptions so;
  so.tolerance = 1e-5f;
  so.max_bounces = 12;
  so.threads = 2;
  so.reach = &box.reach;
  const NearIndex index = near_index(op);
  so.near = &index;
  std::vector<CoarseMap> sources;
  for (size_t j = 0; j < kChangeBatch + 3; ++j) {
    CoarseMap src(nc, glm::vec3(0.0f));
    // A pane's texels on a few tiles, a different set each; every fifth dense.
    for (size_t c = 0; c < nc; ++c)
      if (j % 5 == 4 || op.tile_of[c] % (j + 2) == 0)
        src[c] = glm::vec3(0.2f * float(j + 1), 0.1f, 0.05f * float(c % 3));
    sources.push_back(std::move(src));
  }
  // Near sources for every other job (a third of the near hits each), none for the others.
  std::vector<NearSource> near(sources.size());
  std::vector<const NearSource*> near_of(sources.size(), nullptr);
  for (size_t j = 0; j < sources.size(); j += 2) {
    for (uint32_t i = 0; i < op.near.size(); i += 3) near[j].push_back({i, glm::vec3(0.3f)});
    near_of[j] = &near[j];
  }
  // Each source its own tolerance (light groups of different significance).
  std::vector<float> tolerance(sources.size());
  for (size_t j = 0; j < sources.size(); ++j) tolerance[j] = j % 3 == 2 ? 4e-5f : 1e-5f;
  std::vector<SolveStats> stats;
  const auto [together, single_thread] = two_ways(so, [&](const SolveOptions& o, bool first) {
    return solve_indirect_many(op, sources, near_of, o, first ? &stats : nullptr, tolerance);
  });
  ASSERT_EQ(together.size(), sources.size());
  ASSERT_EQ(single_thread.size(), sources.size());
  ASSERT_EQ(stats.size(), sources.size());
  auto same = [&](const CoarseMap& a, const CoarseMap& b) {
    return a.size() == nc && b.size() == nc &&
           std::memcmp(a.data(), b.data(), nc * sizeof(a[0])) == 0;
  };
  bool some_differ = false;
  for (size_t j = 0; j < sources.size(); ++j) {
    SolveStats alone_stats;
    SolveOptions own = so;
    own.tolerance = tolerance[j];
    const Bounces alone = solve_indirect(op, {}, sources[j], own, &alone_stats, near_of[j]);
    for (const Bounces* b : {&together[j], &single_thread[j]}) {
      EXPECT_TRUE(same(alone.first, b->first)) << j;
      EXPECT_TRUE(same(alone.second, b->second)) << j;
      EXPECT_TRUE(same(alone.rest, b->rest)) << j;
    }
    EXPECT_EQ(alone_stats.bounces, stats[j].bounces) << j;
    EXPECT_EQ(alone_stats.gathers, stats[j].gathers) << j;
    EXPECT_GT(stats[j].bounces, 2) << j;  // a series, not just a first bounce
    if (j > 0 && !same(together[j].total(), together[0].total())) some_differ = true;
  }
  EXPECT_TRUE(some_differ) << "the sources should not all give one map";
}

// Near hits (gather.h NearHit): gather rays that land within two texels of where they leave
// (the box room's corners) are listed with their points, and the first bounce reads their own
// source there instead of the cache's value at the texel they land on: the correction is exactly
// weight * (near - cache) on their receiver's first bounce, and none where they agree.
TEST(Indirect, NearHitsReadTheirOwnSourceInTheFirstBounce) {
  BoxRoom box;
  const test::Prepared f = test::prepare(box.scene, 64);
  const std::vector<TexelFootprint> footprints = texel_footprints(f.texels, f.tracer.get(), 2);
  GatherOptions go;
  go.rays = 64;
  go.threads = 2;
  GatherOperator op = build_gather(box.scene, f.layout, f.texels, *f.tracer, 2, go);
  EXPECT_TRUE(op.near.empty());  // without footprints (one texel sample) there are none
  go.footprints = &footprints;
  op = build_gather(box.scene, f.layout, f.texels, *f.tracer, 2, go);
  const size_t nc = op.grid.size();
  ASSERT_EQ(op.near_offset.size(), nc + 1);
  ASSERT_GT(op.near.size(), 0u);
  EXPECT_LT(op.near.size(), op.hit.size() / 4);  // a few rays in the corners, not most
  for (size_t c = 0; c < nc; ++c) {
    for (uint32_t i = op.near_offset[c]; i < op.near_offset[c + 1]; ++i) {
      const NearHit& h = op.near[i];
      ASSERT_LT(h.ray, uint32_t(op.rays));
      ASSERT_NE(op.hit[c * size_t(op.rays) + h.ray], kNoTexel);
      // On the surface of the texel it lands on: within a few of its spacings.
      const float spacing =
          std::max(glm::length(footprints[h.fine].u), glm::length(footprints[h.fine].v));
      EXPECT_LT(glm::length(h.point - f.texels.position[h.fine]), 4.0f * spacing);
      EXPECT_GE(h.count, 1u);
    }
  }
  CoarseMap source(nc);
  for (size_t c = 0; c < nc; ++c) source[c] = glm::vec3(0.5f + 0.01f * float(c % 7), 0.3f, 0.1f);
  // The near source equal to the cache's value at each hit: the same first bounce.
  NearSource near(op.near.size());
  std::vector<uint32_t> receiver(op.near.size());
  for (size_t c = 0; c < nc; ++c)
    for (uint32_t i = op.near_offset[c]; i < op.near_offset[c + 1]; ++i) {
      near[i] = {i, source[op.hit[c * size_t(op.rays) + op.near[i].ray]]};
      receiver[i] = uint32_t(c);
    }
  SolveOptions so;
  so.tolerance = 1e-6f;
  so.max_bounces = 4;
  so.threads = 2;
  const NearIndex index = near_index(op);
  so.near = &index;
  const Bounces plain = solve_indirect(op, {}, source, so);
  const Bounces same = solve_indirect(op, {}, source, so, nullptr, &near);
  for (size_t c = 0; c < nc; ++c)
    EXPECT_NEAR(same.first[c].x, plain.first[c].x, 1e-5f * (1.0f + plain.first[c].x)) << c;
  // One near hit sees 1 more than the cache: its receiver's first bounce gains its rays' weight.
  const size_t pick = op.near.size() / 2;
  near[pick].second += glm::vec3(1.0f);
  const Bounces moved = solve_indirect(op, {}, source, so, nullptr, &near);
  for (size_t c = 0; c < nc; ++c) {
    const float expect = c == receiver[pick] ? op.weight[0][c] * float(op.near[pick].count) : 0.0f;
    EXPECT_NEAR(moved.first[c].x - plain.first[c].x, expect, 1e-5f) << c;
  }
  // A change reads the near hits' change the same way.
  const EmptyRadiance e = empty_radiance(op, source, plain);
  const std::vector<uint8_t> none(box.scene.objects.size(), 0);
  const CoarseMap zero(nc, glm::vec3(0.0f));
  const NearSource near_change = {{uint32_t(pick), glm::vec3(2.0f)}};
  const CoarseMap ch = solve_change(op, none, e, zero, so, nullptr, &near_change);
  // The later bounces add little back to it.
  const float w = op.weight[0][receiver[pick]] * float(op.near[pick].count);
  EXPECT_NEAR(ch[receiver[pick]].x, 2.0f * w, 0.1f * w);
}

}  // namespace
}  // namespace lightpatch::cooker

namespace lightpatch::cooker {
namespace {

// The denoiser's near-field guide (solve.h): where a floor meets a wall, bounce light falls from
// the open floor's level to a fraction of it within a few texels (ambient occlusion). Weights from
// the near field keep the two apart, which the plane and normal weights of a flat floor cannot;
// the filter stays linear.
TEST(Denoise, NearFieldKeepsAContactGradientAndStaysLinear) {
  const TexelSet texels = test::grid_texels(32, 32, glm::vec3(0.0f), glm::vec3(1, 0, 0),
                                            glm::vec3(0, 0, 1), glm::vec3(0, 1, 0));
  const CoarseGrid grid = build_coarse_grid(texels, 2, nullptr, 1);
  ASSERT_GT(grid.size(), 16u);
  // Coarse texels with x < 0.25 are "at the wall's foot": dim, their near field high.
  CoarseMap map(grid.size()), other(grid.size());
  std::vector<float> near(grid.size());
  std::mt19937 rng(3);
  std::uniform_real_distribution<float> u(0.0f, 1.0f);
  for (size_t c = 0; c < grid.size(); ++c) {
    const bool foot = grid.position[c].x < 0.25f;
    map[c] = glm::vec3(foot ? 0.1f : 1.0f);
    other[c] = glm::vec3(u(rng), u(rng), u(rng));
    near[c] = foot ? 0.4f : 0.0f;
  }
  CoarseMap guided = map, plain = map;
  denoise(grid, 2, guided, &near, near_field_sigma(256));
  denoise(grid, 2, plain);
  float worst_guided = 0.0f, worst_plain = 0.0f;
  for (size_t c = 0; c < grid.size(); ++c) {
    if (grid.position[c].x >= 0.25f) continue;
    worst_guided = std::max(worst_guided, guided[c].x);
    worst_plain = std::max(worst_plain, plain[c].x);
  }
  EXPECT_LT(worst_guided, 0.11f) << "the guide lets the open floor's light into the contact";
  EXPECT_GT(worst_plain, 0.3f) << "without the guide the test shows nothing";
  // Linear: the filter of a sum is the sum of the filters.
  CoarseMap sum(grid.size()), a = map, b = other;
  for (size_t c = 0; c < grid.size(); ++c) sum[c] = map[c] + other[c];
  denoise(grid, 2, sum, &near, 0.0625f);
  denoise(grid, 2, a, &near, 0.0625f);
  denoise(grid, 2, b, &near, 0.0625f);
  for (size_t c = 0; c < grid.size(); ++c)
    for (int ch = 0; ch < 3; ++ch) EXPECT_NEAR(sum[c][ch], a[c][ch] + b[c][ch], 1e-5f);
}

}  // namespace
}  // namespace lightpatch::cooker

namespace lightpatch::cooker {
namespace {

// Blocks that touch other geometry are split into coarse texels of one texel each (gather.h,
// build_coarse_grid): the crate's foot and the floor around it, not the open floor. Such texels
// are magnified as themselves and denoised among themselves; the grid is the same on any thread
// count.
TEST(CoarseGrid, BlocksThatTouchOtherGeometryGatherPerTexel) {
  BoxRoom box;
  // Texels of about 11 cm: blocks of 22 cm, whose probes reach 44 cm.
  const test::Prepared f = test::prepare(box.scene, 256);
  const TexelSet& tx = f.texels;
  const CoarseGrid grid = build_coarse_grid(tx, 2, f.tracer.get(), 2, true);
  const CoarseGrid same = build_coarse_grid(tx, 2, f.tracer.get(), 1, true);
  const CoarseGrid blocks = build_coarse_grid(tx, 2, f.tracer.get(), 2, false);
  ASSERT_EQ(grid.fine.size(), grid.size());
  EXPECT_EQ(grid.coarse_of, same.coarse_of);
  EXPECT_EQ(grid.fine, same.fine);
  EXPECT_EQ(std::count(blocks.fine.begin(), blocks.fine.end(), 1), 0);
  EXPECT_GT(grid.size(), blocks.size());
  size_t foot = 0, foot_fine = 0, open = 0, open_fine = 0;
  for (size_t t = 0; t < tx.valid.size(); ++t) {
    if (!tx.valid[t]) continue;
    const glm::vec3 q = tx.position[t], n = tx.normal[t];
    const uint32_t c = grid.coarse_of[t];
    ASSERT_NE(c, kNoTexel);
    if (grid.fine[c]) {
      EXPECT_EQ(grid.member_count(c), 1u);
    }
    // The crate's sides (x, z in -0.4..0.4) within 4 cm of the floor.
    const bool crate_side =
        std::fabs(n.y) < 0.1f && std::fabs(q.x) < 0.45f && std::fabs(q.z) < 0.45f && q.y < 0.04f;
    // A patch of floor on the crate's far side from the stool, half a metre and more from every
    // wall and the crate.
    const bool open_floor =
        n.y > 0.9f && q.y < 0.01f && q.x < -0.95f && q.x > -1.5f && q.z < -0.95f && q.z > -1.5f;
    if (crate_side) foot_fine += grid.fine[c], ++foot;
    if (open_floor) open_fine += grid.fine[c], ++open;
  }
  ASSERT_GT(foot, 8u);
  ASSERT_GT(open, 8u);
  EXPECT_EQ(foot_fine, foot) << "the crate's foot is gathered per texel";
  EXPECT_EQ(open_fine, 0u) << "the open floor keeps its blocks";
  // Magnified, a split texel is its own coarse texel's value; denoised, it reads only other
  // split texels (here all 1, the rest 1000).
  CoarseMap map(grid.size()), ones(grid.size());
  for (size_t c = 0; c < grid.size(); ++c) {
    map[c] = glm::vec3(float(c % 7), float(c % 5), 1.0f);
    ones[c] = glm::vec3(grid.fine[c] ? 1.0f : 1000.0f);
  }
  CoarseMap filtered = ones;
  denoise(grid, 2, filtered);
  FloatImage fine(tx.width, tx.height, 3);
  add_magnified(grid, tx, map, fine);
  for (size_t t = 0; t < tx.valid.size(); ++t) {
    const uint32_t c = tx.valid[t] ? grid.coarse_of[t] : kNoTexel;
    if (c == kNoTexel || !grid.fine[c] || !grid.alive[c]) continue;
    const int x = int(t % size_t(tx.width)), y = int(t / size_t(tx.width));
    EXPECT_EQ(fine.at(x, y, 0), map[c].x);
    EXPECT_EQ(fine.at(x, y, 1), map[c].y);
    EXPECT_NEAR(filtered[c].x, 1.0f, 1e-5f);
  }
}

// A split texel traces fine_ray_count() of the gather's rays; the others stay unused and out of
// its weights, at every bounce level.
TEST(CoarseGrid, SplitTexelsTraceTheirShareOfTheRays) {
  BoxRoom box;
  const test::Prepared f = test::prepare(box.scene, 64);
  GatherOptions go;
  go.rays = 64;
  go.threads = 2;
  go.split_contacts = true;
  const GatherOperator op = build_gather(box.scene, f.layout, f.texels, *f.tracer, 2, go);
  const int fine_rays = fine_ray_count(op.rays);
  ASSERT_LT(fine_rays, op.rays);
  size_t fine = 0;
  for (uint32_t c = 0; c < op.grid.size(); ++c) {
    const uint32_t* hits = op.hit.data() + size_t(c) * size_t(op.rays);
    const int traced = op.grid.fine[c] ? fine_rays : op.rays;
    for (int k = traced; k < op.rays; ++k) ASSERT_EQ(hits[k], kNoTexel) << c;
    if (!op.grid.fine[c] || !op.grid.alive[c]) continue;
    ++fine;
    for (int l = 0; l < GatherOperator::kLevels; ++l)
      EXPECT_EQ(op.weight[l][c], 1.0f / float(std::min(traced, op.level_rays[l]))) << c;
  }
  EXPECT_GT(fine, 0u);
}

}  // namespace
}  // namespace lightpatch::cooker
