// Maps stored as their direct and bounce parts (PackOptions::bounce_tolerance): texels of bounce
// light alone take the bounce tolerance, capped at the light the authored image shows there, so
// a blur never lifts a dark texel by more than the level tolerance, and at half of each map's own
// light there, so that several lights' errors at one texel do not add up to all of its light.
#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <vector>

#include "lightpatch/cooker/cook.h"
#include "lightpatch/cooker/pack_builder.h"
#include "lightpatch/cooker/report.h"
#include "lightpatch/cpu_recomposer.h"
#include "lightpatch/pack_view.h"
#include "lightpatch/scene_state.h"
#include "synthetic.h"

namespace lightpatch {
namespace {

using namespace cooker;

// One light: a bright direct disc in region 0 (its direct part) and, in region 1, bounce light
// alone, tinted, with an edge from `bright` to `dark` output steps at x = kEdge.
constexpr int kEdge = 72;

struct Scenario {
  test::Synthetic s;
  std::vector<std::array<float, 3>> factor;  // each light's authored colour times intensity
  float step = 0.01f;                        // the output step
};

// `lights` lights, each with the same light: a direct disc in region 0 and the edge of bounce
// light in region 1, `bright` and `dark` output steps in all (each light a share).
Scenario make(float bright, float dark, int lights = 1) {
  test::SyntheticOptions o;
  o.width = 96;
  o.height = 80;
  o.lights = lights;
  o.objects = 0;
  Scenario sc;
  sc.s = test::make_synthetic(o);
  BakedMaps& m = sc.s.maps;
  m.output_step = sc.step;
  m.base = FloatImage(o.width, o.height, 3);  // no static light: the lights alone show
  m.shadows.clear();
  m.pair_corrections.clear();
  m.static_shadows.clear();
  m.contribution.clear();
  m.contribution_direct.clear();
  m.contribution_indirect.clear();
  const Rect r0 = sc.s.layout.regions[0].rect, r1 = sc.s.layout.regions[1].rect;
  const float share = 1.0f / float(lights);
  for (int i = 0; i < lights; ++i) {
    const Light& l = sc.s.scene.lights[size_t(m.lights[size_t(i)])];
    std::array<float, 3> f{};
    for (int c = 0; c < 3; ++c) f[size_t(c)] = l.color[c] * l.intensity;
    sc.factor.push_back(f);
    const float a = std::max({f[0], f[1], f[2]});
    FloatImage c(o.width, o.height, 3), direct(o.width, o.height, 1);
    for (int y = r0.y; y < r0.y + r0.h; ++y)
      for (int x = r0.x; x < r0.x + r0.w; ++x) {
        const float dx = float(x - (r0.x + r0.w / 2)), dy = float(y - (r0.y + r0.h / 2));
        if (dx * dx + dy * dy > 100.0f) continue;
        direct.at(x, y, 0) = 300.0f * sc.step / a;  // 300 steps: the light's own peak is bright
        for (int k = 0; k < 3; ++k) c.at(x, y, k) = direct.at(x, y, 0);
      }
    const float tint[3] = {1.0f, 0.85f, 0.7f};
    for (int y = r1.y; y < r1.y + r1.h; ++y)
      for (int x = r1.x; x < r1.x + r1.w; ++x)
        for (int k = 0; k < 3; ++k)
          c.at(x, y, k) = (x < kEdge ? bright : dark) * share * tint[k] * sc.step / a;
    m.contribution.push_back(std::move(c));
    m.contribution_direct.push_back(std::move(direct));
  }
  return sc;
}

// The recomposed authored state against the float maps, over region 1's dark side: the mean of
// recomposed / true (channels summed: a tint under the output step is stored as its mean), and
// the largest difference in output steps.
void measure(const Scenario& sc, const PackOptions& po, double* mean_ratio, double* worst_steps) {
  Report report;
  const std::vector<uint8_t> bytes = build_pack(sc.s.scene, sc.s.layout, sc.s.maps, po, report);
  PackView v;
  Error e;
  ASSERT_EQ(PackView::open(bytes.data(), bytes.size(), &v, &e), Status::kOk) << e.message;
  SceneState st;
  CpuRecomposer r;
  ASSERT_EQ(st.init(v, nullptr), Status::kOk);
  ASSERT_EQ(r.init(v, nullptr), Status::kOk);
  for (uint32_t l = 0; l < v.light_count(); ++l) ASSERT_EQ(st.set_light_on(l, true), Status::kOk);
  ASSERT_EQ(r.rebuild(st), Status::kOk);
  const std::vector<FloatImage>& maps = sc.s.maps.contribution;
  const int width = maps[0].width;
  const Rect r1 = sc.s.layout.regions[1].rect;
  double sum = 0.0, worst = 0.0;
  int n = 0;
  for (int y = r1.y; y < r1.y + r1.h; ++y)
    for (int x = kEdge; x < r1.x + r1.w; ++x) {
      double want = 0.0, got = 0.0;
      for (int k = 0; k < 3; ++k) {
        double w = 0.0;
        for (size_t i = 0; i < maps.size(); ++i)
          w += double(maps[i].at(x, y, k)) * sc.factor[i][size_t(k)];
        const double g = r.rgb()[(size_t(y) * width + size_t(x)) * 3 + size_t(k)];
        want += w;
        got += g;
        worst = std::max(worst, std::fabs(g - w) / sc.step);
      }
      sum += got / want;
      ++n;
    }
  *mean_ratio = sum / double(n);
  *worst_steps = worst;
}

TEST(DirectAndBounceParts, ABlurNeverLiftsADarkTexelBeyondWhatItShows) {
  // 5.5 steps beside 1.5: blurred at a coarser level, the dark side would take up to 2 steps
  // more (within a 4-step tolerance, 2.3x its light); capped at the 1.5 steps it shows, its
  // texels keep the level tolerance and the edge stays sharp.
  const Scenario dim = make(5.5f, 1.5f);
  double ratio = 0.0, worst = 0.0;
  measure(dim, PackOptions{}, &ratio, &worst);
  std::printf("dark side beside a 4-step edge: mean ratio %.4f, largest difference %.2f steps\n",
              ratio, worst);
  EXPECT_NEAR(ratio, 1.0, 0.05);
  EXPECT_LT(worst, 1.6);  // the level tolerance and the 8-bit rounding
  // The same edge 4 times brighter (22 beside 6 steps): the dark side shows 6 steps, so the
  // bounce tolerance applies in full there and the coarser levels may blur it, by at most 4
  // steps and the rounding.
  const Scenario lit = make(22.0f, 6.0f);
  measure(lit, PackOptions{}, &ratio, &worst);
  std::printf("the same edge 4x brighter: mean ratio %.4f, largest difference %.2f steps\n", ratio,
              worst);
  EXPECT_LT(worst, kDefaultBounceTolerance + 0.6);
  // With the bounce tolerance at the level tolerance, the dark side is as exact as before.
  PackOptions strict;
  strict.bounce_tolerance = strict.level_tolerance;
  measure(dim, strict, &ratio, &worst);
  std::printf("bounce tolerance 1: mean ratio %.4f, largest difference %.2f steps\n", ratio, worst);
  EXPECT_NEAR(ratio, 1.0, 0.05);
}

// Three lights whose bounce light meets at one edge, 24 steps beside 9 in all (8 beside 3 each):
// capped only at the 9 steps the dark side shows, each map could be off by the whole bounce
// tolerance (3 steps, all of its own light) and the three errors add up. Each map's tolerance is
// also capped at half its own light there (1.5 steps), so the dark side keeps more than half its
// light whatever the levels do.
TEST(DirectAndBounceParts, SeveralLightsAtOneEdgeEachKeepHalfTheirLight) {
  const Scenario three = make(24.0f, 9.0f, 3);
  double ratio = 0.0, worst = 0.0;
  measure(three, PackOptions{}, &ratio, &worst);
  std::printf(
      "three lights at one edge, dark side: mean ratio %.4f, largest difference %.2f "
      "steps\n",
      ratio, worst);
  EXPECT_NEAR(ratio, 1.0, 0.1);
  // Three maps each within max(level tolerance, half its 3 steps) and its rounding.
  EXPECT_LT(worst, 3.0 * (1.5 + 0.6));
}

// The shipping preset keeps bounce light to the level tolerance (kProductionBounceTolerance):
// what `cook --quality production` and the accuracy sweep's production row pack with; an
// explicit --bounce-tolerance still wins.
TEST(DirectAndBounceParts, ProductionPacksBounceLightAtTheLevelTolerance) {
  BakeOptions preview, production;
  production.quality = Quality::kProduction;
  EXPECT_EQ(pack_options(preview).bounce_tolerance, kDefaultBounceTolerance);
  EXPECT_EQ(pack_options(production).bounce_tolerance, kProductionBounceTolerance);
  EXPECT_EQ(pack_options(production).bounce_tolerance, pack_options(production).level_tolerance);
  production.bounce_tolerance = 4.0f;
  EXPECT_EQ(pack_options(production).bounce_tolerance, 4.0f);
}

}  // namespace
}  // namespace lightpatch
