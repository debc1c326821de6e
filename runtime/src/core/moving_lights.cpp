#include "lightpatch/moving_lights.h"

#include <cfloat>
#include <cmath>

#include "lightpatch/pack_view.h"
#include "lightpatch/scene_state.h"

namespace lightpatch {

using namespace pack;

namespace {

float dot3(const float a[3], const float b[3]) {
  return a[0] * b[0] + a[1] * b[1] + a[2] * b[2];
}

float clamp01(float v) {
  return v < 0.0f ? 0.0f : (v > 1.0f ? 1.0f : v);
}

// KHR_lights_punctual's range window, as cooker/src/direct_light.cpp's range_window().
float range_window(float range, float d) {
  if (!(range > 0.0f)) return 1.0f;
  const float x = d / range;
  const float x2 = x * x;
  return clamp01(1.0f - x2 * x2);
}

// The bilinear blend of [dist <= depth] over the 4 depth texels of `record` around square
// coordinates (s, r) in [-1, 1]^2 (pack_format.h, PaneRecord; clamped at the map's edges).
float filtered_visibility(const PaneRecord& record, float s, float r, float dist) {
  constexpr uint32_t kN = kPaneDepthSize;
  const float u = (s + 1.0f) * 0.5f * float(kN) - 0.5f;
  const float v = (r + 1.0f) * 0.5f * float(kN) - 0.5f;
  // (s, r) in [-1, 1]^2 keeps u and v within [-0.5, N - 0.5]: the texel indices below are in
  // range once clamped.
  const float fu = std::floor(u), fv = std::floor(v);
  const float wu = u - fu, wv = v - fv;
  auto clampi = [](float f) { return f < 0.0f ? 0u : (f > float(kN - 1) ? kN - 1 : uint32_t(f)); };
  const uint32_t x0 = clampi(fu), x1 = clampi(fu + 1.0f);
  const uint32_t y0 = clampi(fv), y1 = clampi(fv + 1.0f);
  auto clear = [&](uint32_t x, uint32_t y) {
    const uint16_t depth = record.depth[y * kN + x];
    if (depth == 0xFFFFu) return 1.0f;  // no surface within depth_range
    return dist <= float(depth) / 65535.0f * record.depth_range ? 1.0f : 0.0f;
  };
  const float top = clear(x0, y0) * (1.0f - wu) + clear(x1, y0) * wu;
  const float bottom = clear(x0, y1) * (1.0f - wu) + clear(x1, y1) * wu;
  return clamp01(top * (1.0f - wv) + bottom * wv);
}

// The octahedral map's fold of the lower hemisphere over the square's diagonals (pack_format.h,
// PaneRecord, an anchor's map): (s, r) -> ((1 - |r|) sign(s), (1 - |s|) sign(r)), sign(0) = 1. Its
// own inverse on the square.
void octahedral_fold(float s, float r, float* fs, float* fr) {
  *fs = (1.0f - std::fabs(r)) * (s >= 0.0f ? 1.0f : -1.0f);
  *fr = (1.0f - std::fabs(s)) * (r >= 0.0f ? 1.0f : -1.0f);
}

}  // namespace

bool normalise_pose(LightPose* pose) {
  double p2 = 0.0, d2 = 0.0;
  for (int a = 0; a < 3; ++a) {
    if (!std::isfinite(pose->position[a]) || !std::isfinite(pose->direction[a])) return false;
    p2 += double(pose->position[a]) * pose->position[a];
    d2 += double(pose->direction[a]) * pose->direction[a];
  }
  if (!(p2 <= kMaxPosePosition * kMaxPosePosition)) return false;
  const double len = std::sqrt(d2);
  if (!(std::fabs(len - 1.0) <= kPoseUnitTolerance)) return false;
  for (float& c : pose->direction) c = float(c / len);
  return true;
}

LightPose authored_pose(const MovingLightRecord& light) {
  LightPose p{};
  for (int a = 0; a < 3; ++a) {
    p.position[a] = light.position[a];
    p.direction[a] = light.direction[a];
  }
  return p;
}

void pane_depth_direction(const float normal[3], uint32_t x, uint32_t y, float out_dir[3]) {
  constexpr float n = float(kPaneDepthSize);
  const float s = (float(x) + 0.5f) / n * 2.0f - 1.0f;
  const float r = (float(y) + 0.5f) / n * 2.0f - 1.0f;
  float p = (s + r) * 0.5f;
  float q = (s - r) * 0.5f;
  const float l1 = std::fabs(p) + std::fabs(q);
  if (l1 > 1.0f) {  // never for a texel centre (see the header); kept for any other (s, r)
    p /= l1;
    q /= l1;
  }
  const float z = std::fmax(0.0f, 1.0f - std::fabs(p) - std::fabs(q));
  float t[3], b[3];
  orthonormal_basis(normal, t, b);
  float d[3];
  for (int a = 0; a < 3; ++a) d[a] = p * t[a] + q * b[a] + z * normal[a];
  const float len = std::sqrt(dot3(d, d));
  for (int a = 0; a < 3; ++a) out_dir[a] = d[a] / len;
}

float pane_visibility(const PaneRecord& pane, const float light_position[3]) {
  float d[3];
  for (int a = 0; a < 3; ++a) d[a] = light_position[a] - pane.eye[a];
  const float dn = dot3(d, pane.normal);
  if (!(dn > 0.0f)) return 0.0f;  // behind the pane (or NaN)
  float t[3], b[3];
  orthonormal_basis(pane.normal, t, b);
  const float dt = dot3(d, t), db = dot3(d, b);
  const float l1 = std::fabs(dt) + std::fabs(db) + dn;  // > 0: dn > 0
  const float p = dt / l1, q = db / l1;
  // |p| + |q| <= 1 keeps (s, r) within [-1, 1]^2.
  return filtered_visibility(pane, p + q, p - q, std::sqrt(dot3(d, d)));
}

float pane_weight(const MovingLightRecord& light, uint32_t type, const LightPose& pose,
                  const PaneRecord& pane) {
  const float visibility = pane_visibility(pane, pose.position);
  if (!(visibility > 0.0f)) return 0.0f;
  const bool spot = type == kLightSpot;
  float cone_scale = 0.0f, cone_offset = 0.0f;
  if (spot) {  // direct_light.cpp's spot_attenuation(), computed once per pane
    const float cos_outer = std::cos(light.outer_cone);
    cone_scale = 1.0f / std::fmax(0.001f, std::cos(light.inner_cone) - cos_outer);
    cone_offset = -cos_outer * cone_scale;
  }
  const float floor2 = pane.radius * pane.radius;
  const uint32_t m = pane.point_count < kMaxPanePoints ? pane.point_count : kMaxPanePoints;
  float sum = 0.0f;
  for (uint32_t i = 0; i < m; ++i) {
    const PanePoint& pt = pane.points[i];
    float l[3];
    for (int a = 0; a < 3; ++a) l[a] = pose.position[a] - pt.position[a];
    const float d2 = dot3(l, l);
    const float d = std::sqrt(d2);
    if (!(d > 0.0f) || !std::isfinite(d)) continue;
    for (float& c : l) c /= d;
    const float cos_theta = dot3(pt.normal, l);
    if (!(cos_theta > 0.0f)) continue;
    float e = cos_theta / std::fmax(d2, floor2) * range_window(light.range, d);
    if (spot) {
      const float a = clamp01(
          -(pose.direction[0] * l[0] + pose.direction[1] * l[1] + pose.direction[2] * l[2]) *
              cone_scale +
          cone_offset);
      e *= a * a;
    }
    sum += e;
  }
  const float w = visibility * (sum / float(m > 0 ? m : 1));
  return std::isfinite(w) ? w : FLT_MAX;
}

void anchor_depth_direction(uint32_t x, uint32_t y, float out_dir[3]) {
  constexpr float n = float(kPaneDepthSize);
  const float s = (float(x) + 0.5f) / n * 2.0f - 1.0f;
  const float r = (float(y) + 0.5f) / n * 2.0f - 1.0f;
  float d[3] = {s, r, 1.0f - std::fabs(s) - std::fabs(r)};
  if (d[2] < 0.0f) octahedral_fold(s, r, &d[0], &d[1]);  // the lower hemisphere
  const float len = std::sqrt(dot3(d, d));               // >= 1/sqrt(3): |x| + |y| + |z| = 1
  for (int a = 0; a < 3; ++a) out_dir[a] = d[a] / len;
}

float anchor_visibility(const PaneRecord& anchor, const float position[3]) {
  float d[3];
  for (int a = 0; a < 3; ++a) d[a] = position[a] - anchor.eye[a];
  const float l1 = std::fabs(d[0]) + std::fabs(d[1]) + std::fabs(d[2]);
  if (!(l1 > 0.0f)) return 1.0f;  // at the anchor (or NaN, which the finite inputs exclude)
  float s = d[0] / l1, r = d[1] / l1;
  if (d[2] < 0.0f) octahedral_fold(d[0] / l1, d[1] / l1, &s, &r);
  return filtered_visibility(anchor, s, r, std::sqrt(dot3(d, d)));
}

float anchor_tent(const PaneRecord& anchor, const float position[3]) {
  float t = 1.0f;
  for (int a = 0; a < 3; ++a) {
    const float f = 1.0f - std::fabs(position[a] - anchor.eye[a]) / anchor.radius;
    if (!(f > 0.0f)) return 0.0f;
    t *= f;
  }
  return t;
}

float anchor_normalizer(const PaneRecord* anchors, uint32_t count, const float position[3]) {
  float sum = 0.0f;
  for (uint32_t k = 0; k < count; ++k) {
    const float t = anchor_tent(anchors[k], position);
    if (t > 0.0f) sum += t * anchor_visibility(anchors[k], position);
  }
  return sum;
}

float anchor_weight(const PaneRecord& anchor, const float position[3], float normalizer) {
  if (!(normalizer > 0.0f)) return 0.0f;
  const float t = anchor_tent(anchor, position);
  if (!(t > 0.0f)) return 0.0f;
  // A term of the normalizer over the normalizer: at most 1 but for rounding.
  return clamp01(t * anchor_visibility(anchor, position) / normalizer);
}

namespace {

// out_rgb += f * w, kept finite: as every factor is, so that 0 * f stays 0 (the planner refuses
// what is too bright).
void add_weighted(const float f[3], float w, float out_rgb[3]) {
  for (int c = 0; c < 3; ++c) {
    const float v = out_rgb[c] + f[c] * w;
    out_rgb[c] = std::isfinite(v) ? v : FLT_MAX;
  }
}

}  // namespace

void pane_factors(const PackView& pack, const SceneState& state, float* out_rgb) {
  const uint32_t np = pack.pane_count();
  for (uint32_t k = 0; k < 3 * np; ++k) out_rgb[k] = 0.0f;
  if (np == 0) return;
  // Light by light, so that an anchor lattice's normalizer is computed once per light; each
  // pane's sum runs over the lights in the same order as pane_factor()'s (the same bits).
  for (uint32_t m = 0; m < pack.moving_light_count(); ++m) {
    const MovingLightRecord& ml = pack.moving_light(m);
    float f[3];
    state.light_factor(ml.light, f);
    if (f[0] == 0.0f && f[1] == 0.0f && f[2] == 0.0f) continue;
    const LightPose pose = state.light_pose(ml.light);
    const uint32_t type = pack.light(ml.light).type;
    // A pack's pane records are all panes or all anchors (PackView::open).
    const float normalizer =
        is_anchor(pack.pane(0)) ? anchor_normalizer(&pack.pane(0), np, pose.position) : 0.0f;
    for (uint32_t k = 0; k < np; ++k) {
      const PaneRecord& pr = pack.pane(k);
      add_weighted(f,
                   is_anchor(pr) ? anchor_weight(pr, pose.position, normalizer)
                                 : pane_weight(ml, type, pose, pr),
                   out_rgb + 3 * k);
    }
  }
}

void pane_factor(const PackView& pack, uint32_t pane, const SceneState& state, float out_rgb[3]) {
  out_rgb[0] = out_rgb[1] = out_rgb[2] = 0.0f;
  const PaneRecord& pr = pack.pane(pane);
  for (uint32_t k = 0; k < pack.moving_light_count(); ++k) {
    const MovingLightRecord& m = pack.moving_light(k);
    float f[3];
    state.light_factor(m.light, f);
    if (f[0] == 0.0f && f[1] == 0.0f && f[2] == 0.0f) continue;  // off: no visibility lookup
    const LightPose pose = state.light_pose(m.light);
    const float w =
        is_anchor(pr)
            ? anchor_weight(pr, pose.position,
                            anchor_normalizer(&pack.pane(0), pack.pane_count(), pose.position))
            : pane_weight(m, pack.light(m.light).type, pose, pr);
    add_weighted(f, w, out_rgb);
  }
}

}  // namespace lightpatch
