// Moving lights (pack_format.h, "Moving lights"; moving_lights.h): the pane weights against closed
// forms, the depth map's mapping and its inverse, visibility behind an occluder, the pack
// validation of the two sections (one refusal per rule, truncation, flipped bytes), SceneState's
// poses and panes, and the CPU recomposer and the light probes moving a light against an
// independent evaluation.
#include "lightpatch/moving_lights.h"

#include <gtest/gtest.h>

#include <cmath>
#include <cstring>
#include <functional>
#include <string>
#include <vector>

#include "lightpatch/cpu_recomposer.h"
#include "lightpatch/light_probes.h"
#include "lightpatch/pack_view.h"
#include "lightpatch/planner.h"
#include "lightpatch/scene_state.h"
#include "runtime/map_reference.h"
#include "runtime/pack_checks.h"
#include "runtime/synthetic_pack.h"

namespace lightpatch {
namespace {

using pack::kPaneDepthSize;
using testing::make_synthetic_pack;
using testing::open_message;
using testing::SyntheticOptions;
using testing::SyntheticPack;

// A pane at the origin facing +Y with one entry point there, nothing in its depth map.
pack::PaneRecord floor_pane() {
  pack::PaneRecord p{};
  p.light = 0;
  p.normal[1] = 1.0f;
  p.radius = 0.25f;
  p.depth_range = 10.0f;
  p.point_count = 1;
  p.points[0].normal[1] = 1.0f;
  for (uint16_t& d : p.depth) d = 0xFFFFu;
  return p;
}

// `pane` made an anchor (pack_format.h, "Anchors") at its eye on a lattice of `spacing` metres.
pack::PaneRecord as_anchor(pack::PaneRecord pane, float spacing) {
  pane.point_count = 0;
  pane.normal[0] = pane.normal[1] = 0.0f;
  pane.normal[2] = 1.0f;
  pane.radius = spacing;
  for (pack::PanePoint& pt : pane.points) pt = pack::PanePoint{};
  return pane;
}

pack::MovingLightRecord point_light() {
  pack::MovingLightRecord m{};
  m.direction[1] = -1.0f;
  m.inner_cone = 0.3f;
  m.outer_cone = 0.7f;
  return m;
}

LightPose pose_at(float x, float y, float z, float dx = 0.0f, float dy = -1.0f, float dz = 0.0f) {
  return LightPose{{x, y, z}, {dx, dy, dz}};
}

// The forward mapping of pack_format.h's PaneRecord comment, written out again.
void forward_texel(const float n[3], const float d[3], float* u, float* v) {
  float t[3], b[3];
  pack::orthonormal_basis(n, t, b);
  const float dt = d[0] * t[0] + d[1] * t[1] + d[2] * t[2];
  const float db = d[0] * b[0] + d[1] * b[1] + d[2] * b[2];
  const float dn = d[0] * n[0] + d[1] * n[1] + d[2] * n[2];
  const float l1 = std::fabs(dt) + std::fabs(db) + dn;
  const float p = dt / l1, q = db / l1;
  *u = (p + q + 1.0f) * 0.5f * kPaneDepthSize - 0.5f;
  *v = (p - q + 1.0f) * 0.5f * kPaneDepthSize - 0.5f;
}

TEST(MovingLights, DepthDirectionInvertsTheForwardMapping) {
  const float s = 1.0f / std::sqrt(3.0f);
  const float normals[][3] = {{0, 0, 1},       {0, 0, -1},      {0, 1, 0}, {0, -1, 0},
                              {1, 0, 0},       {-1, 0, 0},      {s, s, s}, {-s, s, -s},
                              {0.6f, 0, 0.8f}, {0, -0.8f, 0.6f}};
  float worst = 0.0f;
  for (const auto& n : normals) {
    for (uint32_t y = 0; y < kPaneDepthSize; ++y) {
      for (uint32_t x = 0; x < kPaneDepthSize; ++x) {
        float d[3];
        pane_depth_direction(n, x, y, d);
        const float len = std::sqrt(d[0] * d[0] + d[1] * d[1] + d[2] * d[2]);
        ASSERT_NEAR(len, 1.0f, 1e-5f);
        ASSERT_GE(d[0] * n[0] + d[1] * n[1] + d[2] * n[2], 0.0f);  // in the hemisphere
        float u, v;
        forward_texel(n, d, &u, &v);
        worst = std::fmax(worst, std::fmax(std::fabs(u - float(x)), std::fabs(v - float(y))));
      }
    }
  }
  EXPECT_LT(worst, 1e-4f);  // texel centres, to float rounding
}

TEST(MovingLights, VisibilityWithoutOccludersIsOneInFrontAndZeroBehind) {
  const pack::PaneRecord p = floor_pane();
  const float front[3] = {0.3f, 2.0f, -0.4f}, behind[3] = {0.3f, -0.1f, 0.0f},
              grazing[3] = {5.0f, 1e-3f, 0.0f}, on_plane[3] = {1.0f, 0.0f, 0.0f};
  EXPECT_EQ(pane_visibility(p, front), 1.0f);
  EXPECT_EQ(pane_visibility(p, grazing), 1.0f);
  EXPECT_EQ(pane_visibility(p, behind), 0.0f);
  EXPECT_EQ(pane_visibility(p, on_plane), 0.0f);
}

TEST(MovingLights, WeightOfAPointLightHasItsClosedForm) {
  const pack::PaneRecord p = floor_pane();
  const pack::MovingLightRecord m = point_light();
  // Straight above at 2 m: 1 / d^2.
  EXPECT_FLOAT_EQ(pane_weight(m, pack::kLightPoint, pose_at(0, 2, 0), p), 0.25f);
  // At 60 degrees from the normal, 3 m away: cos / d^2.
  const float th = 1.0471976f;
  const float w =
      pane_weight(m, pack::kLightPoint, pose_at(3 * std::sin(th), 3 * std::cos(th), 0), p);
  EXPECT_NEAR(w, std::cos(th) / 9.0f, 1e-6f);
  // Closer than the pane's radius: the squared distance floored at radius^2.
  EXPECT_FLOAT_EQ(pane_weight(m, pack::kLightPoint, pose_at(0, 0.1f, 0), p), 1.0f / 0.0625f);
  // Two entry points: the mean.
  pack::PaneRecord two = p;
  two.point_count = 2;
  two.points[1].position[0] = 1.0f;
  two.points[1].normal[1] = 1.0f;
  const float e1 = 1.0f / 4.0f, e2 = (2.0f / std::sqrt(5.0f)) / 5.0f;
  EXPECT_NEAR(pane_weight(m, pack::kLightPoint, pose_at(0, 2, 0), two), (e1 + e2) / 2.0f, 1e-6f);
  // Range window: 1 - (d / range)^4 at d = 2, range 4; nothing at the range.
  pack::MovingLightRecord ranged = m;
  ranged.range = 4.0f;
  EXPECT_NEAR(pane_weight(ranged, pack::kLightPoint, pose_at(0, 2, 0), p),
              0.25f * (1.0f - 1.0f / 16.0f), 1e-7f);
  ranged.range = 2.0f;
  EXPECT_EQ(pane_weight(ranged, pack::kLightPoint, pose_at(0, 2, 0), p), 0.0f);
  // Behind the pane: nothing.
  EXPECT_EQ(pane_weight(m, pack::kLightPoint, pose_at(0, -2, 0), p), 0.0f);
}

TEST(MovingLights, WeightOfASpotFollowsItsCone) {
  const pack::PaneRecord p = floor_pane();
  const pack::MovingLightRecord m = point_light();  // inner 0.3, outer 0.7 rad
  // Shining straight at the pane: full.
  EXPECT_FLOAT_EQ(pane_weight(m, pack::kLightSpot, pose_at(0, 2, 0), p), 0.25f);
  // Tilted by an angle a off the pane's direction: KHR's smooth cone.
  auto tilted = [&](float a) {
    return pane_weight(m, pack::kLightSpot, pose_at(0, 2, 0, std::sin(a), -std::cos(a), 0), p);
  };
  const float scale = 1.0f / (std::cos(0.3f) - std::cos(0.7f)), offset = -std::cos(0.7f) * scale;
  for (float a : {0.2f, 0.3f, 0.45f, 0.6f, 0.69f}) {
    const float k = std::fmin(1.0f, std::fmax(0.0f, std::cos(a) * scale + offset));
    EXPECT_NEAR(tilted(a), 0.25f * k * k, 1e-6f) << a;
  }
  EXPECT_EQ(tilted(0.7001f), 0.0f);  // at the outer cone's edge and beyond: nothing
  EXPECT_EQ(tilted(1.2f), 0.0f);
  EXPECT_NEAR(tilted(0.3f), 0.25f, 1e-6f);  // the inner cone: full
  // A point light ignores its direction.
  EXPECT_FLOAT_EQ(pane_weight(m, pack::kLightPoint, pose_at(0, 2, 0, 1, 0, 0), p), 0.25f);
}

TEST(MovingLights, AnOccluderHidesTheLightAndVisibilityIsContinuous) {
  // An occluder at 1 m over the texels of the half space x > 0 (in the pane's frame: the
  // directions whose texel column lies right of the middle), nothing elsewhere.
  pack::PaneRecord p = floor_pane();
  for (uint32_t y = 0; y < kPaneDepthSize; ++y)
    for (uint32_t x = 0; x < kPaneDepthSize; ++x)
      p.depth[y * kPaneDepthSize + x] = x >= kPaneDepthSize / 2 ? uint16_t(65535 / 10) : 0xFFFFu;
  // Find a direction on each side: probe along the pane's first tangent.
  float t[3], b[3];
  pack::orthonormal_basis(p.normal, t, b);
  auto at = [&](float s, float h) {
    return std::vector<float>{s * (t[0] + b[0]), h + s * (t[1] + b[1]), s * (t[2] + b[2])};
  };
  // s > 0 moves toward +u (p + q > 0): the occluded columns.
  const std::vector<float> hidden = at(1.0f, 1.5f), clear = at(-1.0f, 1.5f);
  EXPECT_EQ(pane_visibility(p, hidden.data()), 0.0f);
  EXPECT_EQ(pane_visibility(p, clear.data()), 1.0f);
  // In front of the occluder (nearer than 1 m) the light is seen on both sides.
  const std::vector<float> near_hidden = at(0.3f, 0.5f);
  EXPECT_EQ(pane_visibility(p, near_hidden.data()), 1.0f);
  // A walk across the edge in 1 mm steps at 1.5 m: V goes 1 -> 0 without a jump (bilinear over
  // one texel: a step changes V by at most about the step over a texel's width there).
  float previous = pane_visibility(p, at(-1.0f, 1.5f).data()), largest = 0.0f;
  for (int i = 1; i <= 2000; ++i) {
    const float v = pane_visibility(p, at(-1.0f + 1e-3f * float(i), 1.5f).data());
    largest = std::fmax(largest, std::fabs(v - previous));
    previous = v;
  }
  EXPECT_EQ(previous, 0.0f);
  EXPECT_LT(largest, 0.02f);
  EXPECT_GT(largest, 0.0f);
  // The weight carries V: a hidden light gives nothing.
  const pack::MovingLightRecord m = point_light();
  LightPose pose{};
  std::memcpy(pose.position, hidden.data(), sizeof pose.position);
  pose.direction[1] = -1.0f;
  EXPECT_EQ(pane_weight(m, pack::kLightPoint, pose, p), 0.0f);
}

// Anchors: the whole sphere's depth map maps back to its texels, the blend is trilinear over a
// lattice cell where every anchor sees the light, an anchor that does not see it is left out and
// the others renormalised, and outside every cell nothing weighs.
TEST(MovingLights, AnchorDepthDirectionInvertsTheVisibilityLookup) {
  pack::PaneRecord a = as_anchor(floor_pane(), 1.0f);
  for (uint32_t y = 0; y < kPaneDepthSize; ++y) {
    for (uint32_t x = 0; x < kPaneDepthSize; ++x) {
      float dir[3];
      anchor_depth_direction(x, y, dir);
      EXPECT_NEAR(dir[0] * dir[0] + dir[1] * dir[1] + dir[2] * dir[2], 1.0f, 1e-5f);
      // Only texel (x, y) holds a surface, 1 m away: a point 2 m along its centre direction is
      // hidden (the lookup lands on that texel's centre), one 0.5 m along it is seen.
      for (uint16_t& d : a.depth) d = 0xFFFFu;
      a.depth[y * kPaneDepthSize + x] = uint16_t(65535.0f / a.depth_range);
      const float far[3] = {2.0f * dir[0], 2.0f * dir[1], 2.0f * dir[2]};
      const float near[3] = {0.5f * dir[0], 0.5f * dir[1], 0.5f * dir[2]};
      EXPECT_NEAR(anchor_visibility(a, far), 0.0f, 1e-4f) << x << ", " << y;
      EXPECT_EQ(anchor_visibility(a, near), 1.0f) << x << ", " << y;
    }
  }
  const float at[3] = {0.0f, 0.0f, 0.0f};
  EXPECT_EQ(anchor_visibility(a, at), 1.0f);
}

TEST(MovingLights, AnchorsBlendTrilinearlyAndLeaveOutWhatTheyDoNotSee) {
  std::vector<pack::PaneRecord> cell;
  for (int k = 0; k < 8; ++k) {
    pack::PaneRecord a = as_anchor(floor_pane(), 1.0f);
    a.eye[0] = float(k & 1);
    a.eye[1] = float((k >> 1) & 1);
    a.eye[2] = float((k >> 2) & 1);
    cell.push_back(a);
  }
  const float p[3] = {0.25f, 0.5f, 0.875f};
  const float n = anchor_normalizer(cell.data(), uint32_t(cell.size()), p);
  EXPECT_NEAR(n, 1.0f, 1e-6f);  // the tents are a partition of unity
  float sum = 0.0f;
  for (const pack::PaneRecord& a : cell) {
    float tri = 1.0f;
    for (int i = 0; i < 3; ++i) tri *= a.eye[i] > 0.5f ? p[i] : 1.0f - p[i];
    EXPECT_NEAR(anchor_weight(a, p, n), tri, 1e-6f);
    sum += anchor_weight(a, p, n);
  }
  EXPECT_NEAR(sum, 1.0f, 1e-6f);
  // A wall between anchor 0 and the light: anchor 0 weighs nothing, the others share its part.
  for (uint16_t& d : cell[0].depth) d = uint16_t(0.1f / cell[0].depth_range * 65535.0f);
  const float n0 = anchor_normalizer(cell.data(), uint32_t(cell.size()), p);
  EXPECT_NEAR(n0, 1.0f - 0.75f * 0.5f * 0.125f, 1e-6f);
  EXPECT_EQ(anchor_weight(cell[0], p, n0), 0.0f);
  sum = 0.0f;
  for (const pack::PaneRecord& a : cell) sum += anchor_weight(a, p, n0);
  EXPECT_NEAR(sum, 1.0f, 1e-6f);
  // Outside the cell, or where no anchor sees the light: no weight at all.
  const float out[3] = {2.5f, 0.5f, 0.5f};
  EXPECT_EQ(anchor_normalizer(cell.data(), uint32_t(cell.size()), out), 0.0f);
  EXPECT_EQ(anchor_weight(cell[1], out, 0.0f), 0.0f);
  // At an anchor, that anchor alone.
  const float corner[3] = {1.0f, 1.0f, 0.0f};
  const float nc = anchor_normalizer(cell.data(), uint32_t(cell.size()), corner);
  EXPECT_NEAR(anchor_weight(cell[3], corner, nc), 1.0f, 1e-6f);
}

SyntheticOptions moving_options(uint32_t seed = 1) {
  SyntheticOptions o;
  o.seed = seed;
  o.lights = 2;
  o.objects = 2;
  o.moving_lights = 1;
  o.panes = 3;
  return o;
}

TEST(MovingLights, APackWithMovingLightsOpensAndShowsThem) {
  SyntheticOptions o = moving_options();
  o.moving_lights = 2;
  o.panes = 9;
  const SyntheticPack bytes = make_synthetic_pack(o);
  PackView v;
  ASSERT_EQ(open_message(bytes, &v), "");
  EXPECT_EQ(v.light_count(), 13u);
  EXPECT_EQ(v.moving_light_count(), 2u);
  EXPECT_EQ(v.pane_count(), 9u);
  EXPECT_EQ(v.pane_bytes(), 9u * 744u);
  EXPECT_EQ(v.moving_index(2), 0);
  EXPECT_EQ(v.moving_index(3), 1);
  EXPECT_EQ(v.moving_index(0), -1);
  EXPECT_EQ(v.pane_index(4), 0);
  EXPECT_EQ(v.pane_index(12), 8);
  EXPECT_EQ(v.pane_index(13), -1);
  EXPECT_TRUE(v.light_moves(3));
  EXPECT_TRUE(v.light_is_pane(5));
  EXPECT_FALSE(v.light_is_pane(1));
  EXPECT_EQ(v.find_light("moving_1", 8), 3);
  EXPECT_EQ(v.find_light("", 0), -1);  // panes are unnamed and never found
  for (uint32_t k = 0; k < 9; ++k) EXPECT_GE(v.contribution_group(4 + k), 0);
  // Without moving lights: nothing.
  PackView plain;
  ASSERT_EQ(open_message(make_synthetic_pack(SyntheticOptions()), &plain), "");
  EXPECT_EQ(plain.moving_light_count(), 0u);
  EXPECT_EQ(plain.pane_count(), 0u);
  EXPECT_EQ(plain.pane_index(0), -1);
  // Moving lights and no pane is valid.
  o.panes = 0;
  ASSERT_EQ(open_message(make_synthetic_pack(o), &v), "");
  EXPECT_EQ(v.pane_count(), 0u);
}

using MovingEdit =
    std::function<void(std::vector<pack::LightRecord>&, std::vector<pack::MovingLightRecord>&,
                       std::vector<pack::PaneRecord>&)>;

// The message a pack of moving_options() with `edit` applied is refused with.
std::string refusal(const MovingEdit& edit, SyntheticOptions o = moving_options()) {
  o.mutate_moving = edit;
  return open_message(make_synthetic_pack(o));
}

TEST(MovingLights, ValidationRefusesEachMalformedCase) {
  using L = std::vector<pack::LightRecord>;
  using M = std::vector<pack::MovingLightRecord>;
  using P = std::vector<pack::PaneRecord>;
  struct Case {
    const char* expect;
    MovingEdit edit;
  };
  const float nan = std::nanf("");
  const Case cases[] = {
      {"unknown flags", [](L& l, M&, P&) { l[0].flags = 2; }},
      {"flagged moving but not a point or spot",
       [](L& l, M&, P&) { l[2].type = pack::kLightDirectional; }},
      {"light 1 moves and has no groups",
       [](L& l, M&, P&) { l[1].flags = pack::kLightFlagMoving; }},
      {"a pane light with a name", [](L& l, M&, P&) { l[3].name_length = 2; }},
      {"a pane light with flags", [](L& l, M&, P&) { l[3].flags = pack::kLightFlagMoving; }},
      {"intensity", [](L& l, M&, P&) { l[4].intensity = 2.0f; }},
      {"empty name", [](L& l, M&, P&) { l[0].name_length = 0; }},
      {"pane records for", [](L&, M&, P& p) { p.pop_back(); }},
      {"pane records for", [](L&, M&, P& p) { p.push_back(p.back()); }},
      {"not after light", [](L&, M&, P& p) { std::swap(p[0], p[1]); }},
      {"is not a pane light", [](L&, M&, P& p) { p[0].light = 0; }},
      {"is not a light flagged moving", [](L&, M& m, P&) { m[0].light = 1; }},
      {"moving light 0: direction", [](L&, M& m, P&) { m[0].direction[1] = -0.9f; }},
      {"moving light 0: position", [nan](L&, M& m, P&) { m[0].position[2] = nan; }},
      {"moving light 0: range", [](L&, M& m, P&) { m[0].range = -1.0f; }},
      {"moving light 0: radius", [nan](L&, M& m, P&) { m[0].radius = nan; }},
      {"moving light 0: reserved", [](L&, M& m, P&) { m[0].reserved = 1; }},
      {"cone angles are not finite", [nan](L&, M& m, P&) { m[0].inner_cone = nan; }},
      {"pane 1: normal", [](L&, M&, P& p) { p[1].normal[0] = 0.1f; }},
      {"pane 0: eye", [nan](L&, M&, P& p) { p[0].eye[0] = nan; }},
      {"pane 2: radius", [](L&, M&, P& p) { p[2].radius = 0.0f; }},
      {"pane 2: depth range", [](L&, M&, P& p) { p[2].depth_range = -1.0f; }},
      // No entry points: an anchor (pack_format.h, "Anchors"), with an anchor's fields.
      {"anchor 0: normal is not (0, 0, 1)", [](L&, M&, P& p) { p[0].point_count = 0; }},
      {"pane 1: a pane among anchors", [](L&, M&, P& p) { p[0] = as_anchor(p[0], p[0].radius); }},
      {"pane 2: an anchor among panes", [](L&, M&, P& p) { p[2] = as_anchor(p[2], p[2].radius); }},
      {"anchor 1: spacing differs from anchor 0's",
       [](L&, M&, P& p) {
         for (size_t k = 0; k < p.size(); ++k) p[k] = as_anchor(p[k], k == 1 ? 2.0f : 1.0f);
       }},
      {"unused entry point 3 not zero",
       [](L&, M&, P& p) {
         for (pack::PaneRecord& r : p) r = as_anchor(r, 1.0f);
         p[0].points[3].normal[0] = 1.0f;
       }},
      {"9 entry points", [](L&, M&, P& p) { p[0].point_count = 9; }},
      {"unused entry point 5 not zero", [](L&, M&, P& p) { p[0].points[5].position[0] = 1.0f; }},
      {"entry point 0 normal", [](L&, M&, P& p) { p[0].points[0].normal[1] = 2.0f; }},
      {"entry point 0 position", [nan](L&, M&, P& p) { p[0].points[0].position[1] = nan; }},
  };
  for (const Case& c : cases) {
    const std::string m = refusal(c.edit);
    EXPECT_NE(m.find(c.expect), std::string::npos)
        << "expected '" << c.expect << "', got '" << m << "'";
  }
  // Every record an anchor of one lattice: a valid pack.
  EXPECT_EQ(refusal([](L&, M&, P& p) {
              for (pack::PaneRecord& r : p) r = as_anchor(r, 1.0f);
            }),
            "");
  // Two lights flagged moving, one record; a flagged light without the sections.
  SyntheticOptions two = moving_options();
  two.moving_lights = 2;
  EXPECT_NE(refusal([](L&, M& m, P&) { m.pop_back(); }, two).find("1 moving light records for 2"),
            std::string::npos);
  SyntheticOptions none;
  EXPECT_NE(refusal([](L& l, M&, P&) { l[0].flags = pack::kLightFlagMoving; }, none)
                .find("flagged moving but no moving lights section"),
            std::string::npos);
  // A spot's cone.
  SyntheticOptions spot = moving_options();
  spot.moving_spot = true;
  EXPECT_EQ(refusal({}, spot), "");
  EXPECT_NE(refusal([](L&, M& m, P&) { m[0].outer_cone = 1.6f; }, spot).find("spot cone"),
            std::string::npos);
  EXPECT_NE(refusal([](L&, M& m, P&) { m[0].inner_cone = 0.8f; }, spot).find("spot cone"),
            std::string::npos);
  // Groups: a moving light with one, a pane with a shadow group.
  SyntheticOptions g = moving_options();
  g.moving_light_group = true;
  EXPECT_NE(open_message(make_synthetic_pack(g)).find("moves and has no groups"),
            std::string::npos);
  g = moving_options();
  g.pane_shadow_group = true;
  EXPECT_NE(open_message(make_synthetic_pack(g)).find("has only a contribution group"),
            std::string::npos);
  // Sections: each without the other, a moving light without its section.
  g = moving_options();
  g.drop_section = pack::kSectionPanes;
  EXPECT_NE(open_message(make_synthetic_pack(g)).find("without a panes section"),
            std::string::npos);
  g.drop_section = pack::kSectionMovingLights;
  EXPECT_NE(open_message(make_synthetic_pack(g)).find("panes section without"), std::string::npos);
}

// Golden values of moving.lpk (format version 7 with 1 moving light and 3 panes; a pack_load
// fuzz seed too).
constexpr uint64_t kMovingSize = 21760;
constexpr uint32_t kMovingCrc = 0xc95588fau;

TEST(MovingLights, GoldenBytesOfAPackWithMovingLights) {
  const SyntheticPack built = make_synthetic_pack(moving_options(2));
  const uint8_t* b = reinterpret_cast<const uint8_t*>(built.data());
  testing::expect_committed_pack(b, built.size, "moving.lpk", kMovingSize, kMovingCrc);
  PackView v;
  ASSERT_EQ(open_message(built, &v), "");
  // Pinned offsets: a moving light's range, a pane's first entry point and depth texel.
  const uint8_t* m = reinterpret_cast<const uint8_t*>(&v.moving_light(0));
  float range;
  std::memcpy(&range, m + 28, 4);
  EXPECT_EQ(range, v.moving_light(0).range);
  const uint8_t* p = reinterpret_cast<const uint8_t*>(&v.pane(0));
  float x;
  std::memcpy(&x, p + 40, 4);
  EXPECT_EQ(x, v.pane(0).points[0].position[0]);
  uint16_t depth;
  std::memcpy(&depth, p + 232, 2);
  EXPECT_EQ(depth, v.pane(0).depth[0]);
}

TEST(MovingLights, TruncatedAtEveryByteIsRefused) {
  const SyntheticPack bytes = make_synthetic_pack(moving_options(2));
  testing::expect_truncations_refused(bytes.data(), bytes.size);
}

// Uses the moving-light accessors, the weights and a SceneState on a view (ASan: no reads out of
// bounds; every weight finite).
void exercise(const PackView& v) {
  SceneState st;
  ASSERT_EQ(st.init(v, nullptr), Status::kOk);
  for (uint32_t l = 0; l < v.light_count(); ++l) {
    float f[3];
    st.light_factor(l, f);
    for (float c : f) ASSERT_TRUE(std::isfinite(c) && c >= 0.0f);
    (void)v.moving_index(l);
    (void)v.pane_index(l);
  }
}

TEST(MovingLights, FlippedBytesInTheMovingSectionsAreRefusedOrSafe) {
  const SyntheticPack bytes = make_synthetic_pack(moving_options(3));
  const uint8_t* b = reinterpret_cast<const uint8_t*>(bytes.data());
  const std::vector<uint8_t> all(b, b + bytes.size);
  PackView original;
  ASSERT_TRUE(bytes.open(&original, nullptr));
  // The light table, then the two sections (at the end of the file).
  const uint64_t lights = uint64_t(reinterpret_cast<const uint8_t*>(&original.light(0)) - b);
  testing::FlipCounts n = testing::flip_bytes(all, lights, lights + original.light_count() * 32, 1,
                                              [](const PackView& v) { exercise(v); });
  const uint64_t begin = uint64_t(reinterpret_cast<const uint8_t*>(&original.moving_light(0)) - b);
  // Every byte of the records, the depth maps sparsely.
  const uint64_t records_end =
      uint64_t(reinterpret_cast<const uint8_t*>(&original.pane(0).depth[0]) - b);
  const testing::FlipCounts m =
      testing::flip_bytes(all, begin, records_end, 1, [](const PackView& v) { exercise(v); });
  const testing::FlipCounts d =
      testing::flip_bytes(all, records_end, bytes.size, 17, [](const PackView& v) { exercise(v); });
  EXPECT_GT(n.refused_fixed + m.refused_fixed, 0);
  EXPECT_GT(m.refused_raw, 0);
  EXPECT_GT(m.accepted, 0);  // e.g. a position moved to another finite value
  EXPECT_GT(d.accepted, 0);  // any depth is valid
}

TEST(MovingLights, AVersion4PackIsRefusedWithAskingToCookAgain) {
  SyntheticOptions o;
  o.mutate = [](pack::Header& h, std::vector<pack::PatchRecord>&) { h.version = 4; };
  const std::string m = open_message(make_synthetic_pack(o));
  EXPECT_NE(m.find("version 4 is not supported (this reader: 7)"), std::string::npos) << m;
  EXPECT_NE(m.find("cook the scene again"), std::string::npos) << m;
}

TEST(MovingLights, SceneStateHoldsPosesAndDerivesPaneFactors) {
  const SyntheticPack bytes = make_synthetic_pack(moving_options());
  PackView v;
  ASSERT_EQ(open_message(bytes, &v), "");
  SceneState st;
  ASSERT_EQ(st.init(v, nullptr), Status::kOk);
  const uint32_t lantern = 2, pane = 3;
  // Authored pose and factors: the panes' authored colour is their factor.
  EXPECT_EQ(st.light_pose(lantern).position[0], v.moving_light(0).position[0]);
  EXPECT_EQ(st.light_pose(0).position[1], 0.0f);
  for (uint32_t k = 0; k < v.pane_count(); ++k) {
    float f[3];
    st.light_factor(pane + k, f);
    for (int c = 0; c < 3; ++c) EXPECT_EQ(f[c], v.light(pane + k).color[c]);
  }
  // Panes take no setter; poses only for a moving light, in range.
  const float rgb[3] = {1, 1, 1};
  EXPECT_EQ(st.set_light_on(pane, false), Status::kInvalidArgument);
  EXPECT_EQ(st.set_light_color(pane, rgb), Status::kInvalidArgument);
  EXPECT_EQ(st.set_light_intensity(pane, 2.0f), Status::kInvalidArgument);
  EXPECT_EQ(st.set_light(pane, LightState{true, {1, 1, 1}, 1}), Status::kInvalidArgument);
  EXPECT_EQ(st.set_light_pose(0, pose_at(0, 1, 0)), Status::kInvalidArgument);
  EXPECT_EQ(st.set_light_pose(pane, pose_at(0, 1, 0)), Status::kInvalidArgument);
  EXPECT_EQ(st.set_light_pose(lantern, pose_at(std::nanf(""), 1, 0)), Status::kInvalidArgument);
  EXPECT_EQ(st.set_light_pose(lantern, pose_at(2e6f, 1, 0)), Status::kInvalidArgument);
  EXPECT_EQ(st.set_light_pose(lantern, pose_at(0, 1, 0, 0, -0.99f, 0)), Status::kInvalidArgument);
  EXPECT_EQ(st.light_pose(lantern).position[0], v.moving_light(0).position[0]);  // unchanged
  // Within 1e-3 of unit: accepted, stored normalised.
  ASSERT_EQ(st.set_light_pose(lantern, pose_at(0.5f, 1, 0, 0, -1.0005f, 0)), Status::kOk);
  EXPECT_EQ(st.light_pose(lantern).direction[1], -1.0f);
  // The pane factor follows the pose, the colour, the intensity and on.
  float before[3], after[3];
  st.light_factor(pane, before);
  ASSERT_EQ(st.set_light_pose(lantern, pose_at(-1.0f, 0.6f, -1.0f)), Status::kOk);
  st.light_factor(pane, after);
  EXPECT_NE(before[0], after[0]);
  const float w =
      pane_weight(v.moving_light(0), v.light(lantern).type, st.light_pose(lantern), v.pane(0));
  const float lc = v.light(lantern).color[1] * v.light(lantern).intensity;
  EXPECT_EQ(after[1], lc * w);
  ASSERT_EQ(st.set_light_on(lantern, false), Status::kOk);
  st.light_factor(pane, after);
  EXPECT_EQ(after[0] + after[1] + after[2], 0.0f);
  // assign() copies poses.
  SceneState copy;
  ASSERT_EQ(copy.init(v, nullptr), Status::kOk);
  ASSERT_EQ(copy.assign(st), Status::kOk);
  EXPECT_EQ(copy.light_pose(lantern).position[0], -1.0f);
}

// f_pane computed here from pane_weight and the lights' records alone: the test's reference.
void reference_factors(const PackView& v, const bool on[], const float intensity[],
                       const LightPose poses[], std::vector<float>* factors) {
  factors->assign(size_t(v.light_count()) * 3, 0.0f);
  for (uint32_t l = 0; l < v.light_count(); ++l) {
    const pack::LightRecord& r = v.light(l);
    if (r.type == pack::kLightPane || (r.flags & pack::kLightFlagMoving)) continue;
    for (int c = 0; c < 3; ++c) (*factors)[l * 3 + c] = r.color[c] * r.intensity;
  }
  for (uint32_t k = 0; k < v.pane_count(); ++k) {
    const uint32_t pl = v.pane(k).light;
    for (uint32_t m = 0; m < v.moving_light_count(); ++m) {
      const pack::MovingLightRecord& ml = v.moving_light(m);
      if (!on[m]) continue;
      const float w = pane_weight(ml, v.light(ml.light).type, poses[m], v.pane(k));
      for (int c = 0; c < 3; ++c)
        (*factors)[pl * 3 + c] += v.light(ml.light).color[c] * intensity[m] * w;
    }
  }
}

TEST(MovingLights, CpuRecomposerMovesTheBounceLightExactly) {
  for (bool spot : {false, true}) {
    SyntheticOptions o = moving_options(4);
    o.width = 24;
    o.height = 20;
    o.moving_spot = spot;
    o.moving_range = spot ? 0.0f : 6.0f;
    const SyntheticPack bytes = make_synthetic_pack(o);
    PackView v;
    ASSERT_EQ(open_message(bytes, &v), "");
    ASSERT_EQ(v.moving_light_count(), 1u);
    ASSERT_EQ(v.pane_count(), 3u);
    SceneState st;
    ASSERT_EQ(st.init(v, nullptr), Status::kOk);
    CpuRecomposer cpu;
    ASSERT_EQ(cpu.init(v, nullptr), Status::kOk);
    ASSERT_EQ(cpu.rebuild(st), Status::kOk);
    const uint32_t lantern = v.moving_light(0).light;
    bool on[1] = {true};
    float intensity[1] = {v.light(lantern).intensity};
    double largest = 0.0;
    int moved_panes = 0;
    std::vector<float> previous;
    for (int i = 0; i < 40; ++i) {
      const float a = 0.3f * float(i);
      LightPose pose =
          pose_at(1.5f * std::cos(a) - 0.5f, 0.4f + 0.05f * float(i % 7), 1.2f * std::sin(a));
      // Aimed at the panes' corner (-1.8, 0.3, -1) (a spot's cone sweeps across them).
      const float aim[3] = {-1.8f - pose.position[0], 0.3f - pose.position[1],
                            -1.0f - pose.position[2]};
      const float n = std::sqrt(aim[0] * aim[0] + aim[1] * aim[1] + aim[2] * aim[2]);
      for (int c = 0; c < 3; ++c) pose.direction[c] = aim[c] / n;
      ASSERT_EQ(st.set_light_pose(lantern, pose), Status::kOk);
      if (i == 20) {
        on[0] = false;
        ASSERT_EQ(st.set_light_on(lantern, false), Status::kOk);
      }
      if (i == 25) {
        on[0] = true;
        intensity[0] = 7.5f;
        ASSERT_EQ(st.set_light_on(lantern, true), Status::kOk);
        ASSERT_EQ(st.set_light_intensity(lantern, 7.5f), Status::kOk);
      }
      ASSERT_EQ(i % 10 == 9 ? cpu.rebuild(st) : cpu.apply(st), Status::kOk);
      testing::RefState ref;
      const LightPose poses[1] = {st.light_pose(lantern)};
      reference_factors(v, on, intensity, poses, &ref.factor);
      for (uint32_t ob = 0; ob < v.object_count(); ++ob) ref.visible.push_back(1);
      if (!previous.empty())
        for (uint32_t k = 0; k < 3; ++k)
          moved_panes += ref.factor[(3 + k) * 3] != previous[(3 + k) * 3] ? 1 : 0;
      previous = ref.factor;
      const std::vector<double> maps = testing::presented(v, reference_map(v, ref));
      for (size_t t = 0; t < maps.size(); ++t) {
        largest = std::fmax(
            largest, std::fabs(cpu.presented_maps()[t] - maps[t]) / (1.0 + std::fabs(maps[t])));
      }
    }
    EXPECT_LT(largest, 1e-5) << (spot ? "spot" : "point");
    EXPECT_GT(moved_panes, 40);  // the panes' factors did change along the walk
  }
}

// Every probe's SH from pack_format.h's sum with the lights' factors `factor` (3 per light, the
// panes' included), in double, and per coefficient the sum of its terms' magnitudes.
void probe_reference(const PackView& v, const std::vector<float>& factor,
                     const std::vector<uint8_t>& visible, std::vector<double>* value,
                     std::vector<double>* magnitude) {
  value->assign(size_t(v.probe_count()) * kProbeShFloats, 0.0);
  magnitude->assign(value->size(), 0.0);
  for (uint32_t s = 0; s < v.probe_set_count(); ++s) {
    const pack::ProbeSetRecord& set = v.probe_set(s);
    double f[3] = {1.0, 1.0, 1.0};
    if (set.kind == pack::kGroupContribution || set.kind == pack::kGroupShadow) {
      const double sign = set.kind == pack::kGroupShadow ? -1.0 : 1.0;
      const bool shown = set.kind == pack::kGroupContribution || visible[set.object_a];
      for (int c = 0; c < 3; ++c) f[c] = shown ? sign * factor[size_t(set.light) * 3 + c] : 0.0;
    } else if (set.kind == pack::kGroupStaticShadow) {
      f[0] = f[1] = f[2] = visible[set.object_a] ? -1.0 : 0.0;
    }
    for (uint32_t e = set.first_entry; e < set.first_entry + set.entry_count; ++e) {
      const pack::ProbeEntry& pe = v.probe_entry(e);
      for (uint32_t i = 0; i < kProbeShFloats; ++i) {
        const double term = f[i % 3] * double(pe.sh[i]);
        (*value)[size_t(pe.probe) * kProbeShFloats + i] += term;
        (*magnitude)[size_t(pe.probe) * kProbeShFloats + i] += std::fabs(term);
      }
    }
  }
}

SyntheticOptions pane_probe_options(uint32_t seed) {
  SyntheticOptions o = testing::with_probe_grid(moving_options(seed), 3, 2, 3, seed);
  o.pane_probe_sets = true;
  return o;
}

// A pane's probe set is a contribution set (pack_format.h, "Moving lights"): accepted; a moving
// light's set and a pane's shadow set are refused.
TEST(MovingLights, PanesHaveContributionProbeSetsAndMovingLightsNone) {
  const SyntheticPack bytes = make_synthetic_pack(pane_probe_options(6));  // v reads them
  PackView v;
  ASSERT_EQ(open_message(bytes, &v), "");
  uint32_t pane_sets = 0;
  for (uint32_t s = 0; s < v.probe_set_count(); ++s)
    pane_sets += v.probe_set(s).light != pack::kNone16 && v.light_is_pane(v.probe_set(s).light);
  EXPECT_EQ(pane_sets, v.pane_count());
  // The first pane's set given to the moving light before it (still sorted).
  SyntheticOptions o = pane_probe_options(6);
  o.mutate_probes = [](auto&, auto&, auto&, std::vector<pack::ProbeSetRecord>& sets, auto&) {
    for (pack::ProbeSetRecord& s : sets) {
      if (s.kind == pack::kGroupContribution && s.light == 3) s.light = 2;
    }
  };
  EXPECT_NE(open_message(make_synthetic_pack(o)).find("light 2 moves and has no probe sets"),
            std::string::npos);
  // The last pane's set made its shadow of object 0 (still sorted: no other shadow sets).
  o = pane_probe_options(6);
  o.shadow_probability = 0.0f;
  o.pair_probability = 0.0f;
  o.mutate_probes = [](auto&, auto&, auto&, std::vector<pack::ProbeSetRecord>& sets, auto&) {
    for (pack::ProbeSetRecord& s : sets) {
      if (s.kind == pack::kGroupContribution && s.light == 5) {
        s.kind = pack::kGroupShadow;
        s.object_a = 0;
      }
    }
  };
  EXPECT_NE(open_message(make_synthetic_pack(o)).find("pane light 5 has only a contribution"),
            std::string::npos);
}

// LightProbes weighs the panes' sets by the pane factors, as the light map does: those of the
// SceneState (from the moving light's pose, on and intensity) along a walk, and the planner's
// presented ones (what Runtime pushes to it); with the light off the probes are the sum of the
// other sets, bit for bit.
TEST(MovingLights, LightProbesFollowTheMovingLightThroughItsPanes) {
  const SyntheticPack bytes = make_synthetic_pack(pane_probe_options(7));
  PackView v;
  ASSERT_EQ(open_message(bytes, &v), "");
  SceneState st;
  ASSERT_EQ(st.init(v, nullptr), Status::kOk);
  LightProbes probes;
  ASSERT_EQ(probes.init(v, nullptr), Status::kOk);
  const uint32_t lantern = v.moving_light(0).light;
  bool on[1] = {true};
  float intensity[1] = {v.light(lantern).intensity};
  std::vector<float> factor;
  std::vector<double> want, magnitude;
  const std::vector<uint8_t> visible(v.object_count(), 1);
  std::vector<float> previous;
  int changed = 0;
  for (int i = 0; i < 12; ++i) {
    const float a = 0.5f * float(i);
    ASSERT_EQ(
        st.set_light_pose(lantern, pose_at(1.5f * std::cos(a) - 0.5f, 0.5f, 1.2f * std::sin(a))),
        Status::kOk);
    if (i == 6) {
      intensity[0] = 5.0f;
      ASSERT_EQ(st.set_light_intensity(lantern, intensity[0]), Status::kOk);
    }
    ASSERT_EQ(probes.update(st), Status::kOk);
    const LightPose poses[1] = {st.light_pose(lantern)};
    reference_factors(v, on, intensity, poses, &factor);
    probe_reference(v, factor, visible, &want, &magnitude);
    std::vector<float> now(want.size());
    for (uint32_t p = 0; p < v.probe_count(); ++p) {
      probes.probe_sh(p, now.data() + size_t(p) * kProbeShFloats);
      for (uint32_t k = 0; k < kProbeShFloats; ++k) {
        const size_t j = size_t(p) * kProbeShFloats + k;
        ASSERT_NEAR(now[j], want[j], 1e-5 * magnitude[j] + 1e-7) << "step " << i;
      }
    }
    if (!previous.empty()) changed += now != previous ? 1 : 0;
    previous = now;
  }
  EXPECT_EQ(changed, 11);  // every step moved some probe

  // Off: every pane's factor is 0 and the probes are exactly the other sets' sum (the same
  // additions in the same order as a pack whose panes reach no probe).
  ASSERT_EQ(st.set_light_on(lantern, false), Status::kOk);
  ASSERT_EQ(probes.rebuild(st), Status::kOk);
  for (uint32_t k = 0; k < v.pane_count(); ++k) {
    float f[3];
    st.light_factor(v.pane(k).light, f);
    EXPECT_EQ(f[0] + f[1] + f[2], 0.0f);
  }
  std::vector<double> acc(size_t(v.probe_count()) * kProbeShFloats, 0.0);
  for (uint32_t s = 0; s < v.probe_set_count(); ++s) {
    const pack::ProbeSetRecord& set = v.probe_set(s);
    if (set.light != pack::kNone16 && v.light_is_pane(set.light)) continue;
    float f[3] = {1.0f, 1.0f, 1.0f};
    if (set.kind == pack::kGroupContribution || set.kind == pack::kGroupShadow) {
      st.light_factor(set.light, f);
      if (set.kind == pack::kGroupShadow)
        for (float& c : f) c = -c;
    } else if (set.kind == pack::kGroupStaticShadow) {
      f[0] = f[1] = f[2] = -1.0f;
    }
    if (f[0] == 0.0f && f[1] == 0.0f && f[2] == 0.0f) continue;
    for (uint32_t e = set.first_entry; e < set.first_entry + set.entry_count; ++e) {
      const pack::ProbeEntry& pe = v.probe_entry(e);
      for (uint32_t k = 0; k < kProbeShFloats; ++k)
        acc[size_t(pe.probe) * kProbeShFloats + k] += double(f[k % 3]) * double(pe.sh[k]);
    }
  }
  for (uint32_t p = 0; p < v.probe_count(); ++p) {
    float sh[kProbeShFloats];
    probes.probe_sh(p, sh);
    for (uint32_t k = 0; k < kProbeShFloats; ++k)
      ASSERT_EQ(sh[k], float(acc[size_t(p) * kProbeShFloats + k])) << "probe " << p;
  }

  // Through a planner given the pane factors as Runtime gives them: the presented factors.
  Planner planner;
  Error error;
  ASSERT_EQ(planner.init(v, PlannerLimits(), &error), Status::kOk) << error.message;
  testing::CpuMapSink sink(v, testing::Rounding::kNone);
  LightProbes presented;
  ASSERT_EQ(presented.init(v, nullptr), Status::kOk);
  ASSERT_EQ(st.set_light_on(lantern, true), Status::kOk);
  ASSERT_EQ(st.set_light_pose(lantern, pose_at(-1.0f, 0.7f, 0.2f)), Status::kOk);
  for (uint32_t k = 0; k < v.pane_count(); ++k) {
    float f[3];
    st.light_factor(v.pane(k).light, f);
    ASSERT_EQ(planner.set_light(v.pane(k).light, true, f, 1.0f), Status::kOk);
  }
  for (int frame = 0; frame < 100 && !planner.idle(); ++frame) planner.update(1u << 30, sink);
  ASSERT_TRUE(planner.idle());
  ASSERT_EQ(presented.update(planner), Status::kOk);
  ASSERT_EQ(probes.update(st), Status::kOk);
  for (uint32_t p = 0; p < v.probe_count(); ++p) {
    float a[kProbeShFloats], b[kProbeShFloats];
    presented.probe_sh(p, a);
    probes.probe_sh(p, b);
    for (uint32_t k = 0; k < kProbeShFloats; ++k)
      ASSERT_NEAR(a[k], b[k], 1e-6f * (1.0f + std::fabs(b[k]))) << "probe " << p;
  }
}

}  // namespace
}  // namespace lightpatch
