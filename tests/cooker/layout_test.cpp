// The light-map layout and texels: unwrap determinism and non-overlap, density and its lowering,
// verbatim TEXCOORD_1 and its overlap error, seams that agree on both sides, and a sealed room that
// stays dark when lit from outside.
#include <gtest/gtest.h>

#include <cmath>

#include "lightpatch/cooker/bake.h"
#include "lightpatch/cooker/error.h"
#include "lightpatch/cooker/texel_builder.h"
#include "lightpatch/cooker/tracer.h"
#include "lightpatch/cooker/unwrap.h"
#include "test_scenes.h"

namespace lightpatch::cooker {
namespace {

// A smooth open cylinder (shared vertices around, so one smoothing group) along y.
int add_cylinder(Scene& scene, const glm::vec3& base, float radius, float height, int segments,
                 const std::string& name) {
  MeshInstance m;
  m.name = name;
  for (int i = 0; i < segments; ++i) {
    const float a = 6.2831853f * float(i) / float(segments);
    const glm::vec3 n(std::cos(a), 0.0f, std::sin(a));
    for (int k = 0; k < 2; ++k) {
      m.positions.push_back(base + n * radius + glm::vec3(0, height * float(k), 0));
      m.normals.push_back(n);
    }
  }
  for (int i = 0; i < segments; ++i) {
    const uint32_t a = uint32_t(2 * i), b = uint32_t(2 * ((i + 1) % segments));
    // Outward faces: counter-clockwise seen from outside.
    for (uint32_t v : {a, a + 1, b + 1, a, b + 1, b}) m.indices.push_back(v);
  }
  scene.meshes.push_back(std::move(m));
  return int(scene.meshes.size()) - 1;
}

float bilinear(const FloatImage& map, const glm::vec2& uv, int c) {
  const float fx = uv.x * float(map.width) - 0.5f, fy = uv.y * float(map.height) - 0.5f;
  const int x0 = int(std::floor(fx)), y0 = int(std::floor(fy));
  const float ax = fx - float(x0), ay = fy - float(y0);
  float v = 0.0f;
  for (int k = 0; k < 4; ++k) {
    const int x = std::clamp(x0 + (k & 1), 0, map.width - 1);
    const int y = std::clamp(y0 + (k >> 1), 0, map.height - 1);
    v += ((k & 1) ? ax : 1 - ax) * ((k >> 1) ? ay : 1 - ay) * map.at(x, y, c);
  }
  return v;
}

// Brute force: do two UV triangles share area (beyond a small tolerance)?
bool overlap(const glm::vec2* a, const glm::vec2* b) {
  for (int pass = 0; pass < 2; ++pass) {
    const glm::vec2* t = pass ? b : a;
    for (int k = 0; k < 3; ++k) {
      const glm::vec2 e = t[(k + 1) % 3] - t[k];
      const glm::vec2 axis(-e.y, e.x);
      float amin = 1e30f, amax = -1e30f, bmin = 1e30f, bmax = -1e30f;
      for (int j = 0; j < 3; ++j) {
        amin = std::min(amin, glm::dot(a[j], axis));
        amax = std::max(amax, glm::dot(a[j], axis));
        bmin = std::min(bmin, glm::dot(b[j], axis));
        bmax = std::max(bmax, glm::dot(b[j], axis));
      }
      const float tol = 1e-3f * glm::length(axis);  // a thousandth of a texel
      if (amax <= bmin + tol || bmax <= amin + tol) return false;
    }
  }
  return true;
}

Scene props_scene() {
  Scene s;
  test::add_quad(s, {-3, 0, -3}, {-3, 0, 3}, {3, 0, 3}, {3, 0, -3}, "floor");
  test::add_box(s, {-1, 0, -1}, {0, 1, 0}, "crate");
  add_cylinder(s, {1.5f, 0, 1.5f}, 0.4f, 1.2f, 24, "pillar");
  test::add_object_box(s, {1, 0, -2}, {1.4f, 0.3f, -1.6f}, "book");
  test::finish(s);
  return s;
}

TEST(Layout, DeterministicInsideThePageAndWithoutOverlaps) {
  const Scene s = props_scene();
  LayoutOptions o;
  o.texels_per_unit = 16.0f;
  const Layout a = build_layout(s, o);
  const Layout b = build_layout(s, o);
  ASSERT_EQ(a.width, b.width);
  ASSERT_EQ(a.meshes.size(), s.meshes.size());
  for (size_t m = 0; m < a.meshes.size(); ++m) {
    EXPECT_EQ(a.meshes[m].uv, b.meshes[m].uv);
    EXPECT_EQ(a.meshes[m].indices, b.meshes[m].indices);
    EXPECT_EQ(a.meshes[m].indices.size(), s.meshes[m].indices.size());
  }
  EXPECT_FALSE(a.verbatim_uv1);
  EXPECT_FLOAT_EQ(a.texels_per_unit, 16.0f);
  // One region per mesh (scenes built in code have no node indices), disjoint, inside the page.
  ASSERT_EQ(a.regions.size(), s.meshes.size());
  for (size_t i = 0; i < a.regions.size(); ++i) {
    const Rect& r = a.regions[i].rect;
    EXPECT_GE(r.x, 0);
    EXPECT_LE(r.x + r.w, a.width);
    EXPECT_LE(r.y + r.h, a.height);
    for (size_t j = i + 1; j < a.regions.size(); ++j) {
      const Rect& q = a.regions[j].rect;
      EXPECT_FALSE(r.x < q.x + q.w && q.x < r.x + r.w && r.y < q.y + q.h && q.y < r.y + r.h);
    }
  }
  EXPECT_EQ(a.regions[3].object, 0);
  // Every triangle inside its region; no two triangles share area.
  std::vector<glm::vec2> all;
  const glm::vec2 size(float(a.width), float(a.height));
  for (size_t m = 0; m < a.meshes.size(); ++m) {
    const MeshLayout& ml = a.meshes[m];
    const Rect& r = a.regions[m].rect;
    for (uint32_t i : ml.indices) {
      const glm::vec2 p = ml.uv[i] * size;
      EXPECT_GE(p.x, float(r.x));
      EXPECT_LE(p.x, float(r.x + r.w));
      EXPECT_GE(p.y, float(r.y));
      EXPECT_LE(p.y, float(r.y + r.h));
      all.push_back(p);
    }
    for (size_t v = 0; v < ml.source_vertex.size(); ++v)
      EXPECT_LT(ml.source_vertex[v], s.meshes[m].positions.size());
  }
  for (size_t i = 0; i < all.size(); i += 3)
    for (size_t j = i + 3; j < all.size(); j += 3)
      ASSERT_FALSE(overlap(&all[i], &all[j])) << i << " " << j;
}

// What the pack builder's chart cut keeps (split_by_charts, inset Layout::border - 1): every texel
// a bilinear read of a triangle can reach lies in one chart rectangle of its region less the
// border's outer rings, at the default border and at a wider one.
TEST(Layout, BilinearReadsOfEveryTriangleStayInsideItsChartLessTheOuterBorderRings) {
  const Scene s = props_scene();
  for (const int border : {2, 4}) {
    LayoutOptions o;
    o.texels_per_unit = 16.0f;
    o.border_texels = border;
    const Layout a = build_layout(s, o);
    ASSERT_EQ(a.border, border);
    const int inset = a.border - 1;
    const glm::vec2 size(float(a.width), float(a.height));
    size_t triangles = 0;
    for (size_t m = 0; m < a.meshes.size(); ++m) {
      const MeshLayout& ml = a.meshes[m];
      const Region& region = a.regions[m];  // one region per mesh in a scene built in code
      ASSERT_FALSE(region.charts.empty());
      for (size_t t = 0; t + 2 < ml.indices.size(); t += 3) {
        glm::vec2 lo(1e30f), hi(-1e30f);
        for (size_t k = 0; k < 3; ++k) {
          lo = glm::min(lo, ml.uv[ml.indices[t + k]] * size);
          hi = glm::max(hi, ml.uv[ml.indices[t + k]] * size);
        }
        // The texels a bilinear tap anywhere in the triangle's box reads.
        const int x0 = int(std::floor(lo.x - 0.5f)), x1 = int(std::floor(hi.x - 0.5f)) + 1;
        const int y0 = int(std::floor(lo.y - 0.5f)), y1 = int(std::floor(hi.y - 0.5f)) + 1;
        bool inside = false;
        for (const Rect& c : region.charts)
          inside = inside || (x0 >= c.x + inset && x1 < c.x + c.w - inset && y0 >= c.y + inset &&
                              y1 < c.y + c.h - inset);
        EXPECT_TRUE(inside) << region.name << " triangle " << t / 3 << " border " << border;
        ++triangles;
      }
    }
    EXPECT_GT(triangles, 20u);
  }
}

TEST(Layout, DensityGivesChartSizeAndIsLoweredToFitWithANote) {
  Scene s;
  test::add_quad(s, {0, 0, 0}, {0, 0, 1}, {2, 0, 1}, {2, 0, 0}, "plane");  // 2 m x 1 m
  test::finish(s);
  LayoutOptions o;
  o.texels_per_unit = 20.0f;
  o.border_texels = 2;
  const Layout l = build_layout(s, o);
  const Rect& r = l.regions[0].rect;
  EXPECT_EQ(std::max(r.w, r.h), 40 + 4);
  EXPECT_EQ(std::min(r.w, r.h), 20 + 4);
  EXPECT_TRUE(l.notes.empty());

  o.lightmap_size = 24;  // too small for 44 texels
  const Layout small = build_layout(s, o);
  EXPECT_EQ(small.width, 24);
  EXPECT_LT(small.texels_per_unit, 20.0f);
  ASSERT_EQ(small.notes.size(), 1u);
  EXPECT_NE(small.notes[0].find("lowered"), std::string::npos);
  EXPECT_LE(small.regions[0].rect.x + small.regions[0].rect.w, 24);
}

TEST(Layout, Texcoord1WholeSceneOrPerNodeAndOverlapsInOneMeshRejectedByName) {
  Scene s;
  const int a = test::add_quad(s, {0, 0, 0}, {0, 0, 1}, {1, 0, 1}, {1, 0, 0}, "left");
  const int b = test::add_quad(s, {2, 0, 0}, {2, 0, 1}, {4, 0, 1}, {4, 0, 0}, "right");
  s.meshes[size_t(a)].uv1 = {{0.05f, 0.05f}, {0.05f, 0.45f}, {0.45f, 0.45f}, {0.45f, 0.05f}};
  s.meshes[size_t(b)].uv1 = {{0.55f, 0.55f}, {0.55f, 0.95f}, {0.95f, 0.95f}, {0.95f, 0.55f}};
  test::finish(s);
  LayoutOptions o;
  o.lightmap_size = 64;
  const Layout l = build_layout(s, o);
  EXPECT_TRUE(l.verbatim_uv1);
  EXPECT_EQ(l.width, 64);
  EXPECT_EQ(l.meshes[size_t(a)].uv, s.meshes[size_t(a)].uv1);
  EXPECT_EQ(l.meshes[size_t(a)].uv1_scale_offset, glm::vec4(1, 1, 0, 0));
  ASSERT_EQ(l.regions.size(), 2u);

  // Each mesh's UVs over the whole square, as Blender's Lightmap Pack writes them: each placed in
  // its own rectangle by one scale and offset, sized by its area (the right quad is twice the
  // left one), inside the page and apart.
  s.meshes[size_t(a)].uv1 = {{0, 0}, {0, 1}, {1, 1}, {1, 0}};
  s.meshes[size_t(b)].uv1 = {{0, 0}, {0, 1}, {1, 1}, {1, 0}};
  o.lightmap_size = 0;
  o.texels_per_unit = 16.0f;
  const Layout per = build_layout(s, o);
  EXPECT_FALSE(per.verbatim_uv1);
  EXPECT_EQ(per.uv1_regions, 2);
  ASSERT_EQ(per.regions.size(), 2u);
  for (int m : {a, b}) {
    const MeshLayout& ml = per.meshes[size_t(m)];
    EXPECT_TRUE(ml.from_uv1);
    for (size_t v = 0; v < ml.uv.size(); ++v) {
      const glm::vec4 so = ml.uv1_scale_offset;
      EXPECT_EQ(ml.uv[v],
                s.meshes[size_t(m)].uv1[v] * glm::vec2(so.x, so.y) + glm::vec2(so.z, so.w));
      const glm::vec2 px = ml.uv[v] * glm::vec2(float(per.width), float(per.height));
      const Rect& r = per.regions[size_t(m)].rect;
      EXPECT_GE(px.x, float(r.x + o.border_texels) - 1e-3f);
      EXPECT_LE(px.x, float(r.x + r.w - o.border_texels) + 1e-3f);
      EXPECT_GE(px.y, float(r.y + o.border_texels) - 1e-3f);
      EXPECT_LE(px.y, float(r.y + r.h - o.border_texels) + 1e-3f);
    }
  }
  // 16 texels per metre: the 1 m quad spans 16 texels, the 2 m x 1 m one 16 * sqrt(2) per side.
  const float sa = per.meshes[size_t(a)].uv1_scale_offset.x * float(per.width);
  const float sb = per.meshes[size_t(b)].uv1_scale_offset.x * float(per.width);
  EXPECT_NEAR(sa, 16.0f, 1e-3f);
  EXPECT_NEAR(sb, 16.0f * std::sqrt(2.0f), 1e-3f);
  const Rect &ra = per.regions[0].rect, &rb = per.regions[1].rect;
  EXPECT_FALSE(ra.x < rb.x + rb.w && rb.x < ra.x + ra.w && ra.y < rb.y + rb.h &&
               rb.y < ra.y + ra.h);

  // One mesh folded onto itself in its own UVs: an error naming it.
  s.meshes[size_t(b)].uv1 = {{0, 0}, {0, 1}, {1, 1}, {1, 1}};
  s.meshes[size_t(b)].indices = {0, 1, 2, 0, 2, 1};
  try {
    build_layout(s, o);
    FAIL() << "overlapping TEXCOORD_1 accepted";
  } catch (const CookError& e) {
    EXPECT_NE(std::string(e.what()).find("'right'"), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("overlap"), std::string::npos) << e.what();
  }
}

TEST(Layout, LightmapScaleSetsANodesDensityAndExcludedMeshesGetNoTexels) {
  Scene s = props_scene();
  s.meshes[0].lightmap_scale = 0.5f;    // the 6 m floor at half density
  s.meshes[1].lightmap_exclude = true;  // the crate: an occluder only
  LayoutOptions o;
  o.texels_per_unit = 16.0f;
  const Layout l = build_layout(s, o);
  ASSERT_EQ(l.regions.size(), s.meshes.size() - 1);
  EXPECT_TRUE(l.meshes[1].indices.empty());
  for (const Region& r : l.regions) EXPECT_NE(r.meshes[0], 1);
  // The floor's chart: 6 m at 8 texels per metre, plus the borders.
  const Rect& floor = l.regions[0].rect;
  EXPECT_EQ(floor.w, 48 + 2 * o.border_texels);
  EXPECT_EQ(floor.h, 48 + 2 * o.border_texels);

  // The same node with TEXCOORD_1 of its own: its texels per metre follow the factor too.
  s.meshes[0].uv1 = {{0, 0}, {0, 1}, {1, 1}, {1, 0}};
  s.meshes[0].lightmap_scale = 2.0f;
  const Layout u = build_layout(s, o);
  EXPECT_EQ(u.uv1_regions, 1);
  EXPECT_NEAR(u.meshes[0].uv1_scale_offset.x * float(u.width), 6.0f * 16.0f * 2.0f, 1e-2f);

  // --unwrap always ignores it; --unwrap never refuses the meshes without one, by name.
  o.unwrap = UnwrapMode::kAlways;
  const Layout a = build_layout(s, o);
  EXPECT_EQ(a.uv1_regions, 0);
  EXPECT_FALSE(a.meshes[0].from_uv1);
  o.unwrap = UnwrapMode::kNever;
  try {
    build_layout(s, o);
    FAIL() << "--unwrap never accepted meshes without TEXCOORD_1";
  } catch (const CookError& e) {
    EXPECT_NE(std::string(e.what()).find("'pillar'"), std::string::npos) << e.what();
  }
  for (MeshInstance& m : s.meshes) m.lightmap_exclude = true;
  o.unwrap = UnwrapMode::kAuto;
  EXPECT_THROW(build_layout(s, o), CookError);
}

struct Baked {
  Layout layout;
  TexelSet texels;
  FloatImage map;
};

Baked bake(const Scene& s, float tpu) {
  LayoutOptions o;
  o.texels_per_unit = tpu;
  Baked b;
  b.layout = build_layout(s, o);
  auto tracer = make_embree_tracer(s);
  b.texels = build_texels(s, b.layout, tracer.get());
  Progress progress(true);
  Report report;
  BakeOptions bo;
  bo.quality = Quality::kDraft;
  b.map = bake_state(s, b.layout, b.texels, *tracer, StateSpec{}, bo, progress, report);
  finalize_map(b.map, s, b.layout, b.texels);
  return b;
}

TEST(Texels, SeamAcrossASmoothSurfaceShowsNoStep) {
  Scene s;
  add_cylinder(s, {0, 0, 0}, 0.5f, 2.0f, 32, "pillar");
  s.lights = {test::point_light("lamp", {2.0f, 1.0f, 0.3f}, 10.0f)};
  test::finish(s);
  const Baked b = bake(s, 24.0f);
  ASSERT_FALSE(b.layout.seams.empty());
  float peak = 0.0f;
  for (float v : b.map.data) peak = std::max(peak, v);
  ASSERT_GT(peak, 0.0f);
  // The filtered value where a renderer samples each side of the cut.
  float worst = 0.0f;
  for (const SeamEdge& e : b.layout.seams)
    for (float f : {0.1f, 0.3f, 0.5f, 0.7f, 0.9f}) {
      const float va = bilinear(b.map, e.a0 + (e.a1 - e.a0) * f, 0);
      const float vb = bilinear(b.map, e.b0 + (e.b1 - e.b0) * f, 0);
      worst = std::max(worst, std::abs(va - vb) / peak);
    }
  EXPECT_LT(worst, 0.01f);
}

void sealed_room_stays_dark(bool single_sided) {
  Scene s;
  if (single_sided) {
    // Six inward-facing quads with no thickness, meeting at the room's edges.
    auto inward = [&](glm::vec3 a, glm::vec3 b, glm::vec3 c, glm::vec3 d, const char* name) {
      const glm::vec3 centre = (a + b + c + d) / 4.0f;
      if (glm::dot(glm::cross(b - a, c - a), glm::vec3(0, 1.25f, 0) - centre) < 0) std::swap(b, d);
      test::add_quad(s, a, b, c, d, name);
    };
    const float x0 = -2, x1 = 2, y0 = 0, y1 = 2.5f, z0 = -2, z1 = 2;
    inward({x0, y0, z0}, {x1, y0, z0}, {x1, y0, z1}, {x0, y0, z1}, "floor");
    inward({x0, y1, z0}, {x1, y1, z0}, {x1, y1, z1}, {x0, y1, z1}, "ceiling");
    inward({x0, y0, z0}, {x0, y0, z1}, {x0, y1, z1}, {x0, y1, z0}, "west");
    inward({x1, y0, z0}, {x1, y0, z1}, {x1, y1, z1}, {x1, y1, z0}, "east");
    inward({x0, y0, z0}, {x1, y0, z0}, {x1, y1, z0}, {x0, y1, z0}, "north");
    inward({x0, y0, z1}, {x1, y0, z1}, {x1, y1, z1}, {x0, y1, z1}, "south");
  } else {
    test::add_closed_room(s, {-2, 0, -2}, {2, 2.5f, 2}, 0.2f, "room");
  }
  s.lights = {test::point_light("sun_lamp", {0.0f, 1.2f, 3.5f}, 500.0f),
              test::point_light("above", {0.5f, 4.0f, 0.5f}, 500.0f)};
  test::finish(s);
  const Baked b = bake(s, 12.0f);
  float outside = 0.0f;
  for (float v : b.map.data) outside = std::max(outside, v);
  if (!single_sided) {
    ASSERT_GT(outside, 1.0f);  // the outer walls are lit
  }
  // What a renderer samples on the visible inner surfaces, the corners and edges where walls meet
  // the floor and ceiling included: every point of every triangle that lies inside the room.
  float inside = 0.0f;
  size_t samples = 0;
  for (size_t m = 0; m < s.meshes.size(); ++m) {
    const MeshInstance& mesh = s.meshes[m];
    const MeshLayout& ml = b.layout.meshes[m];
    for (size_t t = 0; t < mesh.indices.size(); t += 3) {
      constexpr int kSteps = 16;
      for (int i = 0; i <= kSteps; ++i)
        for (int j = 0; i + j <= kSteps; ++j) {
          const float u = float(i) / kSteps, v = float(j) / kSteps, w = 1 - u - v;
          const glm::vec3 p = w * mesh.positions[mesh.indices[t]] +
                              u * mesh.positions[mesh.indices[t + 1]] +
                              v * mesh.positions[mesh.indices[t + 2]];
          if (std::abs(p.x) > 2.0001f || std::abs(p.z) > 2.0001f || p.y < -1e-4f || p.y > 2.5001f)
            continue;
          const glm::vec2 uv = w * ml.uv[ml.indices[t]] + u * ml.uv[ml.indices[t + 1]] +
                               v * ml.uv[ml.indices[t + 2]];
          ++samples;
          for (int c = 0; c < 3; ++c) inside = std::max(inside, bilinear(b.map, uv, c));
        }
    }
  }
  EXPECT_GT(samples, 1000u);
  for (size_t i = 0; i < b.texels.valid.size(); ++i) {
    const glm::vec3 p = b.texels.position[i];
    if (!b.texels.valid[i] || std::abs(p.x) > 1.999f || std::abs(p.z) > 1.999f || p.y < 0.001f ||
        p.y > 2.499f)
      continue;
    for (int c = 0; c < 3; ++c) inside = std::max(inside, b.map.data[i * 3 + size_t(c)]);
  }
  EXPECT_EQ(inside, 0.0f);
}

TEST(Texels, SealedRoomOfSolidWallsLitFromOutsideStaysDark) {
  sealed_room_stays_dark(false);
}

// Zero-thickness walls: texels straddling a corner must not sample the outside.
TEST(Texels, SealedRoomOfSingleSidedWallsLitFromOutsideStaysDark) {
  sealed_room_stays_dark(true);
}

TEST(Texels, EveryValidTexelLiesOnTheSurfaceWithAUnitNormal) {
  const Scene s = props_scene();
  LayoutOptions o;
  o.texels_per_unit = 16.0f;
  const Layout l = build_layout(s, o);
  const TexelSet t = build_texels(s, l, nullptr);
  size_t valid = 0;
  for (size_t i = 0; i < t.valid.size(); ++i) {
    if (!t.valid[i]) continue;
    ++valid;
    EXPECT_NEAR(glm::length(t.normal[i]), 1.0f, 1e-4f);
    const glm::vec3 p = t.position[i];
    EXPECT_TRUE(p.x >= -3.0001f && p.x <= 3.0001f && p.z >= -3.0001f && p.z <= 3.0001f &&
                p.y >= -1e-4f && p.y <= 1.2001f);
    EXPECT_GE(t.region[i], 0);
  }
  // The floor alone covers 36 m² at 16 texels/m.
  EXPECT_GT(valid, size_t(36 * 16 * 16));
  EXPECT_FALSE(t.fill.empty());
}

}  // namespace
}  // namespace lightpatch::cooker
