// Light probes (probes.h): placed where things can move, lit per set so that the sets summed for a
// state by the maps' rules equal that state's probes lit directly, an irradiance that agrees with
// a closed form and with the texel of bake-state at the same point, and no light through walls.
#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <string>
#include <vector>

#include "lightpatch/cooker/cook.h"
#include "lightpatch/cooker/probes.h"
#include "lightpatch/cooker/reference_integrator.h"
#include "lightpatch/group_rules.h"
#include "lightpatch/light_probes.h"
#include "lightpatch/pack_view.h"
#include "lightpatch/scene_state.h"
#include "lightpatch/spherical_harmonics.h"
#include "test_scenes.h"

namespace lightpatch::cooker {
namespace {

using Sh = std::array<float, pack::kProbeShCount * 3>;

// Two rooms side by side, sealed from each other by a solid partition: the lamp (semi-dynamic)
// and a static fill in the west room with a semi-dynamic crate; a placed probe 5 mm above the
// west floor; the east room lit by nothing.
Scene two_sealed_rooms() {
  Scene s;
  Material wall;
  wall.albedo = glm::vec3(0.7f, 0.6f, 0.5f);
  s.materials = {wall};
  test::add_closed_room(s, {-4, 0, -2}, {4, 2.5f, 2}, 0.1f, "room");
  test::add_box(s, {-0.1f, 0.0f, -2.0f}, {0.1f, 2.5f, 2.0f}, "partition");
  test::add_object_box(s, {-2.5f, 0.0f, -0.5f}, {-1.7f, 0.7f, 0.3f}, "crate");
  s.lights = {test::point_light("lamp", {-2.0f, 2.0f, 0.4f}, 5.0f, true),
              test::point_light("fill", {-3.2f, 1.0f, 1.1f}, 1.0f, false)};
  s.probes = {{"on_the_floor", {-1.0f, 0.005f, -1.2f}}};
  test::finish(s);
  return s;
}

struct Cooked {
  PreparedScene p;
  BakeOptions bake;
  BakedMaps maps;
  ProbeBake probes;
  Report report;
  std::vector<uint8_t> pack;
};

void cook(Cooked& c, Scene scene, float spacing = 0.5f, Quality quality = Quality::kDraft) {
  c.bake.quality = quality;
  c.bake.gather_rays = 32;
  c.bake.probes.spacing = spacing;
  c.bake.probes.rays = 256;
  LayoutOptions lo;
  lo.lightmap_size = 128;
  Progress progress(true);
  c.p = prepare_scene(std::move(scene), lo, progress, c.report);
  c.pack = cook_pack(c.p, c.bake, progress, c.report, &c.maps);
  c.probes = cook_probes(c.p, c.maps, c.bake, progress, c.report);
}

// A state's probes by the runtime's rule: every set the state draws, with its sign and factor.
std::vector<Sh> recompose(const Cooked& c, const StateSpec& state) {
  const ResolvedState r = resolve_state(c.p.scene, state);
  std::vector<Sh> out(c.probes.probes.size());
  for (Sh& sh : out) sh.fill(0.0f);
  for (const ProbeBake::Set& s : c.probes.sets) {
    pack::GroupRecord g{s.kind,
                        s.light < 0 ? pack::kNone16 : uint16_t(s.light),
                        s.object < 0 ? pack::kNone16 : uint16_t(s.object),
                        pack::kNone16,
                        0,
                        1};
    glm::vec3 f(1.0f);
    if (group_has_light(s.kind)) f = r.radiant[size_t(c.maps.lights[size_t(s.light)])];
    const bool drawn = group_active(
        g, [&](uint32_t l) { return r.radiant[size_t(c.maps.lights[l])] != glm::vec3(0.0f); },
        [&](uint32_t o) { return r.visible[o] != 0; });
    if (!drawn) continue;
    for (const pack::ProbeEntry& e : s.entries)
      for (uint32_t k = 0; k < pack::kProbeShCount; ++k)
        for (int ch = 0; ch < 3; ++ch)
          out[e.probe][k * 3 + ch] += group_sign(s.kind) * f[ch] * e.sh[k * 3 + ch];
  }
  return out;
}

glm::vec3 irradiance(const Sh& sh, const glm::vec3& n) {
  float rgb[3];
  sh_irradiance(sh.data(), n.x, n.y, n.z, rgb);
  return {rgb[0], rgb[1], rgb[2]};
}

// Relative RMSE of the irradiance facing the six axes over every probe.
double axis_rel_rmse(const std::vector<Sh>& a, const std::vector<Sh>& b) {
  static const glm::vec3 kAxes[6] = {{1, 0, 0},  {-1, 0, 0}, {0, 1, 0},
                                     {0, -1, 0}, {0, 0, 1},  {0, 0, -1}};
  double num = 0.0, den = 0.0;
  for (size_t i = 0; i < a.size(); ++i)
    for (const glm::vec3& n : kAxes) {
      const glm::vec3 x = irradiance(a[i], n), r = irradiance(b[i], n);
      for (int ch = 0; ch < 3; ++ch) {
        num += double(x[ch] - r[ch]) * double(x[ch] - r[ch]);
        den += double(r[ch]) * double(r[ch]);
      }
    }
  return std::sqrt(num / std::max(den, 1e-30));
}

size_t probe_named(const ProbeBake& b, const std::string& name) {
  for (size_t i = 0; i < b.probes.size(); ++i)
    if (b.probes[i].name == name) return i;
  ADD_FAILURE() << "no probe " << name;
  return 0;
}

TEST(Probes, GridKeepsTheFreeSpaceAndMeasuresReach) {
  Cooked c;
  cook(c, two_sealed_rooms());
  const ProbeBake& b = c.probes;
  ASSERT_TRUE(b.has_grid);
  EXPECT_FLOAT_EQ(b.grid_spacing, 0.5f);
  size_t inside_walls = 0, free_points = 0;
  for (size_t i = 0; i < b.grid_index.size(); ++i) {
    const glm::ivec3 g(int(i) % b.grid_size.x, (int(i) / b.grid_size.x) % b.grid_size.y,
                       int(i) / (b.grid_size.x * b.grid_size.y));
    const glm::vec3 p = b.grid_origin + b.grid_spacing * glm::vec3(g);
    // Inside the room's air, not within the partition's slab.
    const bool free = p.x > -3.9f && p.x < 3.9f && std::abs(p.x) > 0.1f && p.y > 0.0f &&
                      p.y < 2.4f && p.z > -1.9f && p.z < 1.9f;
    const bool in_slab = std::abs(p.x) < 0.09f || p.x < -4.01f || p.x > 4.01f || p.y < -0.01f ||
                         p.y > 2.51f || p.z < -2.01f || p.z > 2.01f;
    if (free) {
      ++free_points;
      EXPECT_NE(b.grid_index[i], pack::kNone32) << "free point " << p.x << " " << p.y << " " << p.z;
    }
    if (in_slab && std::abs(p.x) < 0.09f) {
      ++inside_walls;
      EXPECT_EQ(b.grid_index[i], pack::kNone32) << "point in the partition kept";
    }
  }
  EXPECT_GT(free_points, 100u);
  EXPECT_GT(inside_walls, 0u);
  // The placed probe: reach down is its 5 mm to the floor, up the 0.5 m cap.
  const ProbeBake::Probe& floor = b.probes[probe_named(b, "on_the_floor")];
  EXPECT_NEAR(floor.reach[3], 0.005f, 1e-3f);
  EXPECT_FLOAT_EQ(floor.reach[2], 0.5f);
}

TEST(Probes, RecomposedSetsEqualTheStateLitDirectly) {
  Cooked c;
  cook(c, two_sealed_rooms());
  ASSERT_FALSE(c.probes.sets.empty());
  const ProbeOptions po = probe_options(c.bake);
  std::vector<StateSpec> states(4);
  states[1].lights["lamp"].has_on = true;
  states[1].lights["lamp"].on = false;
  states[2].objects["crate"] = false;
  states[3].objects["crate"] = false;
  states[3].lights["lamp"].has_color = true;
  states[3].lights["lamp"].color[0] = 1.0f;
  states[3].lights["lamp"].color[1] = 0.5f;
  states[3].lights["lamp"].color[2] = 0.25f;
  Progress progress(true);
  for (size_t i = 0; i < states.size(); ++i) {
    const FloatImage map = cook_state(c.p, states[i], c.bake, progress, c.report);
    const auto direct = bake_state_probes(c.probes, c.p.scene, c.p.layout, c.p.texels, *c.p.tracer,
                                          map, states[i], po);
    std::vector<Sh> reference(direct.begin(), direct.end());
    const double e = axis_rel_rmse(recompose(c, states[i]), reference);
    EXPECT_LT(e, 2e-4) << "state " << i;
    RecordProperty("state_" + std::to_string(i) + "_rel_rmse", std::to_string(e));
  }
}

// The placed probe 5 mm above the floor against the path tracer's floor texel under it (8192
// paths, that texel alone): facing up the probe gets what that texel gets, facing down the floor's
// radiance rho E / pi over the lower hemisphere, i.e. rho times it (a closed form); within 5 %
// (measured -3.4 to -2.5 % up, -0.4 to +0.7 % down). Against bake-state's texel (draft: 32 rays
// per 4x4 block) the probe's error and the texel's add up (measured 5.1-5.8 %, the texel +0.8 to
// +3.5 % from the path tracer): within 8 %.
TEST(Probes, ProbeAboveTheFloorAgreesWithTheFloorTexel) {
  Cooked c;
  cook(c, two_sealed_rooms());
  const size_t i = probe_named(c.probes, "on_the_floor");
  const std::vector<Sh> sh = recompose(c, StateSpec{});
  Progress progress(true);
  const FloatImage map = cook_state(c.p, StateSpec{}, c.bake, progress, c.report);
  // The floor texel nearest the probe's foot.
  const glm::vec3 foot = c.probes.probes[i].position - glm::vec3(0, 0.005f, 0);
  size_t best = 0;
  float best_d = 1e30f;
  for (size_t t = 0; t < c.p.texels.valid.size(); ++t) {
    if (!c.p.texels.valid[t] || c.p.texels.normal[t].y < 0.9f) continue;
    const float d = glm::length(c.p.texels.position[t] - foot);
    if (d < best_d) best_d = d, best = t;
  }
  ASSERT_LT(best_d, 0.1f);
  ReferenceOptions ro;
  ro.samples = 8192;
  ro.region.assign(c.p.texels.valid.size(), 0);
  ro.region[best] = 1;
  Report reference_report;
  const ReferenceBake ref =
      bake_reference(c.p.scene, c.p.texels, *c.p.tracer, {}, ro, progress, reference_report);
  const glm::vec3 floor(map.data[best * 3], map.data[best * 3 + 1], map.data[best * 3 + 2]);
  const glm::vec3 truth(ref.map.data[best * 3], ref.map.data[best * 3 + 1],
                        ref.map.data[best * 3 + 2]);
  const glm::vec3 up = irradiance(sh[i], {0, 1, 0}), down = irradiance(sh[i], {0, -1, 0});
  const glm::vec3 rho = c.p.scene.materials[0].albedo;
  for (int ch = 0; ch < 3; ++ch) {
    EXPECT_LT(ref.std_error.data[best * 3 + size_t(ch)], 0.02f * truth[ch]);
    EXPECT_NEAR(up[ch] / truth[ch], 1.0, 0.05) << "channel " << ch;
    EXPECT_NEAR(down[ch] / (rho[ch] * truth[ch]), 1.0, 0.05) << "channel " << ch;
    EXPECT_NEAR(up[ch] / floor[ch], 1.0, 0.08) << "channel " << ch;
  }
  RecordProperty("up_over_path_traced_texel", std::to_string(up.x / truth.x));
  RecordProperty("down_over_rho_path_traced_texel", std::to_string(down.x / (rho.x * truth.x)));
  RecordProperty("up_over_texel", std::to_string(up.x / floor.x));
}

// Probes 5 mm in front of texels all over the west room, at least 0.5 m from the lamps: their
// irradiance facing each texel's normal is the texel's in bake-state (order-2 truncation and the
// probes' own rays apart). Measured 8.7 % relative RMSE (texels in corners, where a point 5 mm
// out sees the next wall), median ratio 1.006.
TEST(Probes, ProbesInFrontOfTexelsAgreeWithBakeState) {
  Scene scene = two_sealed_rooms();
  Cooked layout_only;
  cook(layout_only, scene);
  const TexelSet& texels = layout_only.p.texels;
  scene.probes.clear();
  std::vector<size_t> at;
  for (size_t t = 0; t < texels.valid.size(); t += 7) {
    const glm::vec3 q = texels.position[t] + 0.005f * texels.normal[t];
    bool far = q.x < -0.2f && q.x > -3.9f;
    for (const Light& l : scene.lights) far = far && glm::length(l.position - q) >= 0.5f;
    if (!texels.valid[t] || !far) continue;
    scene.probes.push_back({"t" + std::to_string(t), q});
    at.push_back(t);
  }
  ASSERT_GT(at.size(), 100u);
  Cooked c;
  cook(c, scene);
  const std::vector<Sh> sh = recompose(c, StateSpec{});
  Progress progress(true);
  const FloatImage map = cook_state(c.p, StateSpec{}, c.bake, progress, c.report);
  double num = 0.0, den = 0.0;
  std::vector<double> ratio;
  for (size_t i = 0; i < at.size(); ++i) {
    const size_t probe = probe_named(c.probes, "t" + std::to_string(at[i]));
    const glm::vec3 e = glm::max(irradiance(sh[probe], texels.normal[at[i]]), glm::vec3(0.0f));
    const glm::vec3 r(map.data[at[i] * 3], map.data[at[i] * 3 + 1], map.data[at[i] * 3 + 2]);
    for (int ch = 0; ch < 3; ++ch) {
      num += double(e[ch] - r[ch]) * double(e[ch] - r[ch]);
      den += double(r[ch]) * double(r[ch]);
    }
    if (r.y > 0.0f) ratio.push_back(double(e.y / r.y));
  }
  std::sort(ratio.begin(), ratio.end());
  const double rmse = std::sqrt(num / den), median = ratio[ratio.size() / 2];
  EXPECT_LT(rmse, 0.12);
  EXPECT_NEAR(median, 1.0, 0.03);
  RecordProperty("rel_rmse", std::to_string(rmse));
  RecordProperty("median_ratio", std::to_string(median));
}

// The partition seals the east room: no set of the lamp, the fill or the crate reaches a probe
// there, so switching anything changes no probe of the east room.
TEST(Probes, NoLightReachesProbesThroughAWall) {
  Cooked c;
  cook(c, two_sealed_rooms());
  size_t east = 0, west_lit = 0;
  std::vector<uint8_t> reached(c.probes.probes.size(), 0);
  for (const ProbeBake::Set& s : c.probes.sets)
    for (const pack::ProbeEntry& e : s.entries) reached[e.probe] = 1;
  for (size_t i = 0; i < c.probes.probes.size(); ++i) {
    const float x = c.probes.probes[i].position.x;
    if (x > 0.2f && x < 3.9f) {
      ++east;
      EXPECT_EQ(reached[i], 0) << "east probe " << i << " at x " << x << " is lit";
    } else if (x < -0.2f && x > -3.9f) {
      west_lit += reached[i];
    }
  }
  EXPECT_GT(east, 50u);
  EXPECT_GT(west_lit, 50u);
}

// The same partition in the lamp's map at every preset (32 gather rays, as above: few rays leave
// more texels buried, where this matters). A texel whose gather rays mostly hit the back of a
// surface is buried (its sample point inside solid geometry: a ceiling texel under the
// partition), and a hit on it moved to the texel nearest in the page, for a hit in the east room
// as often the one beyond the partition, lit by the lamp: the east room's brightest texel had
// 0.20 % (preview) and 0.41 % (production) of the west's brightest, and 0.054 % and 0.020 % of the
// west's light in all. A hit now goes to the nearest texel its own point sees: 0.017 % and
// 0.048 %, 0.0013 % and 0.0012 % in all (draft: none), from surface-patch points inside the floor
// and ceiling slabs, which run under the partition: a footprint cell that a wall covered only in
// part was open, and its points inside the wall cast rays that travelled inside the slabs. With
// a texel's gather points and directions drawn as one sequence (gather.cpp) that leak grew to
// 0.0063 % in all and 0.20 % at the brightest texel (production); since a cell is open only when
// its corners are too (texel_footprint.cpp), none at any preset.
TEST(Probes, TheSealedRoomStaysDarkInTheLampsMapAtEveryPreset) {
  for (Quality q : {Quality::kDraft, Quality::kPreview, Quality::kProduction}) {
    Cooked c;
    cook(c, two_sealed_rooms(), 0.5f, q);
    const FloatImage& m = c.maps.contribution[0];
    double east = 0.0, east_max = 0.0, west = 0.0, west_max = 0.0;
    for (size_t t = 0; t < c.p.texels.valid.size(); ++t) {
      if (!c.p.texels.valid[t]) continue;
      const double v = m.data[t * size_t(m.channels)];
      const float x = c.p.texels.position[t].x;
      if (x >= 0.1f) east += v, east_max = std::max(east_max, v);
      if (x <= -0.1f) west += v, west_max = std::max(west_max, v);
    }
    std::printf("sealed room, %s: east %.3g of the west's light, its brightest texel %.3g\n",
                q == Quality::kDraft     ? "draft"
                : q == Quality::kPreview ? "preview"
                                         : "production",
                east / west, east_max / west_max);
    ASSERT_GT(west, 0.0);
    if (q == Quality::kDraft) {
      EXPECT_EQ(east, 0.0);
    } else {
      EXPECT_LT(east / west, 1e-6);
      EXPECT_LT(east_max / west_max, 1e-5);
    }
  }
}

// Through the pack and the runtime: LightProbes brought incrementally through a sequence of
// states gives each state's probes lit directly (less what the pack leaves out below its sets'
// significance), and a light switched off darkens exactly the probes its sets reach.
TEST(Probes, RuntimeProbesFollowTheStateThroughThePack) {
  Cooked c;
  cook(c, two_sealed_rooms());
  PackView view;
  Error error;
  ASSERT_EQ(PackView::open(c.pack.data(), c.pack.size(), &view, &error), Status::kOk)
      << error.message;
  ASSERT_EQ(view.probe_count(), c.probes.probes.size());
  LightProbes probes;
  SceneState state;
  ASSERT_EQ(probes.init(view, &error), Status::kOk) << error.message;
  ASSERT_EQ(state.init(view, &error), Status::kOk) << error.message;
  const int32_t lamp = view.find_light("lamp", 4), crate = view.find_object("crate", 5);
  ASSERT_GE(lamp, 0);
  ASSERT_GE(crate, 0);
  auto runtime_sh = [&] {
    std::vector<Sh> out(probes.probe_count());
    for (uint32_t i = 0; i < probes.probe_count(); ++i) probes.probe_sh(i, out[i].data());
    return out;
  };
  const ProbeOptions po = probe_options(c.bake);
  Progress progress(true);
  auto expect_state = [&](const StateSpec& spec, const char* what) {
    const FloatImage map = cook_state(c.p, spec, c.bake, progress, c.report);
    const auto direct =
        bake_state_probes(c.probes, c.p.scene, c.p.layout, c.p.texels, *c.p.tracer, map, spec, po);
    const double e = axis_rel_rmse(runtime_sh(), std::vector<Sh>(direct.begin(), direct.end()));
    EXPECT_LT(e, 2e-3) << what;
    RecordProperty(std::string(what) + "_rel_rmse", std::to_string(e));
  };
  ASSERT_EQ(probes.update(state), Status::kOk);
  expect_state(StateSpec{}, "authored");
  const std::vector<Sh> lit = runtime_sh();

  ASSERT_EQ(state.set_light_on(uint32_t(lamp), false), Status::kOk);
  ASSERT_EQ(probes.update(state), Status::kOk);
  StateSpec off;
  off.lights["lamp"].has_on = true;
  off.lights["lamp"].on = false;
  expect_state(off, "lamp_off");
  const std::vector<Sh> dark = runtime_sh();
  // The lamp's sets (its contribution, its shadows of the crate) name the probes it reaches.
  std::vector<uint8_t> reached(view.probe_count(), 0);
  for (uint32_t s = 0; s < view.probe_set_count(); ++s) {
    const pack::ProbeSetRecord& r = view.probe_set(s);
    if (r.light != uint16_t(lamp)) continue;
    for (uint32_t e = 0; e < r.entry_count; ++e)
      reached[view.probe_entry(r.first_entry + e).probe] = 1;
  }
  size_t darker = 0, reached_count = 0;
  for (uint32_t i = 0; i < view.probe_count(); ++i) {
    if (!reached[i]) {
      EXPECT_EQ(lit[i], dark[i]) << "probe " << i << " changed without an entry of the lamp";
      continue;
    }
    ++reached_count;
    // The mean irradiance over directions (the order-0 term) falls.
    darker += dark[i][0] + dark[i][1] + dark[i][2] < lit[i][0] + lit[i][1] + lit[i][2] ? 1 : 0;
  }
  EXPECT_GT(reached_count, 50u);
  EXPECT_EQ(darker, reached_count);
  EXPECT_GT(probes.stats().entries_last_update, 0u);

  ASSERT_EQ(state.set_object_visible(uint32_t(crate), false), Status::kOk);
  const float warm[3] = {1.0f, 0.5f, 0.25f};
  ASSERT_EQ(state.set_light_on(uint32_t(lamp), true), Status::kOk);
  ASSERT_EQ(state.set_light_color(uint32_t(lamp), warm), Status::kOk);
  ASSERT_EQ(probes.update(state), Status::kOk);
  StateSpec warm_spec;
  warm_spec.objects["crate"] = false;
  warm_spec.lights["lamp"].has_color = true;
  std::copy(warm, warm + 3, warm_spec.lights["lamp"].color);
  expect_state(warm_spec, "warm_lamp_no_crate");
}

// Sampling between probes never blends through the partition: at 0.35 m spacing a grid cell
// straddles it with probes on both sides, and a point just east of it must take nothing from the
// lit west probes (the east room is unlit: its SH is exactly zero), while a point just west of it
// is lit.
TEST(Probes, SamplingDoesNotBlendThroughAWall) {
  Cooked c;
  cook(c, two_sealed_rooms(), 0.35f);
  ASSERT_TRUE(c.probes.has_grid);
  // The cell around x = 0 has probes on both sides of the 0.2 m partition.
  const glm::vec3 o = c.probes.grid_origin;
  const float h = c.probes.grid_spacing;
  const int i = int(std::floor((0.0f - o.x) / h));
  ASSERT_LT(o.x + h * float(i), -0.1f);
  ASSERT_GT(o.x + h * float(i + 1), 0.1f);
  PackView view;
  Error error;
  ASSERT_EQ(PackView::open(c.pack.data(), c.pack.size(), &view, &error), Status::kOk)
      << error.message;
  LightProbes probes;
  SceneState state;
  ASSERT_EQ(probes.init(view, &error), Status::kOk) << error.message;
  ASSERT_EQ(state.init(view, &error), Status::kOk) << error.message;
  ASSERT_EQ(probes.update(state), Status::kOk);
  size_t east = 0, west = 0;
  for (float x : {0.12f, 0.2f, 0.3f})
    for (float y : {0.4f, 1.3f, 2.2f})
      for (float z : {-1.5f, -0.2f, 0.9f}) {
        float sh[27];
        const float east_point[3] = {x, y, z}, west_point[3] = {-x, y, z};
        ASSERT_TRUE(probes.sample(east_point, sh));
        float sum = 0.0f;
        for (float v : sh) sum += std::abs(v);
        EXPECT_EQ(sum, 0.0f) << "east point " << x << " " << y << " " << z << " takes light";
        east += sum == 0.0f ? 1 : 0;
        ASSERT_TRUE(probes.sample(west_point, sh));
        float rgb[3];
        const float up[3] = {0, 1, 0}, toward_wall[3] = {1, 0, 0};
        LightProbes::irradiance(sh, up, rgb);
        float e = rgb[0];
        LightProbes::irradiance(sh, toward_wall, rgb);
        e += rgb[0];
        west += e > 0.0f ? 1 : 0;
      }
  EXPECT_EQ(east, 27u);
  EXPECT_EQ(west, 27u);
}

}  // namespace
}  // namespace lightpatch::cooker
