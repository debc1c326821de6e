// The reference integrator (path tracing) against closed forms: point, spot and directional light
// over an open floor (no bounce, so no noise), a sphere light facing and straddling a receiver's
// horizon, an emissive square's form factor; its standard error against the spread of
// independent seeds; the same bits on any thread count; the state honoured as bake_state honours
// it; paths that start inside solid geometry dropped. The furnace is in
// quality/reference_quality_test.cpp (seconds).
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <string>

#include "direct_light.h"
#include "indirect_test_scenes.h"
#include "lightpatch/cooker/error.h"
#include "lightpatch/cooker/reference_integrator.h"
#include "test_scenes.h"

namespace lightpatch::cooker {
namespace {

using test::add_quad;
using test::grid_texels;

ReferenceBake trace(const Scene& scene, const TexelSet& texels, int samples, uint64_t seed = 1,
                    int threads = 0, const StateSpec& state = {}) {
  auto tracer = make_embree_tracer(scene);
  Progress progress(true);
  Report report;
  ReferenceOptions o;
  o.samples = samples;
  o.seed = seed;
  o.threads = threads;
  o.texel_patch = false;  // the closed forms here are of points
  return bake_reference(scene, texels, *tracer, state, o, progress, report);
}

// A 10 m x 10 m floor at y = 0 facing +y.
Scene floor_scene() {
  Scene s;
  add_quad(s, {-5, 0, -5}, {-5, 0, 5}, {5, 0, 5}, {5, 0, -5}, "floor");
  return s;
}

// An open floor: every continuation ray leaves the scene, so the estimate is next-event
// estimation alone, exact for punctual lights (standard error 0).
TEST(ReferenceIntegrator, PunctualLightsOverAnOpenFloorAreExact) {
  Scene scene = floor_scene();
  const glm::vec3 lp(0.7f, 2.0f, -0.3f), sp(-0.5f, 3.0f, 0.4f);
  Light point = test::point_light("bulb", lp, 10.0f);
  point.color = glm::vec3(1.0f, 0.5f, 0.25f);
  Light spot =
      test::spot_light("spot", sp, glm::normalize(glm::vec3(0.2f, -1.0f, 0.1f)), 30.0f, 0.3f, 0.6f);
  Light sun = test::directional_light("sun", glm::normalize(glm::vec3(0.3f, -1.0f, 0.5f)), 2.0f);
  scene.lights = {point, spot, sun};
  test::finish(scene);
  const int n = 24;
  const TexelSet texels = grid_texels(n, n, {-4, 0, -4}, {8, 0, 0}, {0, 0, 8}, {0, 1, 0});
  const ReferenceBake r = trace(scene, texels, 4);
  double worst = 0.0;
  for (int y = 0; y < n; ++y) {
    for (int x = 0; x < n; ++x) {
      const glm::vec3 p = texels.position[texels.index(x, y)];
      // Closed forms written out here, independent of direct_light.cpp.
      const glm::vec3 dp = lp - p;
      const float d2 = glm::dot(dp, dp);
      const float e_point = 10.0f * (dp.y / std::sqrt(d2)) / d2;
      const glm::vec3 ds = sp - p;
      const float s2 = glm::dot(ds, ds);
      const float cd = glm::dot(spot.direction, -ds / std::sqrt(s2));
      const float cone =
          std::clamp((cd - std::cos(0.6f)) / (std::cos(0.3f) - std::cos(0.6f)), 0.0f, 1.0f);
      const float e_spot = 30.0f * (ds.y / std::sqrt(s2)) / s2 * cone * cone;
      const float e_sun = 2.0f * -sun.direction.y;
      for (int c = 0; c < 3; ++c) {
        const float want = point.color[c] * e_point + e_spot + e_sun;
        const float got = r.map.at(x, y, c);
        worst = std::max(worst, std::fabs(double(got) - want) / want);
        EXPECT_EQ(r.std_error.at(x, y, c), 0.0f);
      }
    }
  }
  std::printf("reference, point + spot + sun over an open floor: worst relative error %.3g\n",
              worst);
  EXPECT_LT(worst, 1e-5);
  EXPECT_EQ(r.rel_rmse_noise, 0.0);
}

// A sphere light of radius r at height h over the floor: I cos / d^2 wherever the whole sphere is
// above the receiver's horizon; on receivers tilted so that it straddles the horizon, the
// clipped integral (sphere_cosine_integral, checked against quadrature in direct_light_test).
TEST(ReferenceIntegrator, SphereLightMatchesItsClosedForm) {
  Scene scene = floor_scene();
  const glm::vec3 lp(0.0f, 1.0f, 0.0f);
  Light l = test::point_light("globe", lp, 5.0f);
  l.radius = 0.4f;
  scene.lights = {l};
  test::finish(scene);
  scene.materials[0].albedo = glm::vec3(0.0f);  // direct light only
  const int n = 12;
  TexelSet texels = grid_texels(n, n, {-1.5f, 0, -1.5f}, {3, 0, 0}, {0, 0, 3}, {0, 1, 0});
  // The right half of the texels tilted 70 degrees about z, towards +x: the sphere straddles
  // the horizon of those near x = 0.35.
  const float tilt = 70.0f * 3.14159265f / 180.0f;
  for (int y = 0; y < n; ++y) {
    for (int x = n / 2; x < n; ++x) {
      texels.normal[texels.index(x, y)] = glm::vec3(std::sin(tilt), std::cos(tilt), 0.0f);
    }
  }
  const ReferenceBake r = trace(scene, texels, 256);
  double sum_err = 0.0, sum_want = 0.0, worst_z = 0.0;
  int straddling = 0;
  for (int y = 0; y < n; ++y) {
    for (int x = 0; x < n; ++x) {
      const size_t t = texels.index(x, y);
      const glm::vec3 p = texels.position[t], nrm = texels.normal[t];
      const glm::vec3 d = lp - p;
      const float dist = glm::length(d);
      const float cos_theta = glm::dot(nrm, d / dist);
      const float s2 = (l.radius / dist) * (l.radius / dist);
      straddling += cos_theta * cos_theta < s2 ? 1 : 0;
      const float radiance = 5.0f / (3.14159265f * l.radius * l.radius);
      const double want = radiance * sphere_cosine_integral(cos_theta, s2);
      const double got = r.map.at(x, y, 0), se = r.std_error.at(x, y, 0);
      sum_err += got - want;
      sum_want += want;
      if (want > 0.0)
        worst_z = std::max(worst_z, std::fabs(got - want) / std::max(se, 1e-4 * want));
    }
  }
  std::printf(
      "reference, sphere light: signed mean error %.3g %%, worst |error| / se %.2f, %d "
      "texels straddle the horizon, mean rel. se %.3g %%\n",
      100.0 * sum_err / sum_want, worst_z, straddling, 100.0 * r.mean_rel_std_error);
  EXPECT_GT(straddling, 10);
  EXPECT_LT(std::fabs(sum_err / sum_want), 0.005);
  EXPECT_LT(worst_z, 5.0);  // 144 texels: |z| > 5 is a 1e-4 event for honest errors
}

// A candle's flame sphere 1 cm above its wax over a 20 m floor: the scene-scaled ray offset (about
// 0.3 mm) is 3 % of the gap. Paths leave eps above the surface; the light is the sphere as the
// surface point sees it, or the sphere looks wider and the rim only continuation rays find is
// counted in full (+1.3 % here before the fix, 0.9–1.3 % on the inn's candle wax).
TEST(ReferenceIntegrator, SphereLightJustAboveAReceiverAgainstItsClosedForm) {
  Scene scene;
  add_quad(scene, {-10, 0, -10}, {-10, 0, 10}, {10, 0, 10}, {10, 0, -10}, "floor");
  const glm::vec3 lp(0.0f, 0.025f, 0.0f);
  Light l = test::point_light("candle", lp, 1.5f);
  l.radius = 0.015f;
  scene.lights = {l};
  test::finish(scene);
  scene.materials[0].albedo = glm::vec3(0.0f);  // direct light only
  const int n = 4;
  const TexelSet texels =
      grid_texels(n, n, {-0.02f, 0, -0.02f}, {0.04f, 0, 0}, {0, 0, 0.04f}, {0, 1, 0});
  const ReferenceBake r = trace(scene, texels, 4096);
  double sum_err = 0.0, sum_want = 0.0;
  for (int y = 0; y < n; ++y) {
    for (int x = 0; x < n; ++x) {
      const glm::vec3 d = lp - texels.position[texels.index(x, y)];
      const float dist = glm::length(d);
      const float s2 = (l.radius / dist) * (l.radius / dist);
      const double want =
          1.5f / (3.14159265f * l.radius * l.radius) * sphere_cosine_integral(d.y / dist, s2);
      sum_err += r.map.at(x, y, 0) - want;
      sum_want += want;
    }
  }
  std::printf("reference, sphere light 1 cm above the floor: signed mean error %.3g %%\n",
              100.0 * sum_err / sum_want);
  EXPECT_LT(std::fabs(sum_err / sum_want), 0.004);
}

// Receivers inside a light's sphere (a flame's surface around its candle) see it in every
// direction: E = pi L = I / r^2 whatever their normal, and the estimate is exact.
TEST(ReferenceIntegrator, ReceiversInsideALightSphereGetPiL) {
  Scene scene = floor_scene();
  Light l = test::point_light("candle", {0.0f, 0.5f, 0.0f}, 2.0f);
  l.radius = 0.02f;
  scene.lights = {l};
  test::finish(scene);
  scene.materials[0].albedo = glm::vec3(0.0f);
  // Four receivers inside the sphere (0.5 m above the floor), one tilted, one upside down.
  TexelSet texels =
      grid_texels(2, 2, {-0.01f, 0.5f, -0.01f}, {0.02f, 0, 0}, {0, 0, 0.02f}, {0, 1, 0});
  texels.normal[2] = glm::vec3(0, -1, 0);
  texels.normal[3] = glm::normalize(glm::vec3(1, 1, 0));
  const ReferenceBake r = trace(scene, texels, 16);
  const float want = 2.0f / (l.radius * l.radius);
  for (size_t t = 0; t < 4; ++t) {
    EXPECT_NEAR(r.map.data[3 * t], want, 1e-4f * want) << "texel " << t;
    EXPECT_LT(r.std_error.data[3 * t], 1e-4f * want) << "texel " << t;
  }
}

// A 2 x 2 emitter 1 m above the texel, facing down (emitter black, so nothing bounces back).
TEST(ReferenceIntegrator, EmissiveSquareMatchesFormFactor) {
  const glm::vec3 radiance(1.0f, 2.0f, 0.5f);
  const Scene scene = test::emissive_panel(radiance, 0.0f);
  const TexelSet texels =
      grid_texels(1, 1, {-1e-3f, 0, -1e-3f}, {2e-3f, 0, 0}, {0, 0, 2e-3f}, {0, 1, 0});
  const ReferenceBake r = trace(scene, texels, 8192);
  for (int c = 0; c < 3; ++c) {
    const double want = test::emissive_panel_irradiance(radiance[c]);
    const double got = r.map.at(0, 0, c), se = r.std_error.at(0, 0, c);
    std::printf("reference, emissive square channel %d: %.5f vs %.5f (%+.3f %%, se %.3f %%)\n", c,
                got, want, 100.0 * (got - want) / want, 100.0 * se / want);
    EXPECT_NEAR(got, want, 0.01 * want);
    EXPECT_LT(std::fabs(got - want), 4.0 * se + 1e-4 * want);
    EXPECT_LT(se, 0.005 * want);
  }
}

// The stated standard error is the spread the estimate really has: the variance of independent
// seeds' maps, per texel, averaged, matches the mean squared standard error.
TEST(ReferenceIntegrator, StandardErrorMatchesTheSpreadOfSeeds) {
  Scene s = test::furnace_box(0.6f);
  s.lights = {test::furnace_lamp()};
  const TexelSet texels = test::box_texels({-1, -1, -1}, {1, 1, 1}, 5);
  constexpr int kSeeds = 8;
  const size_t count = texels.position.size();
  std::vector<double> sum(count, 0.0), sum_sq(count, 0.0), se2(count, 0.0);
  for (int k = 0; k < kSeeds; ++k) {
    const ReferenceBake r = trace(s, texels, 8, 100 + uint64_t(k));
    for (size_t t = 0; t < count; ++t) {
      const double v = r.map.data[3 * t], e = r.std_error.data[3 * t];
      sum[t] += v;
      sum_sq[t] += v * v;
      se2[t] += e * e / kSeeds;
    }
  }
  double spread = 0.0, stated = 0.0;
  for (size_t t = 0; t < count; ++t) {
    const double mean = sum[t] / kSeeds;
    spread += (sum_sq[t] - kSeeds * mean * mean) / (kSeeds - 1);
    stated += se2[t];
  }
  const double ratio = std::sqrt(spread / stated);
  std::printf("reference: spread of %d seeds / stated standard error = %.3f over %zu texels\n",
              kSeeds, ratio, count);
  EXPECT_GT(ratio, 0.85);
  EXPECT_LT(ratio, 1.15);
}

// A noise target stops the passes at the first power of two that meets it; the result is the
// same as asking for that many samples.
TEST(ReferenceIntegrator, NoiseTargetStopsAtThePowerOfTwoThatMeetsIt) {
  Scene s = test::furnace_box(0.5f);
  s.lights = {test::furnace_lamp()};
  const TexelSet texels = test::box_texels({-1, -1, -1}, {1, 1, 1}, 4);
  auto tracer = make_embree_tracer(s);
  Progress progress(true);
  Report report;
  ReferenceOptions o;
  o.samples = 4096;
  o.target_noise = 0.05;
  const ReferenceBake early = bake_reference(s, texels, *tracer, {}, o, progress, report);
  EXPECT_GE(early.samples, 64);
  EXPECT_LT(early.samples, 4096);
  EXPECT_EQ(early.samples & (early.samples - 1), 0);
  EXPECT_LE(early.rel_rmse_noise, 0.05);
  std::printf("noise target 5 %%: stopped at %d samples, noise %.3f %%\n", early.samples,
              100.0 * early.rel_rmse_noise);
  ReferenceOptions fixed;
  fixed.samples = early.samples;
  const ReferenceBake same = bake_reference(s, texels, *tracer, {}, fixed, progress, report);
  EXPECT_TRUE(same.map.data == early.map.data);
  if (early.samples > 64) {
    fixed.samples = early.samples / 2;
    EXPECT_GT(bake_reference(s, texels, *tracer, {}, fixed, progress, report).rel_rmse_noise, 0.05);
  }
}

TEST(ReferenceIntegrator, SameBitsOnAnyThreadCountDifferentSeedsDiffer) {
  Scene s = test::furnace_box(0.7f);
  s.lights = {test::furnace_lamp()};
  Light soft = test::point_light("globe", {-0.4f, -0.3f, 0.5f}, 2.0f);
  soft.radius = 0.2f;
  s.lights.push_back(soft);
  const TexelSet texels = test::box_texels({-1, -1, -1}, {1, 1, 1}, 4);
  const ReferenceBake one = trace(s, texels, 20, 3, 1);
  const ReferenceBake two = trace(s, texels, 20, 3, 2);
  const ReferenceBake other = trace(s, texels, 20, 4, 2);
  EXPECT_TRUE(one.map.data == two.map.data);
  EXPECT_TRUE(one.std_error.data == two.std_error.data);
  EXPECT_FALSE(one.map.data == other.map.data);
  EXPECT_GT(one.rays, 0u);
}

// Lights off, recoloured and dimmed, objects hidden: the state resolved as bake_state resolves
// it, with the same errors.
TEST(ReferenceIntegrator, HonoursTheSceneState) {
  Scene scene = floor_scene();
  test::add_object_box(scene, {-0.5f, 1.0f, -0.5f}, {0.5f, 1.2f, 0.5f}, "lid");
  Light lamp = test::point_light("lamp", {0.0f, 3.0f, 0.0f}, 9.0f, true);
  scene.lights = {lamp, test::point_light("fixed", {3.0f, 2.0f, 0.0f}, 4.0f)};
  test::finish(scene);
  scene.materials[0].albedo = glm::vec3(0.0f);  // direct light only: exact and noise-free
  const TexelSet texels =
      grid_texels(1, 1, {-0.01f, 0, -0.01f}, {0.02f, 0, 0}, {0, 0, 0.02f}, {0, 1, 0});
  const float fixed = 4.0f * 2.0f / std::pow(13.0f, 1.5f);  // (3,2,0) seen from the origin
  const ReferenceBake authored = trace(scene, texels, 2);
  EXPECT_NEAR(authored.map.at(0, 0, 0), fixed, 1e-4f * fixed);  // the lid shadows the lamp
  StateSpec state;
  state.objects["lid"] = false;
  state.lights["lamp"].has_color = true;
  state.lights["lamp"].color[1] = 0.5f;
  state.lights["lamp"].has_intensity = true;
  state.lights["lamp"].intensity = 18.0f;
  const ReferenceBake changed = trace(scene, texels, 2, 1, 0, state);
  EXPECT_NEAR(changed.map.at(0, 0, 0), fixed + 18.0f / 9.0f, 1e-3f);
  EXPECT_NEAR(changed.map.at(0, 0, 1), fixed + 0.5f * 18.0f / 9.0f, 1e-3f);
  state.lights["lamp"].has_on = true;
  state.lights["lamp"].on = false;
  const ReferenceBake off = trace(scene, texels, 2, 1, 0, state);
  EXPECT_NEAR(off.map.at(0, 0, 0), fixed, 1e-4f * fixed);
  StateSpec bad;
  bad.objects["nothing"] = false;
  try {
    trace(scene, texels, 2, 1, 0, bad);
    FAIL() << "an unknown object was accepted";
  } catch (const CookError& e) {
    EXPECT_NE(std::string(e.what()).find("object 'nothing'"), std::string::npos) << e.what();
  }
  StateSpec fixed_change;
  fixed_change.lights["fixed"].has_on = true;
  fixed_change.lights["fixed"].on = false;
  EXPECT_THROW(trace(scene, texels, 2, 1, 0, fixed_change), CookError);
}

// A texel's light is that of the visible part of its patch: a path whose first ray meets the back
// of a static surface started inside solid geometry and is not a sample. A 9 x 7 mm post through
// a floor, a sun straight above, no bounce (albedo 0: every kept path brings exactly the sun),
// texels 10 cm apart: the post stands in one cell of the middle texel's patch, clear of the lines
// of sight that close cells (texel_footprint.h), so that cell stays open and 0.6 % of the patch's
// points are inside the post. Counted as black they took 0.6 % of its light, with a standard error;
// now it has the sun's 2 lux exactly, and the post's share of the paths is reported. As a
// semi-dynamic object the same post keeps its paths (an object present is darkness, not a solid
// the texel lies in) until it is hidden.
TEST(ReferenceIntegrator, PathsThatStartInsideSolidGeometryAreNotSamples) {
  const glm::vec3 lo(0.040f, -0.5f, 0.003f), hi(0.049f, 0.5f, 0.010f);
  const TexelSet texels =
      grid_texels(3, 3, {-0.15f, 0.0f, -0.15f}, {0.3f, 0.0f, 0.0f}, {0, 0, 0.3f}, {0, 1, 0});
  for (const bool object : {false, true}) {
    Scene scene = floor_scene();
    if (object) {
      test::add_object_box(scene, lo, hi, "post");
    } else {
      test::add_box(scene, lo, hi, "post");
    }
    scene.lights = {test::directional_light("sun", {0.0f, -1.0f, 0.0f}, 2.0f)};
    test::finish(scene);
    scene.materials[0].albedo = glm::vec3(0.0f);
    auto tracer = make_embree_tracer(scene);
    Progress progress(true);
    Report report;
    ReferenceOptions o;
    o.samples = 4096;
    const ReferenceBake r = bake_reference(scene, texels, *tracer, {}, o, progress, report);
    const float middle = r.map.at(1, 1, 0);
    std::printf("reference, a texel with a post in its patch (%s): %.5f, paths inside %.5f\n",
                object ? "object" : "static", middle, r.inside_path_fraction);
    EXPECT_EQ(r.inside_texels, 0u);
    if (!object) {
      EXPECT_NEAR(middle, 2.0f, 1e-5f);
      EXPECT_EQ(r.std_error.at(1, 1, 0), 0.0f);
      // 0.63 % of the middle texel's paths, a ninth of that of all.
      EXPECT_NEAR(r.inside_path_fraction * 9.0, 0.0063, 0.0015);
      continue;
    }
    EXPECT_LT(middle, 1.997f);
    EXPECT_GT(middle, 1.98f);
    EXPECT_GT(r.std_error.at(1, 1, 0), 0.0f);
    EXPECT_EQ(r.inside_path_fraction, 0.0);
    StateSpec hidden;
    hidden.objects["post"] = false;
    const ReferenceBake h = bake_reference(scene, texels, *tracer, hidden, o, progress, report);
    EXPECT_NEAR(h.map.at(1, 1, 0), 2.0f, 1e-5f);
  }
}

}  // namespace
}  // namespace lightpatch::cooker
