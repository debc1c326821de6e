// Analytic checks of direct light (KHR_lights_punctual) baked through the Embree tracer.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <vector>

#include "direct_light.h"
#include "indirect_test_scenes.h"
#include "lightpatch/cooker/bake.h"
#include "lightpatch/cooker/tracer.h"
#include "test_scenes.h"

namespace lightpatch::cooker {
namespace {

using test::add_quad;
using test::grid_texels;

constexpr int kN = 32;

// A 10 m x 10 m floor at y = 0 facing +y, sampled kN x kN.
Scene floor_scene() {
  Scene s;
  add_quad(s, {-5, 0, -5}, {-5, 0, 5}, {5, 0, 5}, {5, 0, -5}, "floor");
  return s;
}
TexelSet floor_texels(int n = kN, float half = 5.0f) {
  return grid_texels(n, n, {-half, 0, -half}, {2 * half, 0, 0}, {0, 0, 2 * half}, {0, 1, 0});
}

BakedMaps bake(const Scene& scene, const TexelSet& texels, int area_samples = 0) {
  auto tracer = make_embree_tracer(scene);
  Progress progress(true);
  Report report;
  BakeOptions o;
  o.area_samples = area_samples;
  o.indirect = false;   // the analytic checks here are of direct light
  o.texel_samples = 1;  // ... at the texels' sample points
  return bake_maps(scene, test::bare_layout(texels.width, texels.height), texels, *tracer, o,
                   progress, report);
}

float rel_err(float got, float want) {
  return std::fabs(got - want) / std::max(std::fabs(want), 1e-30f);
}

TEST(DirectLight, PointLightOverPlaneIsInverseSquareCosine) {
  Scene scene = floor_scene();
  const glm::vec3 lp(0.7f, 2.0f, -0.3f);
  const float intensity = 10.0f;
  Light l = test::point_light("bulb", lp, intensity);
  l.color = glm::vec3(1.0f, 0.5f, 0.25f);
  scene.lights.push_back(l);
  test::finish(scene);
  const TexelSet texels = floor_texels();
  const BakedMaps maps = bake(scene, texels);
  float worst = 0.0f;
  for (int y = 0; y < kN; ++y) {
    for (int x = 0; x < kN; ++x) {
      const glm::vec3 p = texels.position[texels.index(x, y)];
      const glm::vec3 d = lp - p;
      const float dist = glm::length(d);
      const float e = intensity * (d.y / dist) / (dist * dist);
      for (int c = 0; c < 3; ++c)
        worst = std::max(worst, rel_err(maps.base.at(x, y, c), e * l.color[c]));
    }
  }
  EXPECT_LT(worst, 0.01f);
  RecordProperty("max_relative_error", std::to_string(worst));
  std::printf("point light: max relative error %.3g\n", worst);
}

TEST(DirectLight, SemiDynamicPointLightContributionIsUnitIntensity) {
  Scene scene = floor_scene();
  const glm::vec3 lp(0.0f, 1.5f, 0.0f);
  scene.lights.push_back(test::point_light("lamp", lp, 7.0f, true));
  test::finish(scene);
  const TexelSet texels = floor_texels();
  const BakedMaps maps = bake(scene, texels);
  ASSERT_EQ(maps.contribution.size(), 1u);
  ASSERT_EQ(maps.contribution[0].channels, 1);
  float worst = 0.0f;
  for (int y = 0; y < kN; ++y) {
    for (int x = 0; x < kN; ++x) {
      const glm::vec3 d = lp - texels.position[texels.index(x, y)];
      const float dist = glm::length(d);
      worst =
          std::max(worst, rel_err(maps.contribution[0].at(x, y, 0), (d.y / dist) / (dist * dist)));
      EXPECT_EQ(maps.base.at(x, y, 0), 0.0f);
    }
  }
  EXPECT_LT(worst, 0.01f);
}

TEST(DirectLight, SpotLightInsideInnerAndOutsideOuterCone) {
  Scene scene = floor_scene();
  const glm::vec3 lp(0.0f, 3.0f, 0.0f);
  const float inner = 0.3f, outer = 0.5f, intensity = 20.0f;
  scene.lights.push_back(test::spot_light("spot", lp, {0, -1, 0}, intensity, inner, outer));
  test::finish(scene);
  const TexelSet texels = floor_texels(48, 3.0f);
  const BakedMaps maps = bake(scene, texels);
  int inside = 0, outside = 0, between = 0;
  float worst = 0.0f;
  const float scale = 1.0f / (std::cos(inner) - std::cos(outer));
  for (int y = 0; y < texels.height; ++y) {
    for (int x = 0; x < texels.width; ++x) {
      const glm::vec3 p = texels.position[texels.index(x, y)];
      const glm::vec3 d = lp - p;
      const float dist = glm::length(d);
      const float angle = std::acos(d.y / dist);
      const float e = intensity * (d.y / dist) / (dist * dist);
      const float got = maps.base.at(x, y, 0);
      if (angle < inner) {
        worst = std::max(worst, rel_err(got, e));
        ++inside;
      } else if (angle > outer) {
        EXPECT_EQ(got, 0.0f) << "outside the outer cone at " << x << "," << y;
        ++outside;
      } else {
        const float a = std::clamp(std::cos(angle) * scale - std::cos(outer) * scale, 0.0f, 1.0f);
        if (a * a * e > 1e-3f * intensity) worst = std::max(worst, rel_err(got, a * a * e));
        ++between;
      }
    }
  }
  EXPECT_GT(inside, 50);
  EXPECT_GT(outside, 50);
  EXPECT_GT(between, 20);
  EXPECT_LT(worst, 0.01f);
  std::printf("spot light: max relative error %.3g\n", worst);
}

TEST(DirectLight, DirectionalLightIsSunTimesCosine) {
  Scene scene = floor_scene();
  const glm::vec3 dir = glm::normalize(glm::vec3(0.3f, -1.0f, 0.2f));
  scene.lights.push_back(test::directional_light("sun", dir, 5.0f));
  test::finish(scene);
  const TexelSet texels = floor_texels();
  const BakedMaps maps = bake(scene, texels);
  const float want = 5.0f * -dir.y;
  float worst = 0.0f;
  for (float v : maps.base.data) worst = std::max(worst, rel_err(v, want));
  EXPECT_LT(worst, 0.01f);
}

TEST(DirectLight, BoxCastsHardShadowOfKnownOutline) {
  Scene scene = floor_scene();
  // Light at height 4 over a box whose top face (height 1.5, half-size 0.5) projects to a square
  // of half-size 0.5 * 4 / 2.5 = 0.8 on the floor.
  test::add_box(scene, {-0.5f, 1.0f, -0.5f}, {0.5f, 1.5f, 0.5f}, "box");
  const glm::vec3 lp(0.0f, 4.0f, 0.0f);
  scene.lights.push_back(test::point_light("bulb", lp, 16.0f));
  test::finish(scene);
  const int n = 80;
  const TexelSet texels = floor_texels(n, 2.0f);
  const BakedMaps maps = bake(scene, texels);
  int dark = 0, lit = 0;
  float worst = 0.0f;
  for (int y = 0; y < n; ++y) {
    for (int x = 0; x < n; ++x) {
      const glm::vec3 p = texels.position[texels.index(x, y)];
      const float r = std::max(std::fabs(p.x), std::fabs(p.z));
      const glm::vec3 d = lp - p;
      const float dist = glm::length(d);
      const float e = 16.0f * (d.y / dist) / (dist * dist);
      const float got = maps.base.at(x, y, 0);
      if (r < 0.8f - 0.03f) {
        EXPECT_EQ(got, 0.0f) << "inside the shadow at " << p.x << "," << p.z;
        ++dark;
      } else if (r > 0.8f + 0.03f) {
        worst = std::max(worst, rel_err(got, e));
        ++lit;
      }
    }
  }
  EXPECT_GT(dark, 500);
  EXPECT_GT(lit, 3000);
  EXPECT_LT(worst, 0.01f);
}

TEST(DirectLight, SphereLightGivesPenumbraAndMatchesPointFarAway) {
  Scene scene = floor_scene();
  test::add_box(scene, {-0.5f, 1.0f, -0.5f}, {0.5f, 1.5f, 0.5f}, "box");
  const glm::vec3 lp(0.0f, 4.0f, 0.0f);
  Light l = test::point_light("bulb", lp, 16.0f);
  l.radius = 0.3f;
  scene.lights.push_back(l);
  test::finish(scene);
  const int n = 64;
  const TexelSet texels = floor_texels(n, 2.0f);
  const BakedMaps maps = bake(scene, texels, 64);
  int penumbra = 0;
  float worst_far = 0.0f;
  for (int y = 0; y < n; ++y) {
    for (int x = 0; x < n; ++x) {
      const glm::vec3 p = texels.position[texels.index(x, y)];
      const glm::vec3 d = lp - p;
      const float dist = glm::length(d);
      const float e = 16.0f * (d.y / dist) / (dist * dist);
      const float got = maps.base.at(x, y, 0);
      ASSERT_TRUE(std::isfinite(got));
      if (got > 0.05f * e && got < 0.95f * e) ++penumbra;
      if (std::max(std::fabs(p.x), std::fabs(p.z)) > 1.4f)
        worst_far = std::max(worst_far, rel_err(got, e));
    }
  }
  EXPECT_GT(penumbra, 40);
  EXPECT_LT(worst_far, 0.02f);  // a disc of radius r at distance d differs from a point by ~(r/d)^2
}

TEST(DirectLight, EmissiveSquareOverPointMatchesFormFactor) {
  const Scene scene = test::emissive_panel(glm::vec3(1.0f), 0.8f);
  const TexelSet texels =
      grid_texels(1, 1, {-1e-3f, 0, -1e-3f}, {2e-3f, 0, 0}, {0, 0, 2e-3f}, {0, 1, 0});
  const BakedMaps maps = bake(scene, texels, 16384);
  const double want = test::emissive_panel_irradiance(1.0);
  const double got = maps.base.at(0, 0, 1);
  std::printf("emissive: got %.5f want %.5f (error %.3g)\n", got, want,
              std::fabs(got - want) / want);
  EXPECT_NEAR(got, want, 0.01 * want);
}

TEST(DirectLight, LightTouchingSurfaceStaysFinite) {
  Scene scene = floor_scene();
  Light l = test::point_light("touch", {0.0f, 0.0f, 0.0f}, 1e6f);
  scene.lights.push_back(l);
  l.name = "touch_soft";
  l.radius = 0.2f;
  l.position = {1.0f, 0.05f, 1.0f};
  scene.lights.push_back(l);
  test::finish(scene);
  const TexelSet texels = floor_texels(kN, 1.5f);
  const BakedMaps maps = bake(scene, texels);
  for (float v : maps.base.data) {
    ASSERT_TRUE(std::isfinite(v));
    ASSERT_GE(v, 0.0f);
  }
}

TEST(DirectLight, RangeWindowAndSpotFalloffFollowTheSpec) {
  EXPECT_FLOAT_EQ(range_window(0.0f, 100.0f), 1.0f);
  EXPECT_FLOAT_EQ(range_window(2.0f, 1.0f), 1.0f - 1.0f / 16.0f);
  EXPECT_FLOAT_EQ(range_window(2.0f, 3.0f), 0.0f);
  Light spot = test::spot_light("s", {0, 0, 0}, {0, 0, -1}, 1.0f, 0.2f, 0.4f);
  EXPECT_FLOAT_EQ(spot_attenuation(spot, {0, 0, -1}), 1.0f);
  const float a = 0.3f;
  const float scale = 1.0f / (std::cos(0.2f) - std::cos(0.4f));
  const float want = std::pow((std::cos(a) - std::cos(0.4f)) * scale, 2.0f);
  EXPECT_NEAR(spot_attenuation(spot, {std::sin(a), 0, -std::cos(a)}), want, 1e-5f);
  EXPECT_FLOAT_EQ(spot_attenuation(spot, {std::sin(0.5f), 0, -std::cos(0.5f)}), 0.0f);
  Light p = test::point_light("p", {0, 2, 0}, 1.0f);
  p.range = 3.0f;
  const float e = punctual_irradiance(p, p.position, {0, 0, 0}, {0, 1, 0}, 0.0f);
  EXPECT_NEAR(e, 0.25f * (1.0f - std::pow(2.0f / 3.0f, 4.0f)), 1e-6f);
  EXPECT_EQ(punctual_irradiance(p, p.position, {0, 0, 0}, {0, -1, 0}, 0.0f), 0.0f);
  EXPECT_FLOAT_EQ(light_reach(p, 1e-6f), 3.0f);
}

// The horizon-clipped cosine integral of a cone, against midpoint quadrature over the cone.
TEST(DirectLight, SphereCosineIntegralMatchesQuadrature) {
  for (float sigma : {0.05f, 0.4f, 1.0f, 1.5f}) {
    for (float theta : {0.0f, 0.7f, 1.3f, 1.57f, 1.9f, 2.6f}) {
      const glm::vec3 n(0, 0, 1);
      const glm::vec3 axis(std::sin(theta), 0, std::cos(theta));
      const glm::vec3 t(std::cos(theta), 0, -std::sin(theta)), b(0, 1, 0);
      constexpr int kRings = 300, kSteps = 300;
      const double cos_max = std::cos(double(sigma));
      double sum = 0.0;
      for (int i = 0; i < kRings; ++i) {
        const double c = 1.0 - (i + 0.5) / kRings * (1.0 - cos_max);
        const double sn = std::sqrt(std::max(0.0, 1.0 - c * c));
        for (int j = 0; j < kSteps; ++j) {
          const double phi = 2.0 * M_PI * (j + 0.5) / kSteps;
          const glm::vec3 w =
              axis * float(c) + t * float(sn * std::cos(phi)) + b * float(sn * std::sin(phi));
          sum += std::max(0.0f, glm::dot(n, w));
        }
      }
      const double want = sum * 2.0 * M_PI * (1.0 - cos_max) / (double(kRings) * kSteps);
      const double s = std::sin(double(sigma));
      const double got = sphere_cosine_integral(std::cos(theta), float(s * s));
      EXPECT_NEAR(got, want, 1e-4 + 2e-4 * want) << "sigma " << sigma << " theta " << theta;
    }
  }
}

// The cook's sampler of a sphere light (its visible cone, stratified) against the closed form:
// I cos / d^2 where the sphere is wholly above the horizon (facing and tilted receivers), the
// clipped integral where it straddles it, pi L = I / r^2 where it touches the receiver; one
// sample gives the closed form itself.
TEST(DirectLight, SphereLightSamplerMatchesClosedForms) {
  Light l = test::point_light("globe", {0.0f, 1.0f, 0.0f}, 7.0f);
  l.radius = 0.3f;
  // sample_punctual is for intensity 1 (callers scale by colour * intensity).
  const float radiance = 1.0f / (3.14159265f * l.radius * l.radius);
  struct Case {
    glm::vec3 p, n;
  };
  const float tilt = 1.3f;  // radians; the sphere (half angle ~0.3 at d = 1) straddles it
  const Case cases[] = {
      {{0, 0, 0}, {0, 1, 0}},                                     // facing, d = 1
      {{0.4f, 0, 0}, glm::normalize(glm::vec3(-0.3f, 1, 0.2f))},  // tilted, above the horizon
      {{0, 0, 0}, {-std::sin(tilt), std::cos(tilt), 0}},          // straddling the horizon
      {{0, 0.7f, 0}, {0, 1, 0}},                                  // touching: d = r
      {{0.1f, 0.75f, 0}, glm::normalize(glm::vec3(1, 1, 0))},     // inside the sphere
  };
  for (const Case& c : cases) {
    const glm::vec3 to = l.position - c.p;
    const float d = glm::length(to);
    const float s2 = d > l.radius ? (l.radius / d) * (l.radius / d) : 1.0f;
    const double want = d > l.radius ? radiance * sphere_cosine_integral(glm::dot(c.n, to / d), s2)
                                     : radiance * M_PI;  // inside: the sphere fills the hemisphere
    if (d > l.radius && glm::dot(c.n, to / d) * glm::dot(c.n, to / d) >= s2) {
      EXPECT_NEAR(want, glm::dot(c.n, to / d) / (d * d), 1e-4 * want);  // a point's law
    }
    for (int samples : {1, 16, 1024}) {
      std::vector<LightSample> out;
      ASSERT_TRUE(sample_punctual(l, c.p, c.n, samples, 99, 1e-5f, 100.0f, 0.0f, out));
      double got = 0.0;
      for (const LightSample& s : out) {
        got += s.irradiance.x;
        EXPECT_GE(s.tmax, s.tmin);
        EXPECT_TRUE(std::isfinite(s.irradiance.x));
      }
      std::printf("sphere light at d = %.2f, %4d samples: %.5f vs %.5f (%+.3f %%)\n", d, samples,
                  got, want, 100.0 * (got - want) / want);
      // Unshadowed, every sample count gives the closed form: the samples share it (a ratio
      // estimator), so that only visibility is sampled.
      EXPECT_NEAR(got, want, 1e-4 * want);
    }
  }
}

// With one sample (a gather ray's hit point), the ray goes to a random point of the sphere's
// visible cone above the horizon: where the centre is below the horizon and part of the sphere
// above it, a ray to the centre would run into the receiver's own surface and find it dark. Over
// many receivers the rays cover the visible part of the sphere.
TEST(DirectLight, OneSphereSampleAimsAboveTheHorizon) {
  Light l = test::point_light("globe", {0.0f, 0.1f, 0.0f}, 1.0f);
  l.radius = 0.3f;
  // Seen from a receiver 1 m away facing down, the centre is 0.1 m above its plane (below its
  // horizon) and the sphere reaches 0.2 m below it.
  const glm::vec3 p(1.0f, 0.0f, 0.0f), n(0.0f, -1.0f, 0.0f);
  float lowest = 1.0f, highest = -1.0f;
  for (uint64_t rng = 0; rng < 256; ++rng) {
    std::vector<LightSample> out;
    ASSERT_TRUE(sample_punctual(l, p, n, 1, rng, 1e-5f, 100.0f, 0.0f, out));
    ASSERT_EQ(out.size(), 1u);
    const float c = glm::dot(out[0].dir, n);
    EXPECT_GT(c, 0.0f) << "rng " << rng;
    lowest = std::min(lowest, c);
    highest = std::max(highest, c);
    // The ray ends on the sphere.
    const glm::vec3 end = out[0].origin + out[0].dir * out[0].tmax;
    EXPECT_NEAR(glm::length(end - l.position), l.radius, 1e-3f);
  }
  // Spread over the visible cap (the cap above the horizon spans cos 0 to about 0.2), not one ray.
  EXPECT_GT(highest - lowest, 0.1f);
}

// A rod 0.4 texels wide lies across the floor's texel grid at 30 degrees under a directional light
// from straight above: its shadow is a band thinner than a texel. Sampled at texel centres it is a
// dotted line (each texel all dark or all lit); averaged over each texel's patch it is a grey band
// whose darkening adds up to the band's area, with no texel fully dark.
TEST(DirectLight, ThinShadowIsAGreyBandNotDots) {
  constexpr int kN = 64;
  constexpr float kHalf = 2.0f;
  const float texel = 2.0f * kHalf / float(kN);
  const float width = 0.4f * texel;
  Scene scene = floor_scene();
  // The rod: a thin box 0.5 m above the floor, along (cos 30, 0, sin 30), 3 m long.
  const glm::vec3 along = glm::normalize(glm::vec3(std::cos(0.5236f), 0.0f, std::sin(0.5236f)));
  const glm::vec3 across = glm::cross(glm::vec3(0, 1, 0), along);
  const glm::vec3 c(0.0f, 0.5f, 0.0f);
  const glm::vec3 a = along * 1.5f, b = across * (0.5f * width), up(0.0f, 0.01f, 0.0f);
  // Two quads (top and bottom) make the thin occluder; occluders are double-sided.
  test::add_quad(scene, c - a - b + up, c - a + b + up, c + a + b + up, c + a - b + up, "rod_top");
  test::add_quad(scene, c - a - b, c + a - b, c + a + b, c - a + b, "rod_bottom");
  test::finish(scene);
  scene.lights = {test::directional_light("sun", {0, -1, 0}, 1.0f)};
  const TexelSet texels = floor_texels(kN, kHalf);
  auto darkening = [&](int texel_samples) {
    auto tracer = make_embree_tracer(scene);
    Progress progress(true);
    Report report;
    BakeOptions o;
    o.indirect = false;
    o.texel_samples = texel_samples;
    const BakedMaps maps =
        bake_maps(scene, test::bare_layout(kN, kN), texels, *tracer, o, progress, report);
    double sum = 0.0, darkest = 0.0;
    for (int y = 2; y < kN - 2; ++y)  // away from the rod's ends and the floor's edges
      for (int x = 2; x < kN - 2; ++x) {
        const double d = 1.0 - double(maps.base.at(x, y, 0));
        sum += d;
        darkest = std::max(darkest, d);
      }
    return std::pair<double, double>(sum, darkest);
  };
  // The band's area in texels: its width times the rod's length (3 m, all inside the interior).
  const double band = 0.4 * 3.0 / double(texel);
  const auto [point_sum, point_darkest] = darkening(1);
  const auto [patch_sum, patch_darkest] = darkening(16);
  std::printf("band %.1f texels: point samples %.1f (darkest %.2f), patch %.1f (darkest %.2f)\n",
              band, point_sum, point_darkest, patch_sum, patch_darkest);
  EXPECT_DOUBLE_EQ(point_darkest, 1.0);  // the dots
  EXPECT_LT(patch_darkest, 0.75);        // no texel fully dark
  EXPECT_NEAR(patch_sum / band, 1.0, 0.08);
}

}  // namespace
}  // namespace lightpatch::cooker
