// Clean light maps on content shaped like real exports (issue 13): no negative texel in any
// finalized map, no one-texel dot or line on a smoothly lit surface, in scenes of smooth props
// (shared vertices, so the unwrap's cuts are stitched), big triangles and thin charts.
//
// Direct light only: the unshadowed irradiance at a texel's sample point is then known in closed
// form, so a texel is "smoothly lit" where the raw bake equals it, and the finalized map must stay
// within a few percent of it there (dilation and seam stitching may only mix neighbouring values
// of the same smooth field).
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <memory>
#include <string>
#include <vector>

#include "direct_light.h"
#include "lightpatch/cooker/bake.h"
#include "lightpatch/cooker/texel_builder.h"
#include "lightpatch/cooker/tracer.h"
#include "lightpatch/cooker/unwrap.h"
#include "test_scenes.h"

namespace lightpatch::cooker {
namespace {

constexpr float kPi = 3.14159265358979f;

// A smooth-shaded box seen from inside (a room): 8 shared corners, normals the inward diagonals,
// 12 triangles facing in, as Blender exports a shade-smooth cube with flipped normals and no
// UV seams.
int add_smooth_room(Scene& s, const glm::vec3& lo, const glm::vec3& hi, const std::string& name) {
  MeshInstance m;
  m.name = name;
  const glm::vec3 centre = (lo + hi) * 0.5f;
  for (int i = 0; i < 8; ++i) {
    const glm::vec3 p(i & 1 ? hi.x : lo.x, i & 2 ? hi.y : lo.y, i & 4 ? hi.z : lo.z);
    m.positions.push_back(p);
    m.normals.push_back(glm::normalize(centre - p));
  }
  // Faces as corner quads, counter-clockwise seen from inside.
  const uint32_t faces[6][4] = {{0, 1, 3, 2}, {4, 6, 7, 5}, {0, 4, 5, 1},
                                {2, 3, 7, 6}, {0, 2, 6, 4}, {1, 5, 7, 3}};
  for (const auto& f : faces)
    for (uint32_t k : {0u, 1u, 2u, 0u, 2u, 3u}) m.indices.push_back(f[k]);
  s.meshes.push_back(std::move(m));
  return int(s.meshes.size()) - 1;
}

// A smooth open cylinder along y (a candle, a pole): shared vertices around, radial normals.
int add_smooth_cylinder(Scene& s, const glm::vec3& base, float radius, float height, int segments,
                        const std::string& name, int object = -1) {
  MeshInstance m;
  m.name = name;
  m.object = object;
  for (int i = 0; i < segments; ++i) {
    const float a = 2.0f * kPi * float(i) / float(segments);
    const glm::vec3 n(std::cos(a), 0.0f, -std::sin(a));
    for (int k = 0; k < 2; ++k) {
      m.positions.push_back(base + n * radius + glm::vec3(0, height * float(k), 0));
      m.normals.push_back(n);
    }
  }
  for (int i = 0; i < segments; ++i) {
    const uint32_t a = uint32_t(2 * i), b = uint32_t(2 * ((i + 1) % segments));
    for (uint32_t v : {a, b, b + 1, a, b + 1, a + 1}) m.indices.push_back(v);
  }
  s.meshes.push_back(std::move(m));
  const int index = int(s.meshes.size()) - 1;
  if (object >= 0) s.objects[size_t(object)].meshes.push_back(index);
  return index;
}

// A smooth UV sphere (shared vertices, normals from the centre).
int add_smooth_sphere(Scene& s, const glm::vec3& centre, float radius, int rings,
                      const std::string& name, int object = -1) {
  MeshInstance m;
  m.name = name;
  m.object = object;
  const int segments = 2 * rings;
  for (int r = 0; r <= rings; ++r) {
    const float th = kPi * float(r) / float(rings);
    for (int k = 0; k < segments; ++k) {
      const float ph = 2.0f * kPi * float(k) / float(segments);
      const glm::vec3 n(std::sin(th) * std::cos(ph), std::cos(th), -std::sin(th) * std::sin(ph));
      m.positions.push_back(centre + n * radius);
      m.normals.push_back(n);
    }
  }
  for (int r = 0; r < rings; ++r)
    for (int k = 0; k < segments; ++k) {
      const uint32_t a = uint32_t(r * segments + k),
                     b = uint32_t(r * segments + (k + 1) % segments);
      const uint32_t c = a + uint32_t(segments), d = b + uint32_t(segments);
      if (r > 0) m.indices.insert(m.indices.end(), {a, c, b});
      if (r + 1 < rings) m.indices.insert(m.indices.end(), {b, c, d});
    }
  s.meshes.push_back(std::move(m));
  const int index = int(s.meshes.size()) - 1;
  if (object >= 0) s.objects[size_t(object)].meshes.push_back(index);
  return index;
}

// Props of a tavern corner: a smooth room, candles (thin smooth cylinders: charts a few texels
// wide) and a semi-dynamic smooth sphere, under a semi-dynamic point light and a static spot.
Scene smooth_props() {
  Scene s;
  add_smooth_room(s, {-3, 0, -2.5f}, {3, 3, 2.5f}, "room");
  add_smooth_cylinder(s, {-1.0f, 0.0f, 0.5f}, 0.04f, 0.5f, 16, "candle_a");
  add_smooth_cylinder(s, {1.2f, 0.0f, -0.6f}, 0.03f, 0.3f, 12, "candle_b");
  s.objects.push_back(Object{"ball", -1, {}});
  add_smooth_sphere(s, {0.3f, 0.4f, 0.3f}, 0.25f, 8, "ball", 0);
  s.lights = {test::point_light("lamp", {0.2f, 2.4f, 0.1f}, 20.0f, true),
              test::spot_light("spot", {-2.5f, 2.8f, 2.0f}, glm::normalize(glm::vec3(1, -1, -1)),
                               40.0f, 0.4f, 0.9f)};
  test::finish(s);
  return s;
}

BakeOptions direct_only() {
  BakeOptions o;
  o.quality = Quality::kDraft;
  o.indirect = false;
  return o;
}

struct Prepared {
  Scene scene;
  Layout layout;
  std::unique_ptr<Tracer> tracer;
  TexelSet texels;
  explicit Prepared(Scene s, float tpu, int align = 1) : scene(std::move(s)) {
    LayoutOptions lo;
    lo.texels_per_unit = tpu;
    lo.align = align;
    layout = build_layout(scene, lo);
    tracer = make_embree_tracer(scene);
    texels = build_texels(scene, layout, tracer.get());
  }
};

struct Negatives {
  size_t count = 0;
  float min = 0.0f;
};

Negatives negatives(const FloatImage& m) {
  Negatives n;
  for (float v : m.data) {
    n.count += v < 0.0f ? 1 : 0;
    n.min = std::min(n.min, v);
  }
  return n;
}

// Unshadowed direct irradiance of the state where every light is on as authored.
float analytic(const Scene& s, const glm::vec3& p, const glm::vec3& n) {
  float e = 0.0f;
  for (const Light& l : s.lights) e += l.intensity * punctual_irradiance(l, l.position, p, n, 0.0f);
  return e;
}

// One-texel dots and lines: texels of a smoothly lit surface (the raw bake equals the closed form
// at the texel and its 8 neighbours, which differ from it by less than 20%) where finalizing made
// the texel stand out from its neighbours' mean by more than `tolerance` of its value beyond what
// the closed form itself does (its curvature at texel scale).
struct Dots {
  size_t checked = 0, bright = 0, dark = 0;
  float worst = 0.0f;  // signed excess, relative to the closed form
  int worst_x = -1, worst_y = -1;
};

Dots dots(const Prepared& p, const FloatImage& raw, const FloatImage& final_map, float tolerance) {
  const TexelSet& ts = p.texels;
  std::vector<float> want(ts.valid.size(), -1.0f);  // closed form where the bake is unshadowed
  for (size_t i = 0; i < want.size(); ++i) {
    if (!ts.valid[i]) continue;
    const float e = analytic(p.scene, ts.position[i], ts.normal[i]);
    if (e > 0.0f && std::abs(raw.data[i * 3] - e) <= 1e-3f * e) want[i] = e;
  }
  Dots d;
  for (int y = 1; y + 1 < ts.height; ++y)
    for (int x = 1; x + 1 < ts.width; ++x) {
      const size_t i = ts.index(x, y);
      if (want[i] < 0.0f) continue;
      float mean_want = 0.0f, mean_final = 0.0f;
      bool smooth = true;
      for (int k = 0; k < 9 && smooth; ++k) {
        if (k == 4) continue;
        const size_t j = ts.index(x + k % 3 - 1, y + k / 3 - 1);
        // Resolved at texel scale: the closed form changes by less than 20% between neighbours.
        smooth = want[j] >= 0.0f && ts.mesh[j] == ts.mesh[i] && want[j] <= 1.2f * want[i] &&
                 want[i] <= 1.2f * want[j];
        mean_want += want[j] / 8.0f;
        mean_final += final_map.data[j * 3] / 8.0f;
      }
      if (!smooth) continue;
      ++d.checked;
      const float excess = ((final_map.data[i * 3] - mean_final) - (want[i] - mean_want)) / want[i];
      d.bright += excess > tolerance ? 1 : 0;
      d.dark += excess < -tolerance ? 1 : 0;
      if (std::abs(excess) > std::abs(d.worst)) {
        d.worst = excess;
        d.worst_x = x;
        d.worst_y = y;
      }
    }
  return d;
}

// An indirect map changes where the pack stores bounce light, never the light itself: a state
// baked on a layout with blocks equals the same state baked on the same charts read as a layout
// without blocks (the light map holds what the indirect map's filter gets wrong, map_split.h).
// Defining the bounce light as the indirect map's magnification, as once done, blended it across
// the smooth room's creases and across cuts (12 % from the path tracer on the small inn's
// surfaces).
TEST(CleanMaps, AnIndirectMapLeavesTheBakedLightAsTheSurfacesHaveIt) {
  const Prepared p(smooth_props(), 40.0f, 4);
  ASSERT_EQ(p.layout.align, 4);
  ASSERT_GT(p.layout.seams.size(), 20u);
  BakeOptions with_map;
  with_map.quality = Quality::kDraft;  // gathers on 4 x 4 blocks
  with_map.indirect_scale = 4;
  BakeOptions without = with_map;
  without.indirect_scale = 4;  // the same gather
  Progress progress(true);
  Report report;
  FloatImage a =
      bake_state(p.scene, p.layout, p.texels, *p.tracer, StateSpec{}, with_map, progress, report);
  Layout flat = p.layout;  // the same charts and texels, read as a layout without blocks
  flat.align = 1;
  FloatImage b =
      bake_state(p.scene, flat, p.texels, *p.tracer, StateSpec{}, without, progress, report);
  finalize_map(a, p.scene, p.layout, p.texels);
  finalize_map(b, p.scene, p.layout, p.texels);
  ASSERT_EQ(a.data.size(), b.data.size());
  double peak = 0.0, worst = 0.0;
  for (size_t i = 0; i < a.data.size(); ++i) {
    peak = std::max(peak, double(b.data[i]));
    worst = std::max(worst, std::fabs(double(a.data[i]) - b.data[i]));
  }
  ASSERT_GT(peak, 0.0);
  EXPECT_LE(worst, 1e-6 * peak);
}

TEST(CleanMaps, SmoothPropsHaveNoNegativeTexelAndNoDots) {
  const Prepared p(smooth_props(), 40.0f);
  ASSERT_GT(p.layout.seams.size(), 20u);
  auto tracer = make_embree_tracer(p.scene);
  Progress progress(true);
  Report report;
  FloatImage raw = bake_state(p.scene, p.layout, p.texels, *p.tracer, StateSpec{}, direct_only(),
                              progress, report);
  FloatImage state = raw;
  finalize_map(state, p.scene, p.layout, p.texels);
  const Negatives ns = negatives(state);
  const Dots d = dots(p, raw, state, 0.05f);
  std::printf(
      "bake-state: %zu negative (min %.4g); %zu smooth texels, %zu bright, %zu dark, worst "
      "%.3f at (%d, %d)\n",
      ns.count, double(ns.min), d.checked, d.bright, d.dark, double(d.worst), d.worst_x, d.worst_y);
  EXPECT_EQ(ns.count, 0u) << "min " << ns.min;
  EXPECT_GT(d.checked, 1000u);
  EXPECT_EQ(d.bright + d.dark, 0u) << "worst ratio " << d.worst;

  // The cook's maps: B, each C_l and each C_l - S_ol (light l alone with o present) never
  // negative once finalized.
  BakedMaps maps =
      bake_maps(p.scene, p.layout, p.texels, *p.tracer, direct_only(), progress, report);
  finalize_maps(maps, p.scene, p.layout, p.texels);
  const Negatives nb = negatives(maps.base);
  EXPECT_EQ(nb.count, 0u) << "base min " << nb.min;
  for (size_t l = 0; l < maps.contribution.size(); ++l) {
    const Negatives nc = negatives(maps.contribution[l]);
    std::printf("C_%zu: %zu negative (min %.4g)\n", l, nc.count, double(nc.min));
    EXPECT_EQ(nc.count, 0u) << "contribution " << l << " min " << nc.min;
  }
  ASSERT_FALSE(maps.shadows.empty());
  for (const ShadowMap& sm : maps.shadows) {
    FloatImage t = maps.contribution[size_t(sm.light)];
    const size_t ch = size_t(t.channels), sch = size_t(sm.map.channels);
    for (size_t i = 0; i < t.data.size(); ++i) t.data[i] -= sm.map.data[i / ch * sch + i % sch];
    const Negatives nt = negatives(t);
    std::printf("C - S: %zu negative (min %.4g)\n", nt.count, double(nt.min));
    EXPECT_EQ(nt.count, 0u) << "C - S min " << nt.min;
  }
}

// A city's ground: a 16-gon 166 m across as Blender 3.4 exports it, 14 big triangles over 16
// shared vertices (its n-gon triangulation, indices verbatim), under a street spot and a lamp.
Scene big_triangle_ground() {
  Scene s;
  MeshInstance g;
  g.name = "Ground";
  for (int k = 0; k < 16; ++k) {
    const float a = 2.0f * kPi * float(k) / 16.0f;
    g.positions.push_back({-83.0f * std::sin(a), 0.0f, -83.0f * std::cos(a)});
    g.normals.push_back({0.0f, 1.0f, 0.0f});
  }
  g.indices = {15, 0,  1,  1,  2, 3, 3, 4, 5, 5, 6, 7,  7,  8,  9,  9,  10, 11, 11, 12, 13,
               13, 14, 15, 15, 1, 3, 3, 5, 7, 7, 9, 11, 11, 13, 15, 15, 3,  7,  7,  11, 15};
  s.meshes.push_back(std::move(g));
  s.lights = {test::spot_light("street", {5.0f, 15.0f, -3.0f}, {0, -1, 0}, 2e4f, 0.6f, 0.87f),
              test::point_light("lamp", {-30.0f, 4.0f, 10.0f}, 400.0f)};
  test::finish(s);
  return s;
}

TEST(CleanMaps, BigTrianglesUnderASpotShowNoLines) {
  const Prepared p(big_triangle_ground(), 0.0f);
  Progress progress(true);
  Report report;
  const FloatImage raw = bake_state(p.scene, p.layout, p.texels, *p.tracer, StateSpec{},
                                    direct_only(), progress, report);
  FloatImage state = raw;
  finalize_map(state, p.scene, p.layout, p.texels);
  EXPECT_EQ(negatives(state).count, 0u);
  // Every valid texel the closed form lights above 0.1% of the peak is lit (no black line of
  // texels along the interior edges), and no texel stands out from its neighbours.
  float peak = 0.0f;
  for (float v : raw.data) peak = std::max(peak, v);
  size_t lit = 0, black = 0;
  for (size_t i = 0; i < p.texels.valid.size(); ++i) {
    if (!p.texels.valid[i]) continue;
    const float want = analytic(p.scene, p.texels.position[i], p.texels.normal[i]);
    if (want < 1e-3f * peak) continue;
    ++lit;
    black += state.data[i * 3] < 0.5f * want ? 1 : 0;
  }
  const Dots d = dots(p, raw, state, 0.02f);
  std::printf(
      "%dx%d map, %zu lit texels, %zu dark; %zu smooth texels, %zu bright, %zu dark, worst "
      "%.3f\n",
      p.layout.width, p.layout.height, lit, black, d.checked, d.bright, d.dark, double(d.worst));
  EXPECT_GT(lit, 10000u);
  EXPECT_EQ(black, 0u);
  EXPECT_GT(d.checked, lit / 2);
  EXPECT_EQ(d.bright + d.dark, 0u) << "worst " << d.worst;
}

}  // namespace
}  // namespace lightpatch::cooker
