// Moving lights (pack_format.h, "Moving lights"): the weights that turn the moving lights' poses
// into the factors of the pack's panes, the one copy the cooker (authored factors, depth maps) and
// the runtime (SceneState, Runtime) share.
//
//   f_pane = sum over moving lights m (on) of colour_m * intensity_m * w(m, pane)
//   w(m, pane) = V(m, pane) * (1/M) * sum_{i<M} E(m, x_i, n_i)
//
// E is the irradiance of a unit light (intensity 1 candela, colour (1,1,1)) at the pane's entry
// point x_i with normal n_i, by KHR_lights_punctual as the cooker's direct light computes it
// (cooker/src/direct_light.cpp): max(0, n.l) / max(d^2, radius^2) * range window * spot cone,
// with the squared distance floored at the pane's radius squared (a light touching the pane stays
// finite). V is the pane's filtered visibility of the light's position (pane_visibility()).
// Units: positions in metres, world space; weights in lux per candela (1/m^2).
//
// No allocation, no exceptions; every function is safe for any finite input (a validated pack,
// PackView::open) and returns finite values.
#pragma once

#include <cstdint>

#include "lightpatch/pack_format.h"

namespace lightpatch {

class PackView;
class SceneState;

// Where a moving light is (world space, metres) and where it shines (unit vector; spots only, a
// point light ignores it).
struct LightPose {
  float position[3];
  float direction[3];
};

// What a pose may hold (SceneState::set_light_pose, Runtime::set_light_pose): a position at most
// this far from the origin (metres), a direction of length 1 within this tolerance.
constexpr double kMaxPosePosition = 1.0e6;
constexpr double kPoseUnitTolerance = 1.0e-3;
// Validates a pose against those limits (every value finite) and normalises its direction; false
// (pose unchanged) when it is outside them.
bool normalise_pose(LightPose* pose);

// The pose a pack authors for a moving light.
LightPose authored_pose(const pack::MovingLightRecord& light);

// The unit world direction of the centre of depth texel (x, y) of a pane whose (unit) normal is
// `normal`: the inverse of the hemi-octahedral mapping of pack_format.h's PaneRecord,
//   (s, r) = ((x + 0.5) / N * 2 - 1, (y + 0.5) / N * 2 - 1),  p = (s + r) / 2,  q = (s - r) / 2,
//   z = 1 - |p| - |q|,  dir = normalize(p t + q b + z n)
// with (t, b) = pack::orthonormal_basis(normal), N = kPaneDepthSize. Every texel centre lies in the
// diamond |p| + |q| <= 1 (|p| + |q| = max(|s|, |r|)); a point outside it would fold to the
// hemisphere's rim (z = 0, (p, q) scaled to |p| + |q| = 1). Precondition: x, y < kPaneDepthSize.
void pane_depth_direction(const float normal[3], uint32_t x, uint32_t y, float out_dir[3]);

// The pane's visibility of a light at `light_position` (world space, metres), in [0, 1]: 0 behind
// the pane's plane through its eye (dot(L - eye, normal) <= 0); otherwise the bilinear blend of
// the 4 depth texels around the light's direction (clamped at the map's edges) of
// [|L - eye| <= depth], 65535 meaning no surface (visible at any distance). Continuous in the
// light's position in front of the pane except where it crosses an occluder's depth.
float pane_visibility(const pack::PaneRecord& pane, const float light_position[3]);

// w(m, pane) for a unit moving light (colour (1,1,1), intensity 1) of LightRecord type `type`
// (pack::kLightPoint or pack::kLightSpot: a spot takes its cone from `light`, oriented by
// pose.direction) at `pose`; range from `light` (0: infinite). Lux per candela, finite, >= 0.
float pane_weight(const pack::MovingLightRecord& light, uint32_t type, const LightPose& pose,
                  const pack::PaneRecord& pane);

// Anchors (pack_format.h, "Anchors": a PaneRecord with point_count 0).
inline bool is_anchor(const pack::PaneRecord& pane) {
  return pane.point_count == 0;
}

// The unit world direction of the centre of depth texel (x, y) of an anchor: the inverse of the
// octahedral mapping of pack_format.h's PaneRecord (whole sphere, world axes). Precondition: x, y
// < kPaneDepthSize.
void anchor_depth_direction(uint32_t x, uint32_t y, float out_dir[3]);

// The anchor's visibility of a point at `position` (world space, metres), in [0, 1]: the
// bilinear blend of the 4 depth texels around the point's direction from the anchor (clamped at
// the map's edges) of [distance <= depth] (65535: no surface). 1 at the anchor itself.
float anchor_visibility(const pack::PaneRecord& anchor, const float position[3]);

// The lattice's tent at `position`: prod over axes of max(0, 1 - |position - eye| / radius), in
// [0, 1]; nonzero for the (at most 8) anchors of the lattice cell holding `position`.
float anchor_tent(const pack::PaneRecord& anchor, const float position[3]);

// sum over the pack's anchors b of T(p - b) * V(b, p) for a light at `position`: the denominator
// of w(m, a) (pack_format.h). O(anchors). 0 without anchors.
float anchor_normalizer(const pack::PaneRecord* anchors, uint32_t count, const float position[3]);

// w(m, a) = T(p - a) V(a, p) / normalizer for a light at `position`, `normalizer` from
// anchor_normalizer() of the same position (0 when the normalizer is 0). In [0, 1].
float anchor_weight(const pack::PaneRecord& anchor, const float position[3], float normalizer);

// f_pane (linear RGB, >= 0, finite) of pane `pane` (an index below pack.pane_count()) for the
// moving lights' factors and poses in `state` (a state of `pack`): the sum above, over the moving
// lights in pack order. O(moving lights * points) for a pane, O(moving lights * panes) for an
// anchor (its normalizer); pane_factors() gives every pane's at once in O(moving lights * panes).
void pane_factor(const PackView& pack, uint32_t pane, const SceneState& state, float out_rgb[3]);

// pane_factor() of every pane k < pack.pane_count() into out_rgb[3k..3k+2].
void pane_factors(const PackView& pack, const SceneState& state, float* out_rgb);

}  // namespace lightpatch
