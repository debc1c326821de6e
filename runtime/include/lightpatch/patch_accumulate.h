// Adding decoded patches to a light map held in host memory: the one CPU drawing loop (the
// runtime's CPU path, the CPU reference recomposer, the planner's magnitude bounds and the tests'
// reference all draw through it).
#pragma once

#include <cmath>
#include <cstddef>
#include <cstdint>

#include "lightpatch/group_rules.h"
#include "lightpatch/pack_view.h"
#include "lightpatch/patch_decode.h"

namespace lightpatch {

// Adds factor * (signed decoded value) of every texel of patches [first, first + count) to
// `maps`: the pack's map set (pack_view.h: the light map, then the indirect map if the pack has
// one; RGB, 3 values per texel, row 0 = top), each patch into its own target. With `absolute`,
// adds |factor * value| (magnitude bounds). A grey patch (one channel) adds its value to all three
// channels, or to its one destination channel (pack::patch_destination). The patches must be
// valid indices of a validated pack.
template <typename T>
void add_patches(const PackView& pack, uint32_t first, uint32_t count, const T factor[3], T* maps,
                 bool absolute = false) {
  for (uint32_t i = first; i < first + count; ++i) {
    const pack::PatchRecord& p = pack.patch(i);
    const uint32_t w = pack.map_width(p.target);
    T* map = maps + pack.map_offset(p.target) * 3;
    const uint32_t aw = pack.atlas(p.atlas).width;
    const uint8_t* pixels = pack.atlas_pixels(p.atlas);
    // Decoded, signed values for the 256 codes: the texel loop is a lookup.
    const T sign = T(patch_sign(pack.group(p.group).kind, p.flags));
    T table[256];
    for (int q = 0; q < 256; ++q) {
      const T v = sign * T(p.scale * patch_decode_unit(uint8_t(q), p.encoding));
      table[q] = absolute ? T(std::fabs(v)) : v;
    }
    T f[3];
    for (int c = 0; c < 3; ++c) f[c] = absolute ? T(std::fabs(factor[c])) : factor[c];
    const uint32_t step = p.channel_count == 3 ? 1 : 0;
    const int destination = pack::patch_destination(p.flags);
    if (destination >= 0) {
      const T fd = f[destination];
      for (uint32_t y = 0; y < p.height; ++y) {
        const uint8_t* src = pixels + ((size_t(p.atlas_y) + y) * aw + p.atlas_x) * 4 + p.channel;
        T* dst = map + ((size_t(p.dest_y) + y) * w + p.dest_x) * 3 + destination;
        for (uint32_t x = 0; x < p.width; ++x, src += 4, dst += 3) *dst += fd * table[*src];
      }
      continue;
    }
    for (uint32_t y = 0; y < p.height; ++y) {
      const uint8_t* src = pixels + ((size_t(p.atlas_y) + y) * aw + p.atlas_x) * 4 + p.channel;
      T* dst = map + ((size_t(p.dest_y) + y) * w + p.dest_x) * 3;
      for (uint32_t x = 0; x < p.width; ++x, src += 4, dst += 3) {
        dst[0] += f[0] * table[src[0]];
        dst[1] += f[1] * table[src[step]];
        dst[2] += f[2] * table[src[2 * step]];
      }
    }
  }
}

}  // namespace lightpatch
