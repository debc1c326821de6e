// Hard cases stay numerically stable (DESIGN.md, "Numerically stable"): lights touching or inside
// surfaces, grazing lights, coplanar, overlapping, sliver and degenerate triangles, a 1 mm and a
// 10 km scene, a 10^4 cd light beside a 10^-2 cd one (semi-dynamic or static), albedo 0.99 in a
// closed room, a spot with inner = outer cone, zero-intensity lights, a semi-dynamic object
// touching a light.
//
// Each case is cooked in-process as `lightpatch cook` does (layout, texels, bake, finalize, pack)
// at draft quality on a small light map; then every float map, every decoded patch of the pack and
// every recomposition must be finite, and the CPU reference recomposition of the authored state,
// of each semi-dynamic light off and of each object hidden must match bake_state of that state
// within the pack's bar (relative RMSE 1%, as tests/gles/cooked_scene_test.cpp).
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <map>
#include <memory>
#include <string>
#include <vector>

#include "direct_light.h"
#include "lightpatch/cooker/bake.h"
#include "lightpatch/cooker/cook.h"
#include "lightpatch/cooker/pack_builder.h"
#include "lightpatch/cooker/texel_builder.h"
#include "lightpatch/cooker/tracer.h"
#include "lightpatch/cooker/unwrap.h"
#include "lightpatch/cpu_recomposer.h"
#include "lightpatch/pack_view.h"
#include "lightpatch/patch_decode.h"
#include "lightpatch/scene_state.h"
#include "test_scenes.h"

namespace lightpatch::cooker {
namespace {

// Relative RMSE of a recomposition against bake_state over the valid texels: the pack's bar.
constexpr double kBar = 0.01;
constexpr float kPi = 3.14159265358979f;

BakeOptions draft(bool indirect) {
  BakeOptions o;
  o.quality = Quality::kDraft;
  o.indirect = indirect;
  // Fewer gather rays than the draft preset keep the indirect cases fast under ASan; bake_state
  // uses the same rays, so recomposition stays exact to quantization.
  o.gather_rays = 32;
  return o;
}

void expect_finite(const FloatImage& m, const std::string& what) {
  size_t bad = 0;
  for (float v : m.data) bad += std::isfinite(v) ? 0 : 1;
  EXPECT_EQ(bad, 0u) << what << ": non-finite values";
}

struct Cooked {
  Scene scene;
  Layout layout;
  std::unique_ptr<Tracer> tracer;
  TexelSet texels;
  BakedMaps maps;
  BakeOptions options;
  Report report;
  std::vector<uint8_t> bytes;
  PackView pack;
};

// Every value of every float map, and every decoded texel of every patch, is finite.
void expect_all_finite(const Cooked& c) {
  expect_finite(c.maps.base, "base map");
  for (const FloatImage& m : c.maps.contribution) expect_finite(m, "contribution map");
  for (const ShadowMap& s : c.maps.shadows) expect_finite(s.map, "shadow map");
  for (const PairCorrectionMap& p : c.maps.pair_corrections)
    expect_finite(p.map, "pair correction");
  for (const StaticShadowMap& s : c.maps.static_shadows) expect_finite(s.map, "static shadow map");
  EXPECT_TRUE(std::isfinite(c.maps.output_step) && c.maps.output_step > 0.0f) << c.maps.output_step;
  size_t bad = 0;
  for (uint32_t i = 0; i < c.pack.patch_count(); ++i) {
    const pack::PatchRecord& p = c.pack.patch(i);
    EXPECT_TRUE(std::isfinite(p.scale) && p.scale > 0.0f) << "patch " << i << " scale " << p.scale;
    const pack::AtlasRecord& a = c.pack.atlas(p.atlas);
    const uint8_t* px = c.pack.atlas_pixels(p.atlas);
    const uint32_t level = pack::patch_level(p.flags);
    for (uint32_t y = 0; y < pack::patch_atlas_side(p.height, level); ++y) {
      for (uint32_t x = 0; x < pack::patch_atlas_side(p.width, level); ++x) {
        const size_t at = (size_t(p.atlas_y + y) * a.width + p.atlas_x + x) * 4;
        for (uint32_t k = 0; k < p.channel_count; ++k) {
          bad += std::isfinite(patch_decode(p, px[at + p.channel + k])) ? 0 : 1;
        }
      }
    }
  }
  EXPECT_EQ(bad, 0u) << "non-finite decoded patch texels";
}

// Cooks as `lightpatch cook` does (cooker/tool/cook_verbs.cpp), into a lightmap_size² page.
void cook(Cooked& c, int lightmap_size, const BakeOptions& options,
          const PackOptions& pack_options = PackOptions{}) {
  c.options = options;
  LayoutOptions lo;
  lo.lightmap_size = lightmap_size;
  lo.align = layout_align(options);  // charts on blocks: packs with bounce get an indirect map
  c.layout = build_layout(c.scene, lo);
  c.tracer = make_embree_tracer(c.scene);
  c.texels = build_texels(c.scene, c.layout, c.tracer.get());
  Progress progress(true);
  c.maps = bake_maps(c.scene, c.layout, c.texels, *c.tracer, options, progress, c.report);
  finalize_maps(c.maps, c.scene, c.layout, c.texels);
  c.bytes = build_pack(c.scene, c.layout, c.maps, pack_options, c.report);
  Error error;
  // Format only: a 10 km scene's irradiance is beyond the GLES target's half floats; these tests
  // check the float maps and the CPU recomposition.
  ASSERT_EQ(PackView::open(c.bytes.data(), c.bytes.size(), RecomposeLimits::format_only(), &c.pack,
                           &error),
            Status::kOk)
      << error.message;
  expect_all_finite(c);
}

struct NamedState {
  std::string name;
  StateSpec spec;
};

// The authored state, each semi-dynamic light off, each object hidden.
std::vector<NamedState> standard_states(const Scene& scene) {
  std::vector<NamedState> states{{"authored", {}}};
  for (const Light& l : scene.lights) {
    if (!l.semi_dynamic) continue;
    NamedState s{l.name + " off", {}};
    LightOverride o;
    o.has_on = true;
    o.on = false;
    s.spec.lights[l.name] = o;
    states.push_back(s);
  }
  for (const Object& o : scene.objects) {
    NamedState s{o.name + " hidden", {}};
    s.spec.objects[o.name] = false;
    states.push_back(s);
  }
  return states;
}

LightOverride intensity_override(float intensity) {
  LightOverride o;
  o.has_intensity = true;
  o.intensity = intensity;
  return o;
}

void apply_spec(const PackView& pack, const StateSpec& spec, SceneState* state) {
  state->reset_to_authored(pack);
  for (const auto& [name, o] : spec.lights) {
    const int32_t i = pack.find_light(name.data(), uint32_t(name.size()));
    ASSERT_GE(i, 0) << name;
    if (o.has_on) {
      ASSERT_EQ(state->set_light_on(uint32_t(i), o.on), Status::kOk);
    }
    if (o.has_color) {
      ASSERT_EQ(state->set_light_color(uint32_t(i), o.color), Status::kOk);
    }
    if (o.has_intensity) {
      ASSERT_EQ(state->set_light_intensity(uint32_t(i), o.intensity), Status::kOk);
    }
  }
  for (const auto& [name, visible] : spec.objects) {
    const int32_t i = pack.find_object(name.data(), uint32_t(name.size()));
    ASSERT_GE(i, 0) << name;
    ASSERT_EQ(state->set_object_visible(uint32_t(i), visible), Status::kOk);
  }
}

struct Compared {
  double rmse = 0.0;  // relative RMSE over valid texels
  double peak = 0.0;  // largest bake_state value over valid texels
  // Largest difference over the texels that bilinear filtering reads (the taps of every point of
  // every triangle's light-map box: the gutters a game samples at chart borders), relative to the
  // peak. (The valid texels' 8-neighbours over-count: valid texels are rasterized
  // conservatively, so their neighbours reach a ring of border no tap reads, which packs leave
  // out.)
  double worst_read = 0.0;
};

// Recomposes `spec` on the CPU reference (through the incremental path of `cpu`) and compares it
// with bake_state of the same state; both must be finite.
Compared compare_state(Cooked& c, CpuRecomposer& cpu, const NamedState& st) {
  Compared r;
  SceneState state;
  Error error;
  EXPECT_EQ(state.init(c.pack, &error), Status::kOk) << error.message;
  apply_spec(c.pack, st.spec, &state);
  EXPECT_EQ(cpu.apply(state), Status::kOk);
  Progress progress(true);
  Report report;
  FloatImage want =
      bake_state(c.scene, c.layout, c.texels, *c.tracer, st.spec, c.options, progress, report);
  finalize_map(want, c.scene, c.layout, c.texels);
  expect_finite(want, "bake_state " + st.name);
  const size_t n = size_t(cpu.width()) * cpu.height() * 3;
  size_t bad = 0;
  for (size_t i = 0; i < n; ++i) bad += std::isfinite(cpu.rgb()[i]) ? 0 : 1;
  EXPECT_EQ(bad, 0u) << "recomposition of " << st.name << " has non-finite texels";
  double err = 0.0, ref = 0.0;
  for (size_t t = 0; t < c.texels.valid.size(); ++t) {
    if (!c.texels.valid[t]) continue;
    for (size_t k = 0; k < 3; ++k) {
      const double w = want.data[t * 3 + k], g = cpu.rgb()[t * 3 + k];
      err += (g - w) * (g - w);
      ref += w * w;
      r.peak = std::max(r.peak, w);
    }
  }
  // A black reference (every light off) must be recomposed black.
  r.rmse = ref > 0.0 ? std::sqrt(err / ref) : (err > 0.0 ? 1.0 : 0.0);
  const int w = cpu.width(), h = int(cpu.height());
  // The texels bilinear filtering reads: the taps of every point of every triangle's light-map
  // box (a little more than the triangle's own reads).
  std::vector<uint8_t> reads(size_t(w) * size_t(h), 0);
  const glm::vec2 size{float(w), float(h)};
  for (const MeshLayout& ml : c.layout.meshes) {
    for (size_t t = 0; t + 2 < ml.indices.size(); t += 3) {
      glm::vec2 lo(1e30f), hi(-1e30f);
      for (size_t k = 0; k < 3; ++k) {
        lo = glm::min(lo, ml.uv[ml.indices[t + k]] * size);
        hi = glm::max(hi, ml.uv[ml.indices[t + k]] * size);
      }
      const int x0 = std::max(0, int(std::floor(lo.x - 0.5f)));
      const int x1 = std::min(w - 1, int(std::floor(hi.x - 0.5f)) + 1);
      const int y0 = std::max(0, int(std::floor(lo.y - 0.5f)));
      const int y1 = std::min(h - 1, int(std::floor(hi.y - 0.5f)) + 1);
      for (int y = y0; y <= y1; ++y)
        for (int x = x0; x <= x1; ++x) reads[c.texels.index(x, y)] = 1;
    }
  }
  for (int y = 0; y < h; ++y)
    for (int x = 0; x < w; ++x) {
      if (!reads[c.texels.index(x, y)]) continue;
      for (size_t k = 0; k < 3; ++k) {
        const size_t i = c.texels.index(x, y) * 3 + k;
        r.worst_read = std::max(r.worst_read, std::abs(double(cpu.rgb()[i]) - want.data[i]));
      }
    }
  if (r.peak > 0.0) r.worst_read /= r.peak;
  return r;
}

// Compares every state in `states` (in order, through one recomposer) against bake_state within
// `bar`; returns the worst relative RMSE.
double expect_states_match(Cooked& c, const std::vector<NamedState>& states, double bar = kBar) {
  CpuRecomposer cpu;
  Error error;
  EXPECT_EQ(cpu.init(c.pack, &error), Status::kOk) << error.message;
  double worst = 0.0;
  for (const NamedState& st : states) {
    const Compared r = compare_state(c, cpu, st);
    std::printf(
        "  %-24s relative RMSE %.4f%% (peak %.4g), largest difference where filtering "
        "reads %.3f%% of the peak\n",
        st.name.c_str(), 100.0 * r.rmse, r.peak, 100.0 * r.worst_read);
    EXPECT_LT(r.rmse, bar) << "state " << st.name;
    worst = std::max(worst, r.rmse);
  }
  return worst;
}

double expect_standard_states_match(Cooked& c) {
  return expect_states_match(c, standard_states(c.scene));
}

// A 4 m x 4 m floor facing +y.
void add_floor(Scene& s, float half = 2.0f, float y = 0.0f) {
  test::add_quad(s, {-half, y, -half}, {-half, y, half}, {half, y, half}, {half, y, -half},
                 "floor");
}

// ---------------------------------------------------------------------------------------------

TEST(HardCases, LightsOnAndInsideSurfacesCookAndRecompose) {
  Cooked c;
  Scene& s = c.scene;
  add_floor(s);
  test::add_box(s, {1.0f, 0.0f, 1.0f}, {1.6f, 1.2f, 1.6f}, "pillar");
  test::add_object_box(s, {-1.2f, 0.0f, -0.3f}, {-0.6f, 0.5f, 0.3f}, "crate");
  // On the floor (its centre a hair above the plane), inside the static pillar, and a soft light
  // whose sphere cuts the pillar's face.
  Light on_floor = test::point_light("on_floor", {0.0f, 1e-4f, 0.0f}, 5.0f, true);
  Light inside = test::point_light("inside", {1.3f, 0.6f, 1.3f}, 20.0f, true);
  Light cutting = test::point_light("cutting", {1.0f, 0.8f, 0.0f}, 20.0f, false);
  cutting.radius = 0.2f;
  s.lights = {on_floor, inside, cutting};
  test::finish(s);
  cook(c, 48, draft(false));
  ASSERT_FALSE(HasFatalFailure());
  // The light inside the pillar reaches nothing outside it (floor texels under the pillar, out
  // of the push-out's reach of its walls, see it: they are hidden, as the light is).
  int outside = 0;
  for (size_t t = 0; t < c.texels.valid.size(); ++t) {
    const glm::vec3 p = c.texels.position[t];
    if (!c.texels.valid[t] || (p.x > 0.95f && p.x < 1.65f && p.z > 0.95f && p.z < 1.65f)) continue;
    EXPECT_EQ(c.maps.contribution[1].data[t], 0.0f) << p.x << "," << p.y << "," << p.z;
    ++outside;
  }
  EXPECT_GT(outside, 500);
  const double worst = expect_standard_states_match(c);
  RecordProperty("worst_relative_rmse", std::to_string(worst));
}

TEST(HardCases, GrazingLightsStayWithinTheBar) {
  Cooked c;
  Scene& s = c.scene;
  add_floor(s);
  // A wedge on the floor rising 1° towards +x, 1 m long, 1.75 cm high at its back: its slope
  // faces the grazing sun at 1.1°, and its shadow runs over the rest of the floor. (A box would put
  // a face at 1000 lux beside a floor at 1.7 lux, and the floor would round away at the authored
  // exposure: a test of 8 bits, not of grazing rays.)
  s.objects.push_back(Object{"wedge", -1, {}});
  const float h = std::tan(kPi / 180.0f);
  const glm::vec3 a0(-1.2f, 0.0f, -0.8f), a1(-1.2f, 0.0f, 0.8f);  // front edge, on the floor
  const glm::vec3 b0(-0.2f, h, -0.8f), b1(-0.2f, h, 0.8f);        // back edge, on top
  const glm::vec3 c0(-0.2f, 0.0f, -0.8f), c1(-0.2f, 0.0f, 0.8f);  // back edge, on the floor
  MeshInstance w;
  w.name = "wedge";
  w.object = 0;
  auto face = [&](std::initializer_list<glm::vec3> ps) {
    const std::vector<glm::vec3> v(ps);
    const uint32_t base = uint32_t(w.positions.size());
    const glm::vec3 n = glm::normalize(glm::cross(v[1] - v[0], v[2] - v[0]));
    for (const glm::vec3& q : v) {
      w.positions.push_back(q);
      w.normals.push_back(n);
    }
    for (uint32_t i = 1; i + 1 < v.size(); ++i)
      w.indices.insert(w.indices.end(), {base, base + i, base + i + 1});
  };
  face({a0, a1, b1, b0});  // slope, facing up and towards -x
  face({c0, b0, b1, c1});  // back, facing +x
  face({a0, b0, c0});      // side, facing -z
  face({a1, c1, b1});      // side, facing +z
  face({a0, c0, c1, a1});  // bottom, facing -y
  s.meshes.push_back(std::move(w));
  s.objects[0].meshes.push_back(int(s.meshes.size()) - 1);
  // A point light 1 mm above the floor at its edge, a sun 0.1° above the horizon, and a static
  // spot 2 cm above the floor aimed along it.
  const float elevation = 0.1f * kPi / 180.0f;  // 89.9° from the floor's normal
  const glm::vec3 sun_dir(std::cos(elevation), -std::sin(elevation), 0.0f);
  s.lights = {
      test::point_light("low", {-1.9f, 1e-3f, 0.5f}, 20.0f, true),
      test::directional_light("sunset", sun_dir, 1000.0f, true),
      test::spot_light("skim", {1.9f, 0.02f, -1.9f}, {-1.0f, -0.01f, 1.0f}, 10.0f, 0.2f, 0.4f)};
  test::finish(s);
  cook(c, 48, draft(false));
  ASSERT_FALSE(HasFatalFailure());
  // Where the wedge's shadow does not fall, the sun gives E = lux * sin(elevation) on the floor.
  const FloatImage& sun = c.maps.contribution[1];
  int lit = 0;
  float worst = 0.0f;
  for (size_t t = 0; t < c.texels.valid.size(); ++t) {
    const glm::vec3 p = c.texels.position[t], n = c.texels.normal[t];
    if (!c.texels.valid[t] || n.y < 0.99f || p.y > 1e-3f || std::fabs(p.z) < 0.9f) continue;
    const float want = std::sin(elevation);
    worst = std::max(
        worst,
        std::fabs(sun.at(int(t % size_t(sun.width)), int(t / size_t(sun.width)), 0) - want) / want);
    ++lit;
  }
  EXPECT_GT(lit, 100);
  EXPECT_LT(worst, 0.01f);
  std::printf("grazing sun on the floor: max relative error %.3g over %d texels\n", worst, lit);
  std::vector<NamedState> states = standard_states(s);
  NamedState bright{"sunset at 1e4 lux", {}};
  bright.spec.lights["sunset"] = intensity_override(1e4f);
  states.push_back(bright);
  RecordProperty("worst_relative_rmse", std::to_string(expect_states_match(c, states)));
}

// A static mesh of one triangle list with +y normals.
int add_triangles(Scene& s, const std::vector<glm::vec3>& positions,
                  const std::vector<uint32_t>& indices, const std::string& name) {
  MeshInstance m;
  m.name = name;
  m.positions = positions;
  m.normals.assign(positions.size(), glm::vec3(0.0f, 1.0f, 0.0f));
  m.indices = indices;
  s.meshes.push_back(std::move(m));
  return int(s.meshes.size()) - 1;
}

TEST(HardCases, CoplanarAndOverlappingTrianglesCookAndRecompose) {
  Cooked c;
  Scene& s = c.scene;
  add_floor(s);
  // The same floor again (coincident), a rug overlapping half of it in its plane, the floor
  // facing down in its plane, and two static boxes that interpenetrate.
  test::add_quad(s, {-2, 0, -2}, {-2, 0, 2}, {2, 0, 2}, {2, 0, -2}, "floor_twin");
  test::add_quad(s, {-1, 0, -1}, {-1, 0, 3}, {1, 0, 3}, {1, 0, -1}, "rug");
  test::add_quad(s, {-2, 0, -2}, {2, 0, -2}, {2, 0, 2}, {-2, 0, 2}, "floor_under");
  test::add_box(s, {0.8f, 0.0f, 0.8f}, {1.4f, 0.6f, 1.4f}, "box_a");
  test::add_box(s, {1.1f, 0.3f, 1.1f}, {1.7f, 0.9f, 1.7f}, "box_b");
  test::add_object_box(s, {-1.0f, 0.0f, -1.0f}, {-0.5f, 0.5f, -0.5f}, "crate");
  s.lights = {test::point_light("lamp", {0.2f, 2.0f, 0.1f}, 10.0f, true),
              test::point_light("fill", {-1.5f, 1.5f, 1.5f}, 3.0f, false)};
  test::finish(s);
  cook(c, 64, draft(true));
  ASSERT_FALSE(HasFatalFailure());
  RecordProperty("worst_relative_rmse", std::to_string(expect_standard_states_match(c)));
}

TEST(HardCases, SliverAndDegenerateTrianglesCookAndRecompose) {
  Cooked c;
  Scene& s = c.scene;
  add_floor(s);
  // Above the floor, a strip of valid triangles mixed with zero-area ones (a repeated index,
  // three collinear vertices, all three at one point) and slivers 1e-5 m wide and 2 m long.
  std::vector<glm::vec3> p = {
      {-1.0f, 0.5f, -1.0f},        {-1.0f, 0.5f, 1.0f}, {1.0f, 0.5f, 1.0f},  {1.0f, 0.5f, -1.0f},
      {0.0f, 0.5f, 0.0f},          {0.5f, 0.5f, 0.5f},  {-1.0f, 0.5f, 1.2f}, {1.0f, 0.5f, 1.2f},
      {-1.0f, 0.5f, 1.2f + 1e-5f}, {0.3f, 0.5f, 0.3f}};
  std::vector<uint32_t> idx = {0, 1, 2,   // valid, facing +y
                               0, 0, 3,   // repeated index
                               0, 4, 2,   // collinear
                               9, 9, 9,   // one point
                               0, 2, 3,   // valid
                               6, 8, 7};  // sliver
  add_triangles(s, p, idx, "shelf");
  // Slivers as a semi-dynamic object: a fan of thin triangles.
  Object o;
  o.name = "comb";
  s.objects.push_back(o);
  MeshInstance comb;
  comb.name = "comb";
  comb.object = 0;
  for (int i = 0; i < 8; ++i) {
    const float x = -0.8f + 0.2f * float(i);
    const uint32_t b = uint32_t(comb.positions.size());
    comb.positions.insert(comb.positions.end(),
                          {{x, 1.0f, -0.8f}, {x + 1e-5f, 1.0f, -0.8f}, {x, 1.0f, 0.8f}});
    comb.indices.insert(comb.indices.end(), {b, b + 2, b + 1});
    // Every other tooth also carries a zero-area triangle.
    if (i % 2 == 0) comb.indices.insert(comb.indices.end(), {b, b, b + 2});
  }
  comb.normals.assign(comb.positions.size(), glm::vec3(0.0f, 1.0f, 0.0f));
  s.meshes.push_back(std::move(comb));
  s.objects[0].meshes.push_back(int(s.meshes.size()) - 1);
  s.lights = {test::point_light("lamp", {0.1f, 2.5f, 0.2f}, 12.0f, true),
              test::point_light("side", {1.8f, 0.3f, 1.8f}, 2.0f, false)};
  test::finish(s);
  cook(c, 64, draft(true));
  ASSERT_FALSE(HasFatalFailure());
  RecordProperty("worst_relative_rmse", std::to_string(expect_standard_states_match(c)));
}

TEST(HardCases, ThinPlankThroughAnObjectIsDarkWhereverFilteringReadsIt) {
  // A plank 2 cm thick (charts one or two texels wide, mostly border) passing through a
  // semi-dynamic chest, under a static spot and a semi-dynamic lamp; the chest hidden, then shown
  // again. Inside the chest the plank is dark in every state the chest is visible in: its
  // recomposition must be, out to the gutter texels a game's bilinear filter reads (where the
  // static light's shadow of the chest was left unfinalized: 7.8 where bake-state gave 0).
  Cooked c;
  Scene& s = c.scene;
  add_floor(s);
  test::add_object_box(s, {-0.4f, 0.0f, -0.4f}, {0.4f, 0.8f, 0.4f}, "chest");
  test::add_box(s, {-1.8f, 0.39f, -0.06f}, {1.8f, 0.41f, 0.06f}, "plank");
  s.lights = {test::spot_light("spot", {0.3f, 2.5f, 0.8f}, {0, -1, 0}, 30.0f, 0.6f, 1.2f),
              test::point_light("lamp", {-0.6f, 1.6f, -0.5f}, 10.0f, true)};
  test::finish(s);
  cook(c, 160, draft(false));
  ASSERT_FALSE(HasFatalFailure());
  std::vector<NamedState> states = standard_states(s);
  states.push_back({"chest shown again", {}});
  CpuRecomposer cpu;
  Error error;
  ASSERT_EQ(cpu.init(c.pack, &error), Status::kOk) << error.message;
  for (const NamedState& st : states) {
    const Compared r = compare_state(c, cpu, st);
    std::printf(
        "  %-24s relative RMSE %.4f%%, largest difference where filtering reads %.3f%% "
        "of the peak %.4g\n",
        st.name.c_str(), 100.0 * r.rmse, 100.0 * r.worst_read, r.peak);
    EXPECT_LT(r.rmse, kBar) << st.name;
    EXPECT_LT(r.worst_read, 0.02) << st.name;
  }
}

// Light-map UVs of each box's own in [0,1]: its 6 faces in a 3 x 2 grid of cells (the face's
// corners in add_box order).
void box_texcoord1(MeshInstance& m) {
  m.uv1.resize(m.positions.size());
  const glm::vec2 corner[4] = {{0, 0}, {1, 0}, {1, 1}, {0, 1}};
  for (size_t v = 0; v < m.positions.size(); ++v) {
    const size_t face = v / 4;
    const glm::vec2 cell(float(face % 3) / 3.0f, float(face / 3) / 2.0f);
    m.uv1[v] = cell + (glm::vec2(0.03f) + corner[v % 4] * 0.27f) * glm::vec2(1.0f, 1.5f);
  }
}

TEST(HardCases, PerMeshTexcoord1ScenesRecomposeLikeBakeState) {
  // Every mesh with light-map UVs of its own over the unit square, as Blender's Lightmap Pack,
  // Unity and Godot write them: each placed by a scale and offset; bounce light on.
  Cooked c;
  Scene& s = c.scene;
  add_floor(s);
  s.meshes[0].uv1 = {{0, 0}, {0, 1}, {1, 1}, {1, 0}};
  box_texcoord1(
      s.meshes[size_t(test::add_box(s, {0.8f, 0.0f, 0.8f}, {1.4f, 0.9f, 1.4f}, "cupboard"))]);
  const int chest = test::add_object_box(s, {-1.0f, 0.0f, -0.6f}, {-0.4f, 0.5f, 0.0f}, "chest");
  box_texcoord1(s.meshes[size_t(s.objects[size_t(chest)].meshes[0])]);
  s.lights = {test::point_light("lamp", {0.2f, 2.0f, 0.1f}, 10.0f, true),
              test::spot_light("spot", {-1.5f, 2.5f, 1.5f}, glm::normalize(glm::vec3(1, -2, -1)),
                               20.0f, 0.4f, 0.8f)};
  test::finish(s);
  cook(c, 96, draft(true));
  ASSERT_FALSE(HasFatalFailure());
  EXPECT_EQ(c.layout.uv1_regions, 3);
  EXPECT_FALSE(c.layout.verbatim_uv1);
  RecordProperty("worst_relative_rmse", std::to_string(expect_standard_states_match(c)));
}

// ---------------------------------------------------------------------------------------------
// One room at k times its size: a floor, a back wall, a crate, a semi-dynamic point light and a
// static spot (both in candela), so every map, indirect light included, scales by 1 / k².

void scaled_room(Scene& s, float k) {
  test::add_quad(s, glm::vec3(-2, 0, -2) * k, glm::vec3(-2, 0, 2) * k, glm::vec3(2, 0, 2) * k,
                 glm::vec3(2, 0, -2) * k, "floor");
  test::add_quad(s, glm::vec3(-2, 0, -2) * k, glm::vec3(2, 0, -2) * k, glm::vec3(2, 2, -2) * k,
                 glm::vec3(-2, 2, -2) * k, "back");
  test::add_object_box(s, glm::vec3(-0.5f, 0.0f, -0.5f) * k, glm::vec3(0.1f, 0.6f, 0.1f) * k,
                       "crate");
  s.lights = {test::point_light("lamp", glm::vec3(0.4f, 1.8f, 0.3f) * k, 10.0f, true),
              test::spot_light("spot", glm::vec3(1.5f, 1.5f, 1.0f) * k, {-1.0f, -1.0f, -1.0f},
                               20.0f, 0.3f, 0.7f)};
  test::finish(s);
}

// Relative RMSE of k² * scaled against unit over the texels valid in both layouts.
double scaled_rmse(const FloatImage& scaled, const FloatImage& unit, const TexelSet& a,
                   const TexelSet& b, float k2) {
  double err = 0.0, ref = 0.0;
  for (size_t t = 0; t < a.valid.size(); ++t) {
    if (!a.valid[t] || !b.valid[t]) continue;
    for (int ch = 0; ch < unit.channels; ++ch) {
      const double u = unit.data[t * size_t(unit.channels) + size_t(ch)];
      const double v = double(scaled.data[t * size_t(scaled.channels) +
                                          size_t(std::min(ch, scaled.channels - 1))]) *
                       k2;
      err += (v - u) * (v - u);
      ref += u * u;
    }
  }
  return ref > 0.0 ? std::sqrt(err / ref) : std::sqrt(err);
}

TEST(HardCases, MillimetreAndTenKilometreScenesScaleAsPhysicsSays) {
  Cooked unit;
  scaled_room(unit.scene, 1.0f);
  cook(unit, 48, draft(true));
  ASSERT_FALSE(HasFatalFailure());
  for (const float k : {1e-3f, 1e4f}) {
    SCOPED_TRACE("scale " + std::to_string(k));
    Cooked c;
    scaled_room(c.scene, k);
    cook(c, 48, draft(true));
    ASSERT_FALSE(HasFatalFailure());
    ASSERT_EQ(c.layout.width, unit.layout.width);
    ASSERT_EQ(c.layout.height, unit.layout.height);
    size_t both = 0, either = 0;
    for (size_t t = 0; t < c.texels.valid.size(); ++t) {
      both += c.texels.valid[t] && unit.texels.valid[t];
      either += c.texels.valid[t] || unit.texels.valid[t];
    }
    EXPECT_GT(double(both), 0.98 * double(either)) << "the layout should not depend on the scale";
    // The same candela at k times the distance: irradiance times 1 / k².
    const float k2 = k * k;
    const double base = scaled_rmse(c.maps.base, unit.maps.base, c.texels, unit.texels, k2);
    ASSERT_EQ(c.maps.contribution.size(), 1u);
    const double contribution =
        scaled_rmse(c.maps.contribution[0], unit.maps.contribution[0], c.texels, unit.texels, k2);
    ASSERT_EQ(c.maps.shadows.size(), unit.maps.shadows.size());
    double shadow = 0.0;
    for (size_t i = 0; i < c.maps.shadows.size(); ++i) {
      shadow = std::max(shadow, scaled_rmse(c.maps.shadows[i].map, unit.maps.shadows[i].map,
                                            c.texels, unit.texels, k2));
    }
    std::printf(
        "scale %g: k² B vs unit B %.4f%%, k² C %.4f%%, k² S %.4f%%; output step %.4g vs %.4g\n",
        double(k), 100.0 * base, 100.0 * contribution, 100.0 * shadow,
        double(c.maps.output_step * k2), double(unit.maps.output_step));
    EXPECT_LT(base, 0.02);
    EXPECT_LT(contribution, 0.02);
    EXPECT_LT(shadow, 0.05);
    EXPECT_NEAR(c.maps.output_step * k2, unit.maps.output_step, 0.02f * unit.maps.output_step);
    // Float rounding at 10 km flips the odd gather ray that grazes an edge; a patch whose peak
    // sits at the significance threshold may come or go with it.
    EXPECT_NEAR(double(c.pack.patch_count()), double(unit.pack.patch_count()), 1.0);
    expect_standard_states_match(c);
  }
}

// A room lit by a 10^4 cd flood (semi-dynamic) and a 10^-2 cd ember, semi-dynamic or static,
// with a crate; cooks it and returns the standard states plus the ember alone without the crate.
std::vector<NamedState> cook_flood_and_ember(Cooked& c, bool ember_semi_dynamic) {
  Scene& s = c.scene;
  add_floor(s);
  test::add_quad(s, {-2, 0, -2}, {2, 0, -2}, {2, 2, -2}, {-2, 2, -2}, "back");
  test::add_object_box(s, {-0.3f, 0.0f, -0.3f}, {0.3f, 0.5f, 0.3f}, "crate");
  s.lights = {test::point_light("flood", {-1.0f, 2.0f, 0.5f}, 1e4f, true),
              test::point_light("ember", {1.0f, 1.0f, -0.5f}, 1e-2f, ember_semi_dynamic)};
  test::finish(s);
  cook(c, 48, draft(true));
  std::vector<NamedState> states = standard_states(s);
  NamedState dim_alone{"ember alone, no crate", {}};
  dim_alone.spec.lights["flood"].has_on = true;
  dim_alone.spec.lights["flood"].on = false;
  dim_alone.spec.objects["crate"] = false;
  states.push_back(dim_alone);
  return states;
}

TEST(HardCases, BrightAndDimLightsBothKeepTheirPrecision) {
  Cooked c;
  const std::vector<NamedState> states = cook_flood_and_ember(c, true);
  ASSERT_FALSE(HasFatalFailure());
  ASSERT_GE(c.pack.contribution_group(1), 0) << "the dim light lost its patches";
  RecordProperty("worst_relative_rmse", std::to_string(expect_states_match(c, states)));
}

// A static light far dimmer than the semi-dynamic ones sets none of the authored exposure, but it
// is all that is left when they are off: the base map and the static shadows keep it to one 8-bit
// step of the static light's own peak, as a dim semi-dynamic light keeps its own.
TEST(HardCases, FaintStaticLightSurvivesTheBrightLightsOff) {
  Cooked c;
  const std::vector<NamedState> states = cook_flood_and_ember(c, false);
  ASSERT_FALSE(HasFatalFailure());
  ASSERT_GE(c.pack.base_group(), 0) << "the static light lost the base map";
  RecordProperty("worst_relative_rmse", std::to_string(expect_states_match(c, states)));
}

// A torch on a wall, its bracket's end 3 cm from the light, the bracket one node with the wall
// (content tools export a room so): the bracket's end gets thousands of output steps, the wall
// a metre away a few, and the two share a tile of the contribution map. Linear 8-bit codes of the
// tile's peak stepped by more than the wall's light, which the pack rounded to 0 (the small inn:
// its dining room's wall beside the torch 1.9 -> 0.13 against bake_state). The tile is cut where
// its light spans more than its codes hold (quantize.h, split_for_range), so every wall texel of
// a few steps keeps its light.
TEST(HardCases, ATorchBracketBesideItsLightKeepsTheWallsLight) {
  Cooked c;
  Scene& s = c.scene;
  add_floor(s);
  const int wall = test::add_quad(s, {-2, 0, -2}, {2, 0, -2}, {2, 2, -2}, {-2, 2, -2}, "wall");
  const int bracket =
      test::add_box(s, {-0.02f, 0.98f, -2.0f}, {0.02f, 1.02f, -1.9f}, "wall_bracket");
  s.meshes[size_t(wall)].node_index = 0;
  s.meshes[size_t(bracket)].node_index = 0;  // one node, one region: the bracket's and wall's
  s.lights = {test::point_light("torch", {0.0f, 1.0f, -1.87f}, 3.0f, true)};
  test::finish(s);
  cook(c, 64, draft(false));
  ASSERT_FALSE(HasFatalFailure());
  const nlohmann::json& enc = c.report.root()["pack"]["encoding"];
  EXPECT_GE(enc.value("patches_cut_for_range", 0), 1) << "no tile spans more than 8 bits here";
  CpuRecomposer cpu;
  Error error;
  ASSERT_EQ(cpu.init(c.pack, &error), Status::kOk) << error.message;
  SceneState state;
  ASSERT_EQ(state.init(c.pack, &error), Status::kOk) << error.message;
  ASSERT_EQ(cpu.apply(state), Status::kOk);
  Progress progress(true);
  Report report;
  FloatImage want =
      bake_state(c.scene, c.layout, c.texels, *c.tracer, StateSpec{}, c.options, progress, report);
  finalize_map(want, c.scene, c.layout, c.texels);
  // Every wall texel of at least 4 output steps within a quarter of its light, and the wall's
  // light as a whole within 2 %.
  const double step = c.maps.output_step;
  int judged = 0, lost = 0;
  double sum_want = 0.0, sum_got = 0.0, bracket_peak = 0.0;
  for (size_t t = 0; t < c.texels.valid.size(); ++t) {
    if (!c.texels.valid[t]) continue;
    double w = 0.0, g = 0.0;
    for (size_t k = 0; k < 3; ++k) {
      w = std::max(w, double(want.data[t * 3 + k]));
      g = std::max(g, double(cpu.rgb()[t * 3 + k]));
    }
    if (c.texels.mesh[t] == bracket) bracket_peak = std::max(bracket_peak, w);
    if (c.texels.mesh[t] != wall || w < 4.0 * step) continue;
    ++judged;
    lost += std::fabs(g - w) > 0.25 * w ? 1 : 0;
    sum_want += w;
    sum_got += g;
  }
  std::printf(
      "  bracket peak %.0f steps; %d wall texels of 4 steps or more, %d off by over 25 %%; "
      "their light %.4f of bake_state's\n",
      bracket_peak / step, judged, lost, sum_got / sum_want);
  EXPECT_GT(bracket_peak, 1000.0 * step) << "the bracket should take thousands of steps";
  EXPECT_GT(judged, 100);
  EXPECT_EQ(lost, 0);
  EXPECT_NEAR(sum_got / sum_want, 1.0, 0.02);
}

// A closed grey room of albedo `albedo` with a crate, a semi-dynamic lamp and a static fill light,
// cooked at draft. Light bounces hundreds of times at an albedo near 1: fewer rays keep it fast.
void cook_closed_room(Cooked& c, float albedo) {
  Scene& s = c.scene;
  Material grey;
  grey.albedo = glm::vec3(albedo);
  s.materials = {grey};
  test::add_closed_room(s, {-2, 0, -2}, {2, 2.5f, 2}, 0.1f, "room");
  test::add_object_box(s, {-0.5f, 0.0f, -0.5f}, {0.3f, 0.7f, 0.3f}, "crate");
  s.lights = {test::point_light("lamp", {0.6f, 2.0f, 0.4f}, 5.0f, true),
              test::point_light("fill", {-1.2f, 1.0f, 1.1f}, 1.0f, false)};
  test::finish(s);
  BakeOptions o = draft(true);
  o.gather_rays = 16;
  cook(c, 48, o);
}

TEST(HardCases, AlbedoNearOneInAClosedRoomCookAndRecompose) {
  Cooked c;
  cook_closed_room(c, 0.99f);
  ASSERT_FALSE(HasFatalFailure());
  ASSERT_EQ(c.maps.contribution.size(), 1u);
  EXPECT_EQ(c.maps.contribution[0].channels, 3) << "bounce light should be baked";
  RecordProperty("worst_relative_rmse", std::to_string(expect_standard_states_match(c)));
}

// glTF's default material is white, and Blender writes meshes without a material with it: a
// closed room of albedo 1 keeps its light forever. The albedo light reflects with is at most
// 0.99, so the bounce series converges and recomposition equals bake_state (21 % apart on such a
// room exported from Blender 3.4 before).
TEST(HardCases, AlbedoOneInAClosedRoomConverges) {
  Cooked c;
  cook_closed_room(c, 1.0f);
  ASSERT_FALSE(HasFatalFailure());
  RecordProperty("worst_relative_rmse", std::to_string(expect_standard_states_match(c)));
}

// Two rooms joined by a doorway: the lamp's room is lit directly, the other by bounce only.
void two_rooms(Scene& s) {
  Material wall;
  wall.albedo = glm::vec3(0.8f, 0.7f, 0.6f);
  s.materials = {wall};
  test::add_closed_room(s, {-4, 0, -2}, {4, 2.5f, 2}, 0.1f, "room");
  test::add_box(s, {-0.05f, 0.0f, -2.0f}, {0.05f, 2.5f, 1.0f}, "partition");
  test::add_object_box(s, {-2.5f, 0.0f, -0.5f}, {-1.7f, 0.7f, 0.3f}, "crate");
  s.lights = {test::point_light("lamp", {-2.0f, 2.0f, 0.4f}, 5.0f, true),
              test::point_light("fill", {-3.2f, 1.0f, 1.1f}, 1.0f, false)};
  test::finish(s);
}

// Bounce light on 2 x 2 blocks (--indirect-scale 2), every light group stored split: the pack's
// indirect map holds the bounce light, the light map the rest (negative where the indirect map's
// filter blends across a crease), and every state recomposes like bake_state (max(L + I, 0)).
TEST(HardCases, IndirectMapHoldsTheBounceLightAndRecomposesLikeBakeState) {
  Cooked c;
  two_rooms(c.scene);
  BakeOptions o = draft(true);
  o.indirect_scale = 2;
  PackOptions po;
  po.always_split = true;
  cook(c, 128, o, po);
  ASSERT_FALSE(HasFatalFailure());
  EXPECT_EQ(c.layout.align, 2);
  ASSERT_EQ(c.pack.indirect_scale(), 2u);
  uint64_t texels[2] = {0, 0};
  for (uint32_t i = 0; i < c.pack.patch_count(); ++i) {
    const pack::PatchRecord& p = c.pack.patch(i);
    texels[p.target] += uint64_t(p.width) * p.height;
  }
  std::printf("patch texels: light map %llu, indirect map %llu\n", (unsigned long long)texels[0],
              (unsigned long long)texels[1]);
  EXPECT_GT(texels[1], 0u);
  RecordProperty("worst_relative_rmse", std::to_string(expect_standard_states_match(c)));
}

// A pack's atlas bytes (RGBA8, every atlas whole).
uint64_t atlas_bytes(const PackView& v) {
  uint64_t b = 0;
  for (uint32_t a = 0; a < v.atlas_count(); ++a)
    b += uint64_t(v.atlas(a).width) * v.atlas(a).height * 4;
  return b;
}

// The most texels a light's change draws: its groups' patches (C_l, S_ol, pair corrections).
uint64_t costliest_light_change(const PackView& v) {
  std::map<uint32_t, uint64_t> per_light;
  for (uint32_t g = 0; g < v.group_count(); ++g) {
    const pack::GroupRecord& gr = v.group(g);
    if (gr.light == pack::kNone16) continue;
    for (uint32_t k = gr.first_patch; k < gr.first_patch + gr.patch_count; ++k)
      per_light[gr.light] += uint64_t(v.patch(k).width) * v.patch(k).height;
  }
  uint64_t most = 0;
  for (const auto& [light, texels] : per_light) most = std::max(most, texels);
  return most;
}

// Two packs of the same scene recomposed in one state, at every valid texel: relative RMSE and
// signed bias of `b` against `a`, and the largest difference in output steps beyond 1 % of the
// texel (the 8-bit codes' own rounding grows with the patch's brightest texel, and each pack
// rounds its patches: counted apart).
struct PackDifference {
  double rmse = 0.0, bias = 0.0, worst_steps = 0.0;
};

PackDifference compare_packs(const PackView& pa, const PackView& pb, const NamedState& st,
                             const TexelSet& texels, double step) {
  PackDifference r;
  CpuRecomposer a, b;
  SceneState sa, sb;
  Error error;
  EXPECT_EQ(a.init(pa, &error), Status::kOk);
  EXPECT_EQ(b.init(pb, &error), Status::kOk);
  EXPECT_EQ(sa.init(pa, &error), Status::kOk);
  EXPECT_EQ(sb.init(pb, &error), Status::kOk);
  apply_spec(pa, st.spec, &sa);
  apply_spec(pb, st.spec, &sb);
  EXPECT_EQ(a.apply(sa), Status::kOk);
  EXPECT_EQ(b.apply(sb), Status::kOk);
  double diff = 0.0, sum = 0.0, d2 = 0.0, r2 = 0.0;
  for (size_t t = 0; t < texels.valid.size(); ++t) {
    if (!texels.valid[t]) continue;
    for (size_t k = 0; k < 3; ++k) {
      const double x = a.rgb()[t * 3 + k], y = b.rgb()[t * 3 + k];
      r.worst_steps =
          std::max(r.worst_steps, std::max(0.0, std::fabs(y - x) - 0.01 * std::fabs(x)) / step);
      diff += y - x;
      sum += x;
      d2 += (y - x) * (y - x);
      r2 += x * x;
    }
  }
  r.rmse = r2 > 0.0 ? std::sqrt(d2 / r2) : 0.0;
  r.bias = sum > 0.0 ? diff / sum : 0.0;
  return r;
}

// Light-map patches at the coarsest level their own error allows (PackOptions::max_patch_level,
// the default) against every patch texel for texel: fewer atlas bytes, the bounce light's
// patches magnified, and every state recomposes like bake_state and within a few output steps of
// the level-0 pack at every texel, with no sign to the difference.
TEST(HardCases, LightMapPatchLevelsSaveBytesAndRecomposeLikeBakeState) {
  Cooked full, levels;
  two_rooms(full.scene);
  two_rooms(levels.scene);
  PackOptions po0;
  po0.max_patch_level = 0;
  // The level tolerance alone, bounce light's texels too (the parts' test has the bounce
  // tolerance's own bars).
  PackOptions po;
  po.bounce_tolerance = po.level_tolerance;
  cook(full, 128, draft(true), po0);
  cook(levels, 128, draft(true), po);
  ASSERT_FALSE(HasFatalFailure());
  uint32_t magnified[2] = {0, 0};
  for (int k = 0; k < 2; ++k) {
    const PackView& v = k ? levels.pack : full.pack;
    for (uint32_t i = 0; i < v.patch_count(); ++i)
      magnified[k] += pack::patch_level(v.patch(i).flags) > 0 ? 1 : 0;
  }
  std::printf("atlas bytes: level 0 %llu, levels %llu (%.3fx); magnified patches %u of %u\n",
              (unsigned long long)atlas_bytes(full.pack),
              (unsigned long long)atlas_bytes(levels.pack),
              double(atlas_bytes(levels.pack)) / double(atlas_bytes(full.pack)), magnified[1],
              levels.pack.patch_count());
  EXPECT_EQ(magnified[0], 0u);
  EXPECT_GT(magnified[1], 0u);
  EXPECT_LT(double(atlas_bytes(levels.pack)), 0.7 * double(atlas_bytes(full.pack)));  // 0.598x
  expect_standard_states_match(full);
  expect_standard_states_match(levels);
  // The two packs' recompositions, state by state, in output steps at every valid texel.
  const double step = full.maps.output_step;
  ASSERT_EQ(step, levels.maps.output_step);
  for (const NamedState& st : standard_states(full.scene)) {
    const PackDifference d = compare_packs(full.pack, levels.pack, st, full.texels, step);
    std::printf(
        "  %-24s levels against level 0: relative RMSE %.4f%%, bias %+.4f%%, largest "
        "texel difference %.2f output steps beyond 1 %% of the texel\n",
        st.name.c_str(), 100.0 * d.rmse, 100.0 * d.bias, d.worst_steps);
    EXPECT_LT(d.rmse, 0.005) << st.name;
    EXPECT_LT(std::fabs(d.bias), 0.002) << st.name;
    EXPECT_LT(d.worst_steps, 4.0) << st.name;
  }
}

// Pieces whose light has one colour stored as 1 channel and a tint, and those of two colours as 2
// channels and two tints (PackOptions::tint_pieces): in the two rooms, whose walls tint the bounce
// light (the second room is lit by bounce alone), fewer atlas bytes than the pack that keeps them
// in 3 channels, and the same light within the tints' bound (a quarter of an output step) and the
// 8-bit codes at every valid texel, in every standard state; both within the pack's bar of
// bake_state.
TEST(HardCases, PatchesWithATintSaveBytesAndRecomposeLikeThreeChannels) {
  Cooked colour, tinted;
  two_rooms(colour.scene);
  two_rooms(tinted.scene);
  // Patches at level 0: the colour decision weighs the cuts where patches take levels, so only
  // without levels are both packs cut alike and compared like for like.
  PackOptions po, pt;
  po.tint_pieces = false;
  po.max_patch_level = pt.max_patch_level = 0;
  cook(colour, 128, draft(true), po);
  cook(tinted, 128, draft(true), pt);
  ASSERT_FALSE(HasFatalFailure());
  // Patches with a tint, and the atlas channel-texels the patches take (the atlases of so small
  // a pack round to the same size).
  uint32_t with_tint[2] = {0, 0}, two_channels = 0;
  uint64_t channel_texels[2] = {0, 0};
  for (int k = 0; k < 2; ++k) {
    const PackView& v = k ? tinted.pack : colour.pack;
    for (uint32_t i = 0; i < v.patch_count(); ++i) {
      const pack::PatchRecord& p = v.patch(i);
      with_tint[k] += pack::patch_has_tint(p);
      two_channels += k == 1 && p.channel_count == 2 ? 1 : 0;
      const uint32_t level = pack::patch_level(p.flags);
      channel_texels[k] += uint64_t(pack::patch_atlas_side(p.width, level)) *
                           pack::patch_atlas_side(p.height, level) * p.channel_count;
    }
  }
  const double ratio = double(channel_texels[1]) / double(channel_texels[0]);
  std::printf(
      "atlas channel-texels: 3 channels %llu, with tints %llu (%.3fx); atlas bytes %llu, %llu; "
      "patches with a tint %u of %u (2-channel %u)\n",
      (unsigned long long)channel_texels[0], (unsigned long long)channel_texels[1], ratio,
      (unsigned long long)atlas_bytes(colour.pack), (unsigned long long)atlas_bytes(tinted.pack),
      with_tint[1], tinted.pack.patch_count(), two_channels);
  EXPECT_EQ(with_tint[0], 0u);
  EXPECT_GT(with_tint[1], 0u);
  EXPECT_GT(two_channels, 0u);
  EXPECT_LT(ratio, 0.9);  // 0.813x (0.929x with 1 channel and a tint alone)
  EXPECT_LE(atlas_bytes(tinted.pack), atlas_bytes(colour.pack));
  expect_standard_states_match(colour);
  expect_standard_states_match(tinted);
  const double step = colour.maps.output_step;
  for (const NamedState& st : standard_states(colour.scene)) {
    const PackDifference d = compare_packs(colour.pack, tinted.pack, st, colour.texels, step);
    std::printf(
        "  %-24s tints against 3 channels: relative RMSE %.4f%%, bias %+.4f%%, largest texel "
        "difference %.2f output steps beyond 1 %% of the texel\n",
        st.name.c_str(), 100.0 * d.rmse, 100.0 * d.bias, d.worst_steps);
    EXPECT_LT(d.rmse, 0.002) << st.name;              // at most 0.060 %
    EXPECT_LT(std::fabs(d.bias), 0.0005) << st.name;  // at most 0.0063 %
    EXPECT_LT(d.worst_steps, 1.0) << st.name;         // at most 0.16
  }
}

// The maps' direct parts dropped: packs as they were before maps were stored in parts.
void drop_direct_parts(BakedMaps& m) {
  m.base_direct = FloatImage();
  for (FloatImage& c : m.contribution_direct) c = FloatImage();
  for (ShadowMap& s : m.shadows) s.direct = FloatImage();
  for (PairCorrectionMap& p : m.pair_corrections) p.direct = FloatImage();
  for (StaticShadowMap& s : m.static_shadows) s.direct = FloatImage();
}

// Maps with bounce light are stored as their direct and bounce parts where that costs less
// (PackOptions::bounce_tolerance), or always (PackOptions::always_parts): the same light as the
// whole maps' pack within the bounce tolerance at every texel, bake_state's within the pack's
// bar, and by default fewer bytes.
TEST(HardCases, DirectAndBouncePartsSaveBytesAndStayWithinTheBounceTolerance) {
  Cooked parts;
  two_rooms(parts.scene);
  cook(parts, 256, draft(true));
  ASSERT_FALSE(HasFatalFailure());
  // The bake kept each map's direct part: bounce light on a layout without blocks; grey (one
  // channel) for a light, the static lights' colours for the base map.
  ASSERT_EQ(parts.layout.align, 1);
  ASSERT_EQ(parts.maps.base_direct.channels, 3);
  ASSERT_EQ(parts.maps.contribution_direct.size(), parts.maps.contribution.size());
  ASSERT_FALSE(parts.maps.contribution_direct.empty());
  for (const FloatImage& d : parts.maps.contribution_direct) EXPECT_EQ(d.channels, 1);
  // The same maps without their direct parts (the pack as it was), and every map in parts.
  BakedMaps whole_maps = parts.maps;
  drop_direct_parts(whole_maps);
  PackOptions always;
  always.always_parts = true;
  Report whole_report, always_report;
  const std::vector<uint8_t> whole_bytes =
      build_pack(parts.scene, parts.layout, whole_maps, PackOptions{}, whole_report);
  const std::vector<uint8_t> always_bytes =
      build_pack(parts.scene, parts.layout, parts.maps, always, always_report);
  PackView whole, all_parts;
  Error error;
  for (auto [bytes, view] : {std::pair{&whole_bytes, &whole}, std::pair{&always_bytes, &all_parts}})
    ASSERT_EQ(
        PackView::open(bytes->data(), bytes->size(), RecomposeLimits::format_only(), view, &error),
        Status::kOk)
        << error.message;
  const nlohmann::json& d = parts.report.root()["pack"]["direct_and_bounce_parts"];
  const nlohmann::json& da = always_report.root()["pack"]["direct_and_bounce_parts"];
  EXPECT_TRUE(whole_report.root()["pack"]["direct_and_bounce_parts"]["maps"].empty());
  std::printf(
      "atlas bytes: whole maps %llu, default %llu (%.3fx; %d of %d maps in parts), every map in "
      "parts %llu\n",
      (unsigned long long)atlas_bytes(whole), (unsigned long long)atlas_bytes(parts.pack),
      double(atlas_bytes(parts.pack)) / double(atlas_bytes(whole)), d["maps_in_parts"].get<int>(),
      d["maps_with_direct_part"].get<int>(), (unsigned long long)atlas_bytes(all_parts));
  EXPECT_EQ(d["maps_with_direct_part"].get<int>(), 4);  // B, C_lamp, S_crate,lamp, B - B_crate
  EXPECT_GT(d["maps_in_parts"].get<int>(), 0);
  EXPECT_EQ(da["maps_in_parts"].get<int>(), 4);
  // 0.920x (0.867x before each map's bounce tolerance was capped at half its own light there,
  // pack_builder.cpp kBounceShare: the parts save less where the tolerance is tighter).
  EXPECT_LT(double(atlas_bytes(parts.pack)), 0.95 * double(atlas_bytes(whole)));
  // Chosen per set of charts that no patch leaves (some maps in parts on some surfaces and whole
  // on others), and never so that a light's change draws more texels than the costliest light
  // change of the whole maps' pack.
  int mixed = 0;
  for (const nlohmann::json& m : d["maps"]) {
    const int sets = m["chart_sets"].get<int>(), in_parts = m["chart_sets_in_parts"].get<int>();
    std::printf("  %-48s %d of %d sets of charts in parts\n", m["map"].get<std::string>().c_str(),
                in_parts, sets);
    mixed += in_parts > 0 && in_parts < sets ? 1 : 0;
  }
  EXPECT_GT(mixed, 0);
  std::printf(
      "costliest light change: whole maps %llu texels, default %llu, every map in parts %llu\n",
      (unsigned long long)costliest_light_change(whole),
      (unsigned long long)costliest_light_change(parts.pack),
      (unsigned long long)costliest_light_change(all_parts));
  // The builder's bound is its own cut of each map whole, at the bounce tolerance; this whole
  // maps' pack has no direct parts, so it is cut at the level tolerance everywhere: within 1 %
  // (25,301 against 25,150 texels; the same texels before the bounce tolerance's per-map cap).
  EXPECT_LE(double(costliest_light_change(parts.pack)),
            1.01 * double(costliest_light_change(whole)));
  expect_standard_states_match(parts);
  // Against the whole maps' pack, state by state, in output steps at every valid texel: within
  // the bounce part's tolerance, the direct part's and the whole pack's level tolerance (1 each)
  // and three patches' rounding (half a step each, and 1 % of the texel).
  for (const PackView* pv : {&parts.pack, &all_parts}) {
    for (const NamedState& st : standard_states(parts.scene)) {
      const PackDifference d = compare_packs(whole, *pv, st, parts.texels, parts.maps.output_step);
      std::printf(
          "  %-12s %-24s against whole maps: relative RMSE %.4f%%, bias %+.4f%%, largest texel "
          "difference %.2f output steps beyond 1 %% of the texel\n",
          pv == &all_parts ? "all parts" : "default", st.name.c_str(), 100.0 * d.rmse,
          100.0 * d.bias, d.worst_steps);
      EXPECT_LT(d.rmse, 0.015) << st.name;  // 0.93 % every map in parts, lamp off (dim)
      EXPECT_LT(std::fabs(d.bias), 0.002) << st.name;
      EXPECT_LT(d.worst_steps, kDefaultBounceTolerance + 3.5) << st.name;
    }
  }
}

TEST(HardCases, SpotWithInnerEqualToOuterHasAHardEdge) {
  // The cone falloff divides by cos(inner) - cos(outer) = 0: finite, and a step at the edge.
  Light spot = test::spot_light("s", {0, 0, 0}, {0, 0, -1}, 1.0f, 0.4f, 0.4f);
  for (const float a : {0.0f, 0.39f, 0.4f, 0.41f, 1.5f}) {
    const float v = spot_attenuation(spot, {std::sin(a), 0.0f, -std::cos(a)});
    EXPECT_TRUE(std::isfinite(v) && v >= 0.0f && v <= 1.0f) << a << ": " << v;
  }
  EXPECT_FLOAT_EQ(spot_attenuation(spot, {std::sin(0.39f), 0.0f, -std::cos(0.39f)}), 1.0f);
  EXPECT_EQ(spot_attenuation(spot, {std::sin(0.41f), 0.0f, -std::cos(0.41f)}), 0.0f);

  Cooked c;
  Scene& s = c.scene;
  add_floor(s);
  test::add_object_box(s, {-0.2f, 0.8f, -0.2f}, {0.2f, 1.0f, 0.2f}, "crate");
  const glm::vec3 lp(0.0f, 2.0f, 0.0f);
  const float outer = 0.5f;
  s.lights = {test::spot_light("beam", lp, {0, -1, 0}, 8.0f, outer, outer, true),
              test::spot_light("static_beam", {1.0f, 1.5f, 1.0f}, {0, -1, 0}, 4.0f, 0.3f, 0.3f)};
  test::finish(s);
  cook(c, 64, draft(false));
  ASSERT_FALSE(HasFatalFailure());
  // On the floor: the full inverse-square law inside the cone, nothing outside it.
  const FloatImage& beam = c.maps.contribution[0];
  int inside = 0, outside = 0;
  float worst = 0.0f;
  for (size_t t = 0; t < c.texels.valid.size(); ++t) {
    const glm::vec3 p = c.texels.position[t];
    if (!c.texels.valid[t] || c.texels.normal[t].y < 0.99f || p.y > 1e-3f) continue;
    if (std::max(std::fabs(p.x), std::fabs(p.z)) < 0.7f) continue;  // the crate's shadow
    const glm::vec3 d = lp - p;
    const float dist = glm::length(d);
    const float angle = std::acos(d.y / dist);
    const float got = beam.at(int(t % size_t(beam.width)), int(t / size_t(beam.width)), 0);
    if (angle < outer - 0.02f) {
      const float want = (d.y / dist) / (dist * dist);
      worst = std::max(worst, std::fabs(got - want) / want);
      ++inside;
    } else if (angle > outer + 0.02f) {
      EXPECT_EQ(got, 0.0f) << p.x << "," << p.z;
      ++outside;
    }
  }
  EXPECT_GT(inside, 20);
  EXPECT_GT(outside, 100);
  EXPECT_LT(worst, 0.01f);
  std::printf("spot inner = outer: max relative error inside the cone %.3g (%d texels)\n", worst,
              inside);
  RecordProperty("worst_relative_rmse", std::to_string(expect_standard_states_match(c)));
}

TEST(HardCases, ZeroIntensityLightsContributeNothingAndCanBeTurnedUp) {
  for (const bool alone : {false, true}) {
    SCOPED_TRACE(alone ? "the only light, at 0" : "beside a lit light");
    Cooked c;
    Scene& s = c.scene;
    add_floor(s);
    test::add_object_box(s, {-0.3f, 0.0f, -0.3f}, {0.3f, 0.5f, 0.3f}, "crate");
    s.lights = {test::point_light("dark", {0.5f, 1.5f, 0.5f}, 0.0f, true)};
    if (!alone) {
      s.lights.push_back(test::point_light("lamp", {-1.0f, 2.0f, -0.5f}, 6.0f, true));
      s.lights.push_back(test::point_light("unlit", {1.0f, 1.0f, -1.0f}, 0.0f, false));
    }
    test::finish(s);
    cook(c, 48, draft(true));
    ASSERT_FALSE(HasFatalFailure());
    // Contribution maps are per unit intensity: the dark light keeps its map and its patches.
    float peak = 0.0f;
    for (float v : c.maps.contribution[0].data) peak = std::max(peak, v);
    EXPECT_GT(peak, 0.0f);
    ASSERT_GE(c.pack.contribution_group(0), 0);
    EXPECT_EQ(c.pack.light(0).intensity, 0.0f);

    // At 0 it adds nothing: the authored recomposition equals the one with it off.
    CpuRecomposer a, b;
    Error error;
    ASSERT_EQ(a.init(c.pack, &error), Status::kOk);
    ASSERT_EQ(b.init(c.pack, &error), Status::kOk);
    SceneState authored, off;
    ASSERT_EQ(authored.init(c.pack, &error), Status::kOk);
    ASSERT_EQ(off.init(c.pack, &error), Status::kOk);
    ASSERT_EQ(off.set_light_on(0, false), Status::kOk);
    ASSERT_EQ(a.rebuild(authored), Status::kOk);
    ASSERT_EQ(b.rebuild(off), Status::kOk);
    const size_t n = size_t(a.width()) * a.height() * 3;
    for (size_t i = 0; i < n; ++i) {
      ASSERT_TRUE(std::isfinite(a.rgb()[i]));
      ASSERT_EQ(a.rgb()[i], b.rgb()[i]) << i;
    }

    std::vector<NamedState> states = standard_states(s);
    NamedState up{"dark at 3 cd", {}};
    up.spec.lights["dark"] = intensity_override(3.0f);
    states.push_back(up);
    NamedState up_hidden{"dark at 3 cd, no crate", up.spec};
    up_hidden.spec.objects["crate"] = false;
    states.push_back(up_hidden);
    RecordProperty(alone ? "worst_relative_rmse_alone" : "worst_relative_rmse",
                   std::to_string(expect_states_match(c, states)));
  }
}

TEST(HardCases, SemiDynamicObjectTouchingALight) {
  Cooked c;
  Scene& s = c.scene;
  add_floor(s);
  // A lantern box with a light on its top face, and a chest with a light inside it.
  test::add_object_box(s, {-1.0f, 0.0f, -1.0f}, {-0.4f, 0.6f, -0.4f}, "lantern");
  test::add_object_box(s, {0.6f, 0.0f, 0.6f}, {1.2f, 0.5f, 1.2f}, "chest");
  s.lights = {test::point_light("wick", {-0.7f, 0.6f, -0.7f}, 4.0f, true),
              test::point_light("glow", {0.9f, 0.25f, 0.9f}, 6.0f, true),
              test::point_light("sky", {0.0f, 3.0f, 0.0f}, 10.0f, false)};
  test::finish(s);
  cook(c, 48, draft(true));
  ASSERT_FALSE(HasFatalFailure());
  std::vector<NamedState> states = standard_states(s);
  NamedState none{"both hidden", {}};
  none.spec.objects["lantern"] = false;
  none.spec.objects["chest"] = false;
  states.push_back(none);
  RecordProperty("worst_relative_rmse", std::to_string(expect_states_match(c, states)));
}

}  // namespace
}  // namespace lightpatch::cooker
