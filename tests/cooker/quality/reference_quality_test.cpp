// The reference integrator's heavier checks (seconds, so not "unit"): the furnace at albedo 0.5
// and 0.9 within 1 % of the geometric series, at 0.99 finite and on it, and on scenes of direct
// light only (black surfaces) the reference and the cook's integrator agree within their noise:
// relative RMSE near the reference's own noise, signed median ratio near 1.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <vector>

#include "indirect_test_scenes.h"
#include "lightpatch/cooker/bake.h"
#include "lightpatch/cooker/reference_integrator.h"
#include "test_scenes.h"

namespace lightpatch::cooker {
namespace {

struct Furnace {
  double flux = 0.0, se = 0.0;  // total incident flux sum(E * area) and its standard error
  bool finite = true;
  uint64_t rays = 0;
};

// A closed 2 m box of albedo rho, a 1 cd point light off its centre, n x n texels per face.
Furnace furnace(float rho, int n, int samples) {
  Scene s = test::furnace_box(rho);
  s.lights = {test::furnace_lamp()};
  const TexelSet texels = test::box_texels({-1, -1, -1}, {1, 1, 1}, n);
  auto tracer = make_embree_tracer(s);
  Progress progress(true);
  Report report;
  ReferenceOptions o;
  o.samples = samples;
  o.texel_patch = false;  // the flux sums texel-centre values times texel areas
  const ReferenceBake r = bake_reference(s, texels, *tracer, {}, o, progress, report);
  Furnace f;
  double var = 0.0;
  for (size_t t = 0; t < texels.position.size(); ++t) {
    const double area = test::box_texel_area({-1, -1, -1}, {1, 1, 1}, n, t);
    const double e = r.map.data[3 * t], se = r.std_error.data[3 * t];
    f.finite = f.finite && std::isfinite(e) && std::isfinite(se);
    f.flux += e * area;
    var += se * se * area * area;  // texels are independent
  }
  f.se = std::sqrt(var);
  f.rays = r.rays;
  return f;
}

// Closed box, point light inside: every photon is absorbed eventually, so the total incident
// flux is 4 pi I (1 + rho + rho^2 + ...) = 4 pi I / (1 - rho). The texel sum is a midpoint rule
// over the faces: at 12 x 12 per face it overestimates the direct flux by 0.17 % (measured with
// rho = 0, where the estimate is exact), hence the allowance beside 4 standard errors.
TEST(ReferenceQuality, FurnaceMatchesTheGeometricSeries) {
  for (float rho : {0.5f, 0.9f}) {
    const Furnace f = furnace(rho, 12, 256);
    const double want = 4.0 * M_PI / (1.0 - rho);
    std::printf("reference furnace rho %.2f: %.4f vs %.4f (%+.3f %%, se %.3f %%), %llu rays\n", rho,
                f.flux, want, 100.0 * (f.flux - want) / want, 100.0 * f.se / want,
                static_cast<unsigned long long>(f.rays));
    EXPECT_TRUE(f.finite);
    EXPECT_NEAR(f.flux, want, 0.01 * want) << "rho " << rho;
    EXPECT_LT(std::fabs(f.flux - want), 4.0 * f.se + 0.0025 * want) << "rho " << rho;
  }
}

// At albedo 0.99 paths last ~100 bounces: still finite, on the series within its noise.
TEST(ReferenceQuality, FurnaceAtAlbedo099IsFiniteAndOnTheSeries) {
  const Furnace f = furnace(0.99f, 8, 128);
  const double want = 4.0 * M_PI / (1.0 - 0.99);
  std::printf("reference furnace rho 0.99: %.2f vs %.2f (%+.3f %%, se %.3f %%), %llu rays\n",
              f.flux, want, 100.0 * (f.flux - want) / want, 100.0 * f.se / want,
              static_cast<unsigned long long>(f.rays));
  EXPECT_TRUE(f.finite);
  EXPECT_NEAR(f.flux, want, 0.03 * want);
  EXPECT_LT(std::fabs(f.flux - want), 4.0 * f.se + 0.005 * want);  // midpoint rule: +0.39 %
}

// A 4 m floor under a static box (the shelf), black, with the lights given and the globe: a sphere
// light of radius 0.35 m whose shadow of the shelf is soft.
Light globe_light() {
  Light globe = test::point_light("globe", {0.3f, 2.0f, 0.2f}, 6.0f);
  globe.radius = 0.35f;
  return globe;
}

Scene shelf_scene(std::vector<Light> lights) {
  Scene s;
  test::add_quad(s, {-2, 0, -2}, {-2, 0, 2}, {2, 0, 2}, {2, 0, -2}, "floor");
  test::add_box(s, {-0.4f, 0.6f, -0.3f}, {0.3f, 0.9f, 0.4f}, "shelf");
  s.lights = std::move(lights);
  test::finish(s);
  s.materials[0].albedo = glm::vec3(0.0f);
  return s;
}

// bake_state of the authored state (bo) and the path tracer (`samples` paths a texel) on the
// shelf scene's n x n floor texels.
FloatImage cook_floor(const Scene& s, const Tracer& tracer, const TexelSet& texels,
                      const BakeOptions& bo) {
  Progress progress(true);
  Report report;
  return bake_state(s, test::bare_layout(texels.width, texels.height), texels, tracer, {}, bo,
                    progress, report);
}

ReferenceBake trace_floor(const Scene& s, const Tracer& tracer, const TexelSet& texels,
                          int samples) {
  Progress progress(true);
  Report report;
  ReferenceOptions ro;
  ro.samples = samples;
  return bake_reference(s, texels, tracer, {}, ro, progress, report);
}

// A floor under a static box, lit by a point light (hard shadow), a sphere light (soft shadow)
// and a spot; every surface black, so both integrators compute direct light only.
TEST(ReferenceQuality, AgreesWithTheCookOnDirectLight) {
  const Scene s = shelf_scene(
      {test::point_light("bulb", {-1.0f, 1.8f, 0.5f}, 3.0f), globe_light(),
       test::spot_light("spot", {1.2f, 2.2f, -1.0f}, glm::normalize(glm::vec3(-0.5f, -1.0f, 0.4f)),
                        10.0f, 0.2f, 0.5f)});
  const int n = 40;
  const TexelSet texels = test::grid_texels(n, n, {-2, 0, -2}, {4, 0, 0}, {0, 0, 4}, {0, 1, 0});
  auto tracer = make_embree_tracer(s);
  BakeOptions bo;
  bo.indirect = false;
  bo.area_samples = 256;
  const FloatImage cook = cook_floor(s, *tracer, texels, bo);
  const ReferenceBake ref = trace_floor(s, *tracer, texels, 64);
  double sq = 0.0, ref2 = 0.0, peak = 0.0;
  for (size_t i = 0; i < ref.map.data.size(); ++i) peak = std::max(peak, double(ref.map.data[i]));
  std::vector<double> ratios;
  double z_sum = 0.0;
  int z_count = 0;
  for (size_t i = 0; i < ref.map.data.size(); i += 3) {
    const double c = cook.data[i], r = ref.map.data[i], se = ref.std_error.data[i];
    sq += (c - r) * (c - r);
    ref2 += r * r;
    if (r > 0.01 * peak) ratios.push_back(c / r);
    if (se > 0.0) {
      z_sum += (c - r) / se;
      ++z_count;
    }
  }
  std::nth_element(ratios.begin(), ratios.begin() + long(ratios.size() / 2), ratios.end());
  const double median = ratios[ratios.size() / 2];
  const double rmse = std::sqrt(sq / ref2);
  const double mean_z = z_count > 0 ? z_sum / z_count : 0.0;
  std::printf(
      "cook vs reference, direct light: rel. RMSE %.3f %% (reference noise %.3f %%), "
      "median ratio %.4f, mean z %.3f over %d noisy texels\n",
      100.0 * rmse, 100.0 * ref.rel_rmse_noise, median, mean_z, z_count);
  EXPECT_LT(rmse, 2.0 * ref.rel_rmse_noise + 0.002);
  EXPECT_NEAR(median, 1.0, 0.005);
  EXPECT_LT(std::fabs(mean_z), 0.25);  // no signed bias beyond the noise
}

// Shadow edges at the presets' samples, against the path tracer: a texel whose samples of a
// light are partly blocked draws that light again kPenumbraFactor times denser
// (bake/context.h), in the cook's groups and in bake_state alike. Over the texels of the
// shelf's and the globe's soft shadows (the path tracer between 5 and 95 % of the texel's
// unshadowed light from the globe), at preview's 16 samples and 4 patch points: the cook's own
// error 10.4 % before, 4.6 % with the denser draw (the path tracer's noise, 2.0 %, taken out).
TEST(ReferenceQuality, PenumbraTexelsAreDrawnDenser) {
  const Scene s = shelf_scene({globe_light()});
  const int n = 48;
  const TexelSet texels = test::grid_texels(n, n, {-2, 0, -2}, {4, 0, 0}, {0, 0, 4}, {0, 1, 0});
  auto tracer = make_embree_tracer(s);
  BakeOptions bo;
  bo.quality = Quality::kPreview;
  bo.indirect = false;
  const FloatImage cook = cook_floor(s, *tracer, texels, bo);
  // The same texels with the shelf gone: the unshadowed light.
  Scene bare = s;
  bare.meshes.resize(1);
  BakeOptions open = bo;
  open.area_samples = 1024;
  const FloatImage lit = cook_floor(bare, *make_embree_tracer(bare), texels, open);
  const ReferenceBake ref = trace_floor(s, *tracer, texels, 1024);
  double sq = 0.0, ref2 = 0.0, noise = 0.0;
  int penumbra = 0;
  for (size_t i = 0; i < ref.map.data.size(); i += 3) {
    const double c = cook.data[i], r = ref.map.data[i], u = lit.data[i];
    if (!(r > 0.05 * u && r < 0.95 * u)) continue;
    ++penumbra;
    sq += (c - r) * (c - r);
    ref2 += r * r;
    noise += double(ref.std_error.data[i]) * ref.std_error.data[i];
  }
  const double rmse = std::sqrt(sq / ref2), own = std::sqrt(std::max(0.0, sq - noise) / ref2);
  std::printf(
      "preview direct light in %d penumbra texels: rel. RMSE %.3f %% against the path tracer "
      "(its noise %.3f %%, the cook's own error %.3f %%)\n",
      penumbra, 100.0 * rmse, 100.0 * std::sqrt(noise / ref2), 100.0 * own);
  EXPECT_GT(penumbra, 100);
  EXPECT_LT(own, 0.06);
}

}  // namespace
}  // namespace lightpatch::cooker
