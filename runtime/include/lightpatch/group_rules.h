// The rules of the patch-group kinds (pack_format.h, GroupKind), written once: the sign with which
// a group enters the map, its factor, when a state draws it, and what a change touches. The
// planner, the CPU recomposers, the light probes (light_probes.h) and the tests' reference all use
// these.
//
//   L = B - sum_{o visible} S_o + sum_l f_l * (C_l - sum_{o visible} S_ol + sum_{a<b visible}
//   P_lab)
//
// (B: base, S_o: static-light shadow of o, C_l: contribution, S_ol: shadow, P_lab: pair
// correction; f_l = on * colour * intensity).
#pragma once

#include <cstdint>

#include "lightpatch/pack_format.h"

namespace lightpatch {

// +1 or -1: shadow groups are subtracted, the others added.
constexpr float group_sign(uint16_t kind) {
  return pack::group_subtracts(kind) ? -1.0f : 1.0f;
}

// The sign of one patch's decoded values in the map: its group's sign, flipped by kFlagNegative.
constexpr float patch_sign(uint16_t group_kind, uint8_t patch_flags) {
  return (patch_flags & pack::kFlagNegative) ? -group_sign(group_kind) : group_sign(group_kind);
}

// Whether the group is scaled by its light's factor f_l; the others (base, static shadows) are
// drawn with the fixed factor 1.
constexpr bool group_has_light(uint16_t kind) {
  return kind == pack::kGroupContribution || kind == pack::kGroupShadow ||
         kind == pack::kGroupPairCorrection;
}

// Whether a state draws the group. `lit(light)`: the light's factor is not zero;
// `visible(object)`: the object is visible. `Owner` is a pack::GroupRecord or a
// pack::ProbeSetRecord (a probe set follows the state by the same rule as its owner's group).
template <typename Owner, typename Lit, typename Visible>
bool group_active(const Owner& g, Lit&& lit, Visible&& visible) {
  switch (g.kind) {
    case pack::kGroupBase:
      return true;
    case pack::kGroupStaticShadow:
      return visible(g.object_a);
    case pack::kGroupContribution:
      return lit(g.light);
    case pack::kGroupShadow:
      return lit(g.light) && visible(g.object_a);
    case pack::kGroupPairCorrection:
      return lit(g.light) && visible(g.object_a) && visible(g.object_b);
    default:
      return false;
  }
}

// Whether object `o`'s visibility decides whether the group is drawn.
constexpr bool group_names_object(const pack::GroupRecord& g, uint32_t o) {
  return (g.kind == pack::kGroupStaticShadow || g.kind == pack::kGroupShadow ||
          g.kind == pack::kGroupPairCorrection) &&
         (g.object_a == o || (g.kind == pack::kGroupPairCorrection && g.object_b == o));
}

// What a change touches. A change of light l's factor from a to b (both states otherwise equal)
// redraws with factor b - a every group of l that is drawn while l is lit. A toggle of object o
// draws, with + or - the group's factor, every group naming o that is drawn while o is visible.
template <typename Visible>
bool light_change_touches(const pack::GroupRecord& g, uint32_t l, Visible&& visible) {
  return group_has_light(g.kind) && g.light == l &&
         group_active(
             g, [](uint32_t) { return true; }, visible);
}
template <typename Lit, typename Visible>
bool object_change_touches(const pack::GroupRecord& g, uint32_t o, Lit&& lit, Visible&& visible) {
  return group_names_object(g, o) &&
         group_active(g, lit, [&](uint32_t x) { return x == o || visible(x); });
}

}  // namespace lightpatch
