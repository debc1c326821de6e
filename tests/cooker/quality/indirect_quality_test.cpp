// Indirect light at production quality (seconds, not milliseconds: labelled "cooker;indirect",
// outside the "unit" label the sanitizer run selects). The closed-box energy balance and
// recomposition against bake-state for random states of a room with bounce light.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <random>

#include "indirect_test_scenes.h"
#include "lightpatch/cooker/bake.h"
#include "lightpatch/cooker/tracer.h"

namespace lightpatch::cooker {
namespace {

constexpr double kPi = 3.14159265358979;

double furnace_flux(float rho, int n) {
  Scene s = test::furnace_box(rho);
  s.lights = {test::furnace_lamp()};
  TexelSet texels = test::box_texels({-1, -1, -1}, {1, 1, 1}, n);
  texels.albedo.assign(texels.albedo.size(), glm::vec3(rho));  // gathering reads texel albedo
  auto tracer = make_embree_tracer(s);
  Progress progress(true);
  Report report;
  BakeOptions o;
  o.quality = Quality::kProduction;
  const BakedMaps maps = bake_maps(s, test::bare_layout(texels.width, texels.height), texels,
                                   *tracer, o, progress, report);
  double flux = 0.0;
  for (size_t t = 0; t < texels.position.size(); ++t) {
    const int x = int(t % size_t(texels.width)), y = int(t / size_t(texels.width));
    const float e = maps.base.at(x, y, 0);
    EXPECT_TRUE(std::isfinite(e));
    flux += double(e) * test::box_texel_area({-1, -1, -1}, {1, 1, 1}, n, t);
  }
  return flux;
}

// Sum of E * area over all surfaces = 4 pi I / (1 - rho) for a point light of I cd inside.
TEST(IndirectQuality, FurnaceAtProduction) {
  struct Case {
    float rho;
    double tolerance;
  };
  for (const Case c : {Case{0.5f, 0.01}, Case{0.9f, 0.01}}) {
    const double flux = furnace_flux(c.rho, 24);
    const double expected = 4.0 * kPi / (1.0 - c.rho);
    std::printf("furnace production rho %.2f: flux %.4f, expected %.4f, error %+.2f%%\n", c.rho,
                flux, expected, 100.0 * (flux / expected - 1.0));
    EXPECT_NEAR(flux / expected, 1.0, c.tolerance) << "rho " << c.rho;
  }
}

// A closed room, two semi-dynamic lights (a lamp and a spot on a red wall), three objects apart
// from each other; no static light (B would not show objects, which static lights ignore).
struct Room {
  Scene scene;
  TexelSet texels;
  Room() {
    Material wall;
    wall.albedo = glm::vec3(0.75f);
    Material red;
    red.albedo = glm::vec3(0.85f, 0.15f, 0.1f);
    Material green;
    green.albedo = glm::vec3(0.2f, 0.7f, 0.3f);
    scene.materials = {wall, red, green};
    test::add_closed_room(scene, {-3, 0, -3}, {3, 2.5f, 3}, 0.1f, "room");
    test::add_box(scene, {-3.0f, 0.0f, -3.0f}, {-2.9f, 2.5f, 3.0f}, "red_wall", -1, 1);
    const char* names[3] = {"crate", "chest", "barrel"};
    const glm::vec3 lo[3] = {{-1.8f, 0.0f, -1.6f}, {1.2f, 0.0f, -1.9f}, {0.4f, 0.0f, 1.6f}};
    const glm::vec3 hi[3] = {{-1.1f, 0.7f, -0.9f}, {2.0f, 0.5f, -1.4f}, {0.9f, 0.9f, 2.1f}};
    for (int i = 0; i < 3; ++i) {
      Object o;
      o.name = names[i];
      scene.objects.push_back(o);
      test::add_box(scene, lo[i], hi[i], names[i], i, i == 1 ? 2 : 0);
    }
    scene.lights = {test::point_light("lamp", {0.2f, 2.2f, 0.1f}, 6.0f, true),
                    test::spot_light("spot", {1.5f, 2.0f, 0.5f}, {-1.0f, -0.4f, -0.2f}, 25.0f, 0.3f,
                                     0.6f, true)};
    test::finish(scene);
    texels = test::box_texels({-2.9f, 0, -3}, {3, 2.5f, 3}, 20);
  }
};

TEST(IndirectQuality, RecomposeMatchesBakeStateForRandomStates) {
  Room f;
  auto tracer = make_embree_tracer(f.scene);
  Progress progress(true);
  Report report;
  BakeOptions o;
  o.quality = Quality::kProduction;
  const Layout layout = test::bare_layout(f.texels.width, f.texels.height);
  const BakedMaps maps = bake_maps(f.scene, layout, f.texels, *tracer, o, progress, report);
  ASSERT_EQ(maps.contribution.size(), 2u);
  std::mt19937 rng(11);
  std::uniform_real_distribution<float> unit(0.0f, 1.0f);
  double worst = 0.0;
  for (int trial = 0; trial < 6; ++trial) {
    StateSpec state;
    glm::vec3 radiant[2];
    for (int k = 0; k < 2; ++k) {
      const Light& l = f.scene.lights[size_t(k)];
      LightOverride lo;
      lo.has_on = true;
      lo.on = trial == 0 || unit(rng) < 0.8f;
      lo.has_color = true;
      for (float& c : lo.color) c = 0.2f + unit(rng);
      lo.has_intensity = true;
      lo.intensity = l.intensity * (0.3f + 2.0f * unit(rng));
      state.lights[l.name] = lo;
      radiant[k] =
          lo.on ? glm::vec3(lo.color[0], lo.color[1], lo.color[2]) * lo.intensity : glm::vec3(0.0f);
    }
    std::vector<bool> visible(f.scene.objects.size());
    for (size_t ob = 0; ob < visible.size(); ++ob) {
      visible[ob] = trial == 0 || unit(rng) < 0.6f;
      state.objects[f.scene.objects[ob].name] = visible[ob];
    }
    const FloatImage direct =
        bake_state(f.scene, layout, f.texels, *tracer, state, o, progress, report);
    double err2 = 0.0, ref2 = 0.0;
    for (int y = 0; y < f.texels.height; ++y) {
      for (int x = 0; x < f.texels.width; ++x) {
        for (int c = 0; c < 3; ++c) {
          double v = maps.base.at(x, y, c);
          for (size_t k = 0; k < 2; ++k) {
            const FloatImage& cm = maps.contribution[k];
            double t = cm.at(x, y, cm.channels == 3 ? c : 0);
            for (const ShadowMap& s : maps.shadows) {
              if (s.light == int(k) && visible[size_t(s.object)])
                t -= s.map.at(x, y, s.map.channels == 3 ? c : 0);
            }
            for (const PairCorrectionMap& p : maps.pair_corrections) {
              if (p.light == int(k) && visible[size_t(p.object_a)] && visible[size_t(p.object_b)])
                t += p.map.at(x, y, p.map.channels == 3 ? c : 0);
            }
            v += radiant[k][c] * t;
          }
          const double d = direct.at(x, y, c);
          err2 += (v - d) * (v - d);
          ref2 += d * d;
        }
      }
    }
    const double rel = ref2 > 0.0 ? std::sqrt(err2 / ref2) : 0.0;
    std::printf("state %d: recompose vs bake-state relative RMSE %.4f%%\n", trial, 100.0 * rel);
    worst = std::max(worst, rel);
    // Objects present together change each other's bounce light, which no pair correction holds
    // where their direct shadows do not overlap (here none do): the six states measure 0.000 to
    // 2.02 %. They measured up to 1.55 % while a gather ray that met an object's bottom where it
    // rests on the floor lost the floor there (the tracer stepped past both): the floor under an
    // absent crate now lends its light, one more way for two objects to interact.
    EXPECT_LE(rel, 0.025) << "state " << trial;
  }
  std::printf("worst relative RMSE over the states: %.4f%%\n", 100.0 * worst);
}

}  // namespace
}  // namespace lightpatch::cooker
