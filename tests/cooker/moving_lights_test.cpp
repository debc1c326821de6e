// Moving lights (docs/moving_lights.md): a lantern marked "moving" in its glTF extras is imported
// as such, a state moves it, the cook stores its bounce light as panes, and the runtime's CPU
// reference recomposes that bounce light for a pose close to `bake-state` of the same pose (which
// holds the moving light's bounce light only), without light through the partition, continuous
// in the light's position; the light probes follow it through the panes' probe sets.
#include <gtest/gtest.h>

#include <unistd.h>
#include <algorithm>
#include <array>
#include <cmath>
#include <cstdio>
#include <string>
#include <vector>

#include "gltf_files.h"
#include "lightpatch/cooker/cook.h"
#include "lightpatch/cooker/error.h"
#include "lightpatch/cooker/probes.h"
#include "lightpatch/cpu_recomposer.h"
#include "lightpatch/light_probes.h"
#include "lightpatch/moving_lights.h"
#include "lightpatch/pack_view.h"
#include "lightpatch/scene_state.h"
#include "lightpatch/spherical_harmonics.h"
#include "panes/pane_cluster.h"

namespace lightpatch::cooker {
namespace {

std::string write_two_rooms() {
  char path[] = "/tmp/lightpatch-moving-XXXXXX.glb";
  const int fd = ::mkstemps(path, 4);
  if (fd < 0) return {};
  ::close(fd);
  test::two_rooms_lantern().write(path);
  return path;
}

int light_index(const Scene& s, const std::string& name) {
  for (size_t i = 0; i < s.lights.size(); ++i)
    if (s.lights[i].name == name) return int(i);
  return -1;
}

TEST(MovingLights, ImportMarksTheLanternAndAStateMovesIt) {
  const std::string path = write_two_rooms();
  ASSERT_FALSE(path.empty());
  const Scene scene = import_gltf(path);
  std::remove(path.c_str());
  const int lantern = light_index(scene, "lantern"), lamp = light_index(scene, "lamp_b");
  ASSERT_GE(lantern, 0);
  ASSERT_GE(lamp, 0);
  EXPECT_TRUE(scene.lights[size_t(lantern)].moving);
  EXPECT_TRUE(scene.lights[size_t(lantern)].semi_dynamic);  // moving implies switchable
  EXPECT_FALSE(scene.lights[size_t(lamp)].moving);

  const StateSpec moved = parse_state_json(
      R"({"lights": {"lantern": {"position": [1, 2, 3], "direction": [0, 0, -2]}}})", "test");
  const ResolvedState r = resolve_state(scene, moved);
  EXPECT_EQ(r.position[size_t(lantern)], glm::vec3(1, 2, 3));
  EXPECT_EQ(r.direction[size_t(lantern)], glm::vec3(0, 0, -1));  // normalised
  EXPECT_EQ(r.position[size_t(lamp)], scene.lights[size_t(lamp)].position);
  // Only a moving light moves; a position must be 3 finite numbers.
  EXPECT_THROW(resolve_state(scene, parse_state_json(
                                        R"({"lights": {"lamp_b": {"position": [0, 1, 0]}}})", "t")),
               CookError);
  EXPECT_THROW(parse_state_json(R"({"lights": {"lantern": {"position": [0, 1]}}})", "t"),
               CookError);
  EXPECT_THROW(parse_state_json(R"({"lights": {"lantern": {"direction": [0, 0, 0]}}})", "t"),
               CookError);
}

struct Cooked {
  PreparedScene p;
  BakeOptions bake;
  Report report;
  std::vector<uint8_t> pack;
  PackView view;
  int lantern = -1;  // pack light index
  BakedMaps maps;    // with probes only
  ProbeBake probes;
};

// With `probes`, a 0.5 m grid of light probes in the pack and in c.probes. `pane_level` < 0: the
// default. `anchors` > 0: anchors at that spacing instead of panes.
void cook(Cooked& c, bool probes = false, int pane_level = -1, float anchors = 0.0f) {
  const std::string path = write_two_rooms();
  ASSERT_FALSE(path.empty());
  LayoutOptions lo;
  lo.lightmap_size = 128;
  Progress progress(true);
  c.p = prepare_scene(path, lo, progress, c.report);
  std::remove(path.c_str());
  c.bake.quality = Quality::kDraft;
  c.bake.gather_rays = 64;
  c.bake.probes.enabled = probes;
  c.bake.probes.spacing = 0.5f;
  c.bake.panes = 64;
  c.bake.pane_level = pane_level;
  c.bake.anchor_spacing = anchors;
  c.pack = cook_pack(c.p, c.bake, progress, c.report, &c.maps);
  if (probes) c.probes = cook_probes(c.p, c.maps, c.bake, progress, c.report);
  Error error;
  ASSERT_EQ(PackView::open(c.pack.data(), c.pack.size(), &c.view, &error), Status::kOk)
      << error.message;
  c.lantern = c.view.find_light("lantern", 7);
}

StateSpec lantern_at(const glm::vec3& p) {
  StateSpec s;
  s.lights["lantern"].has_position = true;
  for (int k = 0; k < 3; ++k) s.lights["lantern"].position[k] = p[k];
  return s;
}

StateSpec lantern_off() {
  StateSpec s;
  s.lights["lantern"].has_on = true;
  s.lights["lantern"].on = false;
  return s;
}

// The runtime's state for a state file's lantern.
void set_state(const Cooked& c, const StateSpec& spec, SceneState& state) {
  Error error;
  EXPECT_EQ(state.init(c.view, &error), Status::kOk);
  const auto& o = spec.lights.count("lantern") ? spec.lights.at("lantern") : LightOverride{};
  if (o.has_on) {
    EXPECT_EQ(state.set_light_on(uint32_t(c.lantern), o.on), Status::kOk);
  }
  if (o.has_position) {
    LightPose pose = state.light_pose(uint32_t(c.lantern));
    for (int k = 0; k < 3; ++k) pose.position[k] = o.position[k];
    EXPECT_EQ(state.set_light_pose(uint32_t(c.lantern), pose), Status::kOk);
  }
}

// The CPU reference's light map (light map + magnified indirect map) for a state.
std::vector<float> recompose(const Cooked& c, const StateSpec& spec) {
  SceneState state;
  Error error;
  set_state(c, spec, state);
  CpuRecomposer r;
  EXPECT_EQ(r.init(c.view, &error), Status::kOk);
  EXPECT_EQ(r.rebuild(state), Status::kOk);
  const size_t n = size_t(c.view.lightmap_width()) * c.view.lightmap_height() * 3;
  return std::vector<float>(r.rgb(), r.rgb() + n);
}

std::vector<float> baked(Cooked& c, const StateSpec& spec) {
  Progress progress(true);
  return cook_state(c.p, spec, c.bake, progress, c.report).data;
}

// The moving light's bounce light alone: the map at its pose less the map with it off.
std::vector<float> minus(const std::vector<float>& a, const std::vector<float>& b) {
  std::vector<float> d(a.size());
  for (size_t i = 0; i < a.size(); ++i) d[i] = a[i] - b[i];
  return d;
}

struct Agreement {
  double rel_rmse = 0.0, bias = 0.0;
};

// Over the valid texels of room A and B (x within the rooms' inner walls).
Agreement agreement(const Cooked& c, const std::vector<float>& got, const std::vector<float>& want,
                    float x_min = -1e9f, float x_max = 1e9f) {
  double sq = 0.0, ref_sq = 0.0, sum = 0.0, ref_sum = 0.0;
  for (size_t t = 0; t < c.p.texels.valid.size(); ++t) {
    if (!c.p.texels.valid[t]) continue;
    const float x = c.p.texels.position[t].x;
    if (x < x_min || x > x_max) continue;
    for (int k = 0; k < 3; ++k) {
      const double d = double(got[t * 3 + size_t(k)]) - want[t * 3 + size_t(k)];
      sq += d * d;
      ref_sq += double(want[t * 3 + size_t(k)]) * want[t * 3 + size_t(k)];
      sum += got[t * 3 + size_t(k)];
      ref_sum += want[t * 3 + size_t(k)];
    }
  }
  Agreement a;
  a.rel_rmse = ref_sq > 0.0 ? std::sqrt(sq / ref_sq) : 0.0;
  a.bias = ref_sum != 0.0 ? sum / ref_sum - 1.0 : 0.0;
  return a;
}

// The lantern's bounce light recomposed from `c` (its panes or anchors: `basis`) against
// bake-state at three poses, no light through the partition, no flicker for a 1 cm step.
void recomposes_the_lanterns_bounce_light(Cooked& c, const char* basis) {
  const std::vector<float> rec_off = recompose(c, lantern_off());
  const std::vector<float> bake_off = baked(c, lantern_off());
  // A pose in room A, one in the doorway, one in room B.
  const glm::vec3 poses[] = {{-2.0f, 1.2f, -1.0f}, {0.0f, 1.2f, 1.5f}, {2.0f, 1.2f, 1.5f}};
  for (const glm::vec3& pose : poses) {
    const std::vector<float> got = minus(recompose(c, lantern_at(pose)), rec_off);
    const std::vector<float> want = minus(baked(c, lantern_at(pose)), bake_off);
    const Agreement a = agreement(c, got, want);
    std::printf(
        "%s, lantern at (%.1f, %.1f, %.1f): bounce light relative RMSE %.1f %%, bias %+.1f %%\n",
        basis, pose.x, pose.y, pose.z, 100.0 * a.rel_rmse, 100.0 * a.bias);
    // Measured on this 128 page at 64 panes (refined to 256), level 1 (the default): 29.3 / 23.9
    // / 25.3 % and +4.1 / +0.0 / -2.7 %; 29.9 / 33.6 / 33.8 % and +5.3 / -15.1 / -13.6 % before
    // the panes kept to texels whose light bounces and were split by how unevenly a light lights
    // them (docs/moving_lights.md, "Where the panes go"). The bars catch a lost pane, a wrong
    // weight, a missing bounce, and panes that reach into the other room. Anchors at 0.5 m:
    // 29.3 / 23.7 / 25.3 % and +0.5 / -1.8 / -2.6 %.
    EXPECT_LT(a.rel_rmse, 0.35);
    EXPECT_LT(std::fabs(a.bias), 0.10);
  }

  // No light through the partition: with the lantern in room A's far corner, room B (beyond the
  // doorway's reach as much as bake-state's own) gets at most a little more than bake-state says.
  {
    const glm::vec3 corner(-3.5f, 1.2f, -1.5f);
    const std::vector<float> got = minus(recompose(c, lantern_at(corner)), rec_off);
    const std::vector<float> want = minus(baked(c, lantern_at(corner)), bake_off);
    double got_b = 0.0, want_b = 0.0, want_a = 0.0;
    for (size_t t = 0; t < c.p.texels.valid.size(); ++t) {
      if (!c.p.texels.valid[t]) continue;
      const float x = c.p.texels.position[t].x;
      for (int k = 0; k < 3; ++k) {
        if (x > 0.15f) {
          got_b += got[t * 3 + size_t(k)];
          want_b += want[t * 3 + size_t(k)];
        }
        if (x < -0.15f) want_a += want[t * 3 + size_t(k)];
      }
    }
    std::printf("%s, lantern in room A's corner: room B gets %.3g (bake-state %.3g), room A %.3g\n",
                basis, got_b, want_b, want_a);
    // Measured 183 against 148 (195 before the panes kept to one room).
    EXPECT_LT(got_b, 1.5 * want_b + 0.01 * want_a);
  }

  // No flicker: a 1 cm step of the light changes its recomposed bounce light by little.
  {
    const glm::vec3 p0(-1.5f, 1.3f, -0.5f), p1 = p0 + glm::vec3(0.01f, 0.0f, 0.0f);
    const std::vector<float> a = minus(recompose(c, lantern_at(p0)), rec_off);
    const std::vector<float> b = minus(recompose(c, lantern_at(p1)), rec_off);
    double peak = 0.0, step = 0.0;
    for (size_t t = 0; t < c.p.texels.valid.size(); ++t) {
      if (!c.p.texels.valid[t]) continue;
      for (int k = 0; k < 3; ++k) {
        peak = std::max(peak, double(std::fabs(a[t * 3 + size_t(k)])));
        step = std::max(step, double(std::fabs(a[t * 3 + size_t(k)] - b[t * 3 + size_t(k)])));
      }
    }
    std::printf("%s, 1 cm step: largest texel change %.3g of a peak %.3g\n", basis, step, peak);
    EXPECT_LT(step, 0.03 * peak);
  }
}

TEST(MovingLights, PanesRecomposeTheLanternsBounceLight) {
  Cooked c;
  cook(c);
  ASSERT_GE(c.lantern, 0);
  EXPECT_EQ(c.view.moving_light_count(), 1u);
  EXPECT_GE(c.view.pane_count(), 64u);
  EXPECT_GE(c.view.moving_index(uint32_t(c.lantern)), 0);
  EXPECT_TRUE(c.view.has_indirect_map());  // auto lays the charts on blocks for the panes

  recomposes_the_lanterns_bounce_light(c, "panes");
}

// Anchors (pack_format.h, "Anchors"): the same poses, bars and checks as the panes' above, at a
// 0.5 m lattice.
TEST(MovingLights, AnchorsRecomposeTheLanternsBounceLight) {
  Cooked c;
  cook(c, false, -1, 0.5f);
  ASSERT_GE(c.lantern, 0);
  ASSERT_GT(c.view.pane_count(), 0u);
  for (uint32_t k = 0; k < c.view.pane_count(); ++k) {
    ASSERT_TRUE(is_anchor(c.view.pane(k)));
    EXPECT_EQ(c.view.pane(k).radius, 0.5f);
  }
  recomposes_the_lanterns_bounce_light(c, "anchors");
}

// Panes lie where bounce light can come from and keep to one room: no pane takes the outside of
// the rooms' shell or the floor under the rug (no gather ray reads them: light on them bounces
// nowhere), every open texel of the rooms is in one, and the refinement splits the panes a light
// in front of them lights unevenly, so that a pane running along the south wall through the
// doorway into the other room (whose entry points all see one another) is split at the door.
TEST(MovingLights, PanesCoverTheRoomsAndKeepToOneRoom) {
  Cooked c;
  cook(c);
  ASSERT_FALSE(c.maps.panes.empty());
  const std::vector<int32_t> pane_of = pane_of_texels(c.maps.panes, c.p.texels.valid.size());
  size_t outside = 0, under_rug = 0, open = 0, open_in_pane = 0;
  for (size_t t = 0; t < c.p.texels.valid.size(); ++t) {
    if (!c.p.texels.valid[t]) continue;
    const glm::vec3 q = c.p.texels.position[t], n = c.p.texels.normal[t];
    // The shell's outer faces: beyond the rooms and facing away from them (a floor texel at a
    // wall's foot may have its sample point under the wall, at the shell's edge).
    const float m = 0.02f;  // the texels' sample points sit on their surfaces
    const bool out = (n.x > 0.5f && q.x > 4.0f + m) || (n.x < -0.5f && q.x < -4.0f - m) ||
                     (n.z > 0.5f && q.z > 2.0f + m) || (n.z < -0.5f && q.z < -2.0f - m) ||
                     (n.y < -0.5f && q.y < -m) || (n.y > 0.5f && q.y > 2.5f + m);
    // Floor texels under the rug (2 cm thick), a texel (about 0.3 m on this page) in from its
    // edge.
    const float in = 0.35f;
    const bool rug = q.y < 0.01f && n.y > 0.5f && q.x > -3.0f + in && q.x < -1.0f - in &&
                     q.z > -1.5f + in && q.z < 0.5f - in;
    const bool in_pane = pane_of[t] >= 0;
    outside += out && in_pane;
    under_rug += rug && in_pane;
    // Open floor of room B, away from the walls, the partition and the lamp's foot.
    if (q.y < m && n.y > 0.5f && q.x > 0.5f && q.x < 3.5f && q.z > -1.5f && q.z < 1.5f) {
      ++open;
      open_in_pane += in_pane;
    }
  }
  EXPECT_EQ(outside, 0u);
  EXPECT_EQ(under_rug, 0u);
  ASSERT_GT(open, 0u);
  EXPECT_EQ(open_in_pane, open);

  // Texels of the other room in a pane: the smaller side of every pane, room A (x < -0.15)
  // against room B (x > 0.15), over all pane texels.
  size_t minority = 0, total = 0;
  for (const PaneMap& pane : c.maps.panes) {
    size_t a = 0, b = 0;
    for (uint32_t t : pane.texels) {
      a += c.p.texels.position[t].x < -0.15f;
      b += c.p.texels.position[t].x > 0.15f;
    }
    minority += std::min(a, b);
    total += pane.texels.size();
  }
  std::printf("%zu panes, %zu texels, %zu of them on the smaller room's side of their pane\n",
              c.maps.panes.size(), total, minority);
  EXPECT_LT(double(minority), 0.01 * double(total));
}

// Panes stored at level 1 (pack_format.h, "Magnified patches"; the default) against level 0:
// every pane patch is magnified and no other patch changes, the panes take about a quarter of the
// atlas texels, and the recomposed bounce light stays what level 0 gives, up to the magnification
// of smooth light.
TEST(MovingLights, PanesAtLevelOneTakeAQuarterOfTheAtlasAndKeepTheirLight) {
  Cooked c0, c1;
  cook(c0, false, 0);
  cook(c1, false, 1);
  ASSERT_GE(c0.lantern, 0);
  ASSERT_GE(c1.lantern, 0);
  struct Panes {
    uint64_t atlas_texels = 0;  // channel-texels
    uint32_t patches = 0, at_level_1 = 0, others_magnified = 0;
  };
  auto panes = [](const PackView& v) {
    Panes r;
    for (uint32_t i = 0; i < v.patch_count(); ++i) {
      const pack::PatchRecord& p = v.patch(i);
      const pack::GroupRecord& g = v.group(p.group);
      const uint32_t level = pack::patch_level(p.flags);
      if (g.light == pack::kNone16 || v.light(g.light).type != pack::kLightPane) {
        r.others_magnified += level > 0 ? 1 : 0;
        continue;
      }
      ++r.patches;
      r.at_level_1 += level == 1 ? 1 : 0;
      r.atlas_texels += uint64_t(pack::patch_atlas_side(p.width, level)) *
                        pack::patch_atlas_side(p.height, level) * p.channel_count;
    }
    return r;
  };
  const Panes p0 = panes(c0.view), p1 = panes(c1.view);
  EXPECT_GT(p0.patches, 0u);
  EXPECT_EQ(p0.at_level_1, 0u);
  EXPECT_EQ(p1.at_level_1, p1.patches);  // every pane patch at level 1, nothing else
  // The light-map patches' levels are chosen on their own (PackOptions::max_patch_level): the
  // pane level leaves them as they are.
  EXPECT_EQ(p0.others_magnified, p1.others_magnified);
  const uint64_t t0 = p0.atlas_texels, t1 = p1.atlas_texels;
  std::printf("pane atlas channel-texels: level 0 %llu, level 1 %llu (%.3fx)\n",
              static_cast<unsigned long long>(t0), static_cast<unsigned long long>(t1),
              double(t1) / double(t0));
  EXPECT_LT(double(t1), 0.35 * double(t0));

  const std::vector<float> off0 = recompose(c0, lantern_off()), off1 = recompose(c1, lantern_off());
  EXPECT_EQ(off0, off1);  // no pane drawn: the same maps
  const glm::vec3 poses[] = {{-2.0f, 1.2f, -1.0f}, {0.0f, 1.2f, 1.5f}, {2.0f, 1.2f, 1.5f}};
  for (const glm::vec3& pose : poses) {
    const std::vector<float> a = minus(recompose(c0, lantern_at(pose)), off0);
    const std::vector<float> b = minus(recompose(c1, lantern_at(pose)), off1);
    const Agreement g = agreement(c1, b, a);
    std::printf(
        "lantern at (%.1f, %.1f, %.1f): level 1 against level 0, relative RMSE %.2f %%, "
        "bias %+.2f %%\n",
        pose.x, pose.y, pose.z, 100.0 * g.rel_rmse, 100.0 * g.bias);
    // Measured 16.6 / 15.2 / 16.6 %, bias -1.7 / -1.8 / -3.1 %: this 128 page's indirect map is
    // 64 x 64, so a level-1 pane patch spans a wall in a few texels (on the full inn, level 1
    // adds 0.6-1.8 points against bake-state: docs/moving_lights.md). A patch read from the
    // wrong texels or misplaced is far outside these bars.
    EXPECT_LT(g.rel_rmse, 0.22);
    EXPECT_LT(std::fabs(g.bias), 0.05);
  }
}

TEST(MovingLights, BakeStateHoldsTheMovingLightsBounceOnlyUnlessAsked) {
  Cooked c;
  cook(c);
  const glm::vec3 pose(-2.0f, 1.2f, -1.0f);
  const std::vector<float> bounce = baked(c, lantern_at(pose));
  c.bake.moving_direct = true;
  const std::vector<float> lit = baked(c, lantern_at(pose));
  // The rug's texel under the lantern: its direct light, 3 cd * cos / d^2 (about 2.2 lux in the
  // red channel, colour (1, 0.8, 0.55)), is what only the picture option adds.
  size_t under = 0;
  float best = 1e9f;
  for (size_t t = 0; t < c.p.texels.valid.size(); ++t) {
    if (!c.p.texels.valid[t] || c.p.texels.normal[t].y < 0.9f) continue;
    if (c.p.texels.position[t].y < 0.015f) continue;  // the rug's top, 2 cm up
    const glm::vec3 d = c.p.texels.position[t] - glm::vec3(pose.x, 0.0f, pose.z);
    if (glm::length(d) < best) {
      best = glm::length(d);
      under = t;
    }
  }
  ASSERT_LT(best, 0.1f);
  const glm::vec3 to = pose - c.p.texels.position[under];
  const float expected = 3.0f * (to.y / glm::length(to)) / glm::dot(to, to);
  const float direct = lit[under * 3] - bounce[under * 3];
  EXPECT_NEAR(direct, expected, 0.1f * expected);
}

using Sh = std::array<float, pack::kProbeShCount * 3>;

// The runtime's probes for a state: LightProbes rebuilt from the pack for its SceneState.
std::vector<Sh> runtime_probes(const Cooked& c, const StateSpec& spec) {
  SceneState state;
  set_state(c, spec, state);
  LightProbes probes;
  Error error;
  EXPECT_EQ(probes.init(c.view, &error), Status::kOk) << error.message;
  EXPECT_EQ(probes.rebuild(state), Status::kOk);
  std::vector<Sh> out(probes.probe_count());
  for (uint32_t i = 0; i < probes.probe_count(); ++i) probes.probe_sh(i, out[i].data());
  return out;
}

// The probes lit directly from bake-state's map of the state with the lantern's direct light on
// the surfaces (probes.h: the precondition of bake_state_probes for a moving light).
std::vector<Sh> state_probes(Cooked& c, const StateSpec& spec) {
  Progress progress(true);
  BakeOptions b = c.bake;
  b.moving_direct = true;
  const FloatImage map = cook_state(c.p, spec, b, progress, c.report);
  const auto sh = bake_state_probes(c.probes, c.p.scene, c.p.layout, c.p.texels, *c.p.tracer, map,
                                    spec, probe_options(c.bake));
  return std::vector<Sh>(sh.begin(), sh.end());
}

std::vector<Sh> minus(const std::vector<Sh>& a, const std::vector<Sh>& b) {
  std::vector<Sh> d(a.size());
  for (size_t i = 0; i < a.size(); ++i)
    for (size_t k = 0; k < d[i].size(); ++k) d[i][k] = a[i][k] - b[i][k];
  return d;
}

// The irradiance facing the six axes, all channels, summed with `use`(probe, got, want).
template <typename Use>
void axis_irradiance(const std::vector<Sh>& got, const std::vector<Sh>& want, const Use& use) {
  static const float kAxes[6][3] = {{1, 0, 0},  {-1, 0, 0}, {0, 1, 0},
                                    {0, -1, 0}, {0, 0, 1},  {0, 0, -1}};
  for (size_t i = 0; i < got.size(); ++i)
    for (const auto& n : kAxes) {
      float g[3], w[3];
      sh_irradiance(got[i].data(), n[0], n[1], n[2], g);
      sh_irradiance(want[i].data(), n[0], n[1], n[2], w);
      for (int ch = 0; ch < 3; ++ch) use(i, double(g[ch]), double(w[ch]));
    }
}

// The lantern's light in the probes: the runtime's at three poses in room A (its authored one,
// near the doorway, the far corner) less the lantern off, against the probes lit from bake-state's
// maps (direct light included) of the same states, over room A's probes the lantern reaches
// (bake_state_probes' difference not 0), and room B's. 128 page, draft, 64 panes (256 after the
// refinement), 256 rays a probe, 0.5 m grid. The panes' error is the maps' (docs/moving_lights.md):
// uniform irradiance on a pane where the lantern lights it unevenly, worst in the far corner.
// The probes of a pack whose moving light is baked on panes (`anchors` 0) or anchors.
void probes_follow_the_lantern(float anchors) {
  Cooked c;
  cook(c, /*probes=*/true, -1, anchors);
  ASSERT_GE(c.lantern, 0);
  ASSERT_GT(c.view.probe_count(), 0u);
  ASSERT_TRUE(c.p.scene.objects.empty());
  uint32_t pane_sets = 0;
  for (uint32_t s = 0; s < c.view.probe_set_count(); ++s) {
    const pack::ProbeSetRecord& r = c.view.probe_set(s);
    pane_sets += r.light != pack::kNone16 && c.view.light_is_pane(r.light) ? 1 : 0;
  }
  std::printf("%u probes, %u probe sets, %u of them the panes' (of %u panes)\n",
              c.view.probe_count(), c.view.probe_set_count(), pane_sets, c.view.pane_count());
  EXPECT_GT(pane_sets, c.view.pane_count() / 2);

  // Off: every pane's factor is 0 and the probes are exactly the sum of the other sets (here the
  // base alone: lamp_b is static), as before the panes had sets.
  const std::vector<Sh> rt_off = runtime_probes(c, lantern_off());
  {
    SceneState off;
    set_state(c, lantern_off(), off);
    std::vector<double> sum(rt_off.size() * 27, 0.0);
    for (uint32_t s = 0; s < c.view.probe_set_count(); ++s) {
      const pack::ProbeSetRecord& r = c.view.probe_set(s);
      float f[3] = {1.0f, 1.0f, 1.0f};
      if (r.light != pack::kNone16) {
        off.light_factor(r.light, f);
        if (c.view.light_is_pane(r.light)) {
          EXPECT_EQ(f[0] + f[1] + f[2], 0.0f) << "pane light " << r.light;
          continue;
        }
      }
      if (f[0] == 0.0f && f[1] == 0.0f && f[2] == 0.0f) continue;
      for (uint32_t e = r.first_entry; e < r.first_entry + r.entry_count; ++e) {
        const pack::ProbeEntry& pe = c.view.probe_entry(e);
        for (uint32_t k = 0; k < 27; ++k)
          sum[size_t(pe.probe) * 27 + k] += double(f[k % 3]) * double(pe.sh[k]);
      }
    }
    for (size_t i = 0; i < rt_off.size(); ++i)
      for (uint32_t k = 0; k < 27; ++k)
        ASSERT_EQ(rt_off[i][k], float(sum[i * 27 + k])) << "probe " << i;
  }
  const std::vector<Sh> ref_off = state_probes(c, lantern_off());

  const glm::vec3 poses[] = {{-2.0f, 1.2f, -1.0f}, {-1.0f, 1.5f, 1.0f}, {-3.5f, 1.2f, -1.5f}};
  double mean_rmse = 0.0;
  for (const glm::vec3& pose : poses) {
    const std::vector<Sh> got = minus(runtime_probes(c, lantern_at(pose)), rt_off);
    const std::vector<Sh> want = minus(state_probes(c, lantern_at(pose)), ref_off);
    // Room A's probes the lantern reaches; room B's (beyond the partition) apart.
    std::vector<uint8_t> reached(got.size(), 0);
    axis_irradiance(got, want, [&](size_t i, double, double w) {
      if (w != 0.0) reached[i] = 1;
    });
    double sq = 0.0, ref_sq = 0.0, sum = 0.0, ref_sum = 0.0, b_sum = 0.0, b_ref = 0.0;
    size_t count = 0;
    for (size_t i = 0; i < got.size(); ++i)
      count += reached[i] && c.probes.probes[i].position.x < -0.15f;
    axis_irradiance(got, want, [&](size_t i, double g, double w) {
      const float x = c.probes.probes[i].position.x;
      if (x > 0.15f) {
        b_sum += g;
        b_ref += w;
      }
      if (x >= -0.15f || !reached[i]) return;
      sq += (g - w) * (g - w);
      ref_sq += w * w;
      sum += g;
      ref_sum += w;
    });
    ASSERT_GT(ref_sum, 0.0);
    const double rel_rmse = std::sqrt(sq / ref_sq), bias = sum / ref_sum - 1.0;
    std::printf(
        "lantern at (%.1f, %.1f, %.1f): %zu probes in room A, irradiance on 6 axes relative RMSE "
        "%.1f %%, bias %+.1f %%; room B %.3g (bake-state %.3g) of room A's %.3g\n",
        pose.x, pose.y, pose.z, count, 100.0 * rel_rmse, 100.0 * bias, b_sum, b_ref, ref_sum);
    testing::Test::RecordProperty("rel_rmse_" + std::to_string(int(pose.x * 10)),
                                  std::to_string(rel_rmse));
    testing::Test::RecordProperty("bias_" + std::to_string(int(pose.x * 10)), std::to_string(bias));
    // Measured 3.5 / 4.7 / 7.1 % and +0.2 / -1.8 / -0.5 % (10.7 / 19.7 / 35.6 % and -3.5 / -0.3
    // / -18.9 % before the panes kept to texels whose light bounces and were split by how
    // unevenly a light lights them); without the members' own irradiance 1 in the pane sets
    // 41.4 / 44.1 / 58.5 % and -38 / -36 / -47 % (measured with the panes before); without pane
    // sets 100 % and -100 %.
    EXPECT_LT(rel_rmse, 0.15);
    EXPECT_LT(std::fabs(bias), 0.10);
    mean_rmse += rel_rmse / 3.0;
    // Room B, behind the partition, takes what comes through the doorway, at most a little more
    // than bake-state's (measured 1.03 / 1.05 / 1.01 times; 1.55 / 1.24 / 1.23 before).
    EXPECT_LT(b_sum, 1.25 * b_ref + 0.01 * ref_sum);
  }
  EXPECT_LT(mean_rmse, 0.08);  // measured 5.1 % (22.0 % before); without the members 48.0 %
}

TEST(MovingLights, ProbesFollowTheLanternsBounceLight) {
  probes_follow_the_lantern(0.0f);
}

// An anchor's probe sets take the light's irradiance at the texels a probe sees through the
// anchor's depth map (probe_bake.cpp), not the maps' shadow rays: the same bars.
TEST(MovingLights, ProbesFollowTheLanternsBounceLightOnAnchors) {
  probes_follow_the_lantern(0.5f);
}

}  // namespace
}  // namespace lightpatch::cooker
