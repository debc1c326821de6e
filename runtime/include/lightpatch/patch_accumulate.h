// Adding decoded patches to a light map held in host memory: the one CPU drawing loop (the
// runtime's CPU path, the CPU reference recomposer, the planner's magnitude bounds and the tests'
// reference all draw through it).
#pragma once

#include <algorithm>
#include <cmath>
#include <cstddef>
#include <cstdint>

#include "lightpatch/group_rules.h"
#include "lightpatch/pack_view.h"
#include "lightpatch/patch_decode.h"

namespace lightpatch {

// The magnification rule's taps along one axis (pack_format.h, "Magnified patches"): destination
// texel x of a patch stored at `level` on n texels reads stored texels i0 and i1 = i0 + 1 (both
// clamped to [0, n - 1]) with weight t on i1, at s = (x + 0.5) / 2^level - 0.5. s and t are exact
// in float and double (a power-of-two division of small integers). Precondition: n >= 1.
template <typename T>
struct MagnifyTap {
  uint32_t i0, i1;
  T t;
};
template <typename T>
MagnifyTap<T> magnify_tap(uint32_t x, uint32_t n, uint32_t level) {
  // Times the reciprocal, exact for a power of two: no division on the drawing loop.
  const T s = (T(x) + T(0.5)) * (T(1) / T(1u << level)) - T(0.5);
  const T fl = std::floor(s);  // s in [-0.5, n - 0.5): floor(s) >= -1
  const int64_t i = int64_t(fl);
  const int64_t last = int64_t(n) - 1;
  return MagnifyTap<T>{uint32_t(std::clamp<int64_t>(i, 0, last)),
                       uint32_t(std::clamp<int64_t>(i + 1, 0, last)), s - fl};
}

// The rule's interpolation of the four taps' values: along x on both rows, then along y (a, b
// on row i0, c, d on row i1; tx, ty the taps' weights). The one order every path uses.
template <typename T>
T magnify_blend(T a, T b, T c, T d, T tx, T ty) {
  const T top = a + tx * (b - a);
  const T bottom = c + tx * (d - c);
  return top + ty * (bottom - top);
}

// One magnified patch (pack_format.h, "Magnified patches"): destination texel (x, y) gets the
// bilinear interpolation of the decoded values `table` of the patch's own atlas rectangle at the
// taps of magnify_tap(). Indices and weights are computed per texel: nothing to allocate.
template <typename T>
void add_magnified_patch(const pack::PatchRecord& p, uint32_t level, const uint8_t* pixels,
                         uint32_t atlas_width, const T table[256], const T f[3], uint32_t step,
                         int destination, T* map, uint32_t map_width, const T* f_b = nullptr) {
  const uint32_t aw = pack::patch_atlas_side(p.width, level);
  const uint32_t ah = pack::patch_atlas_side(p.height, level);
  // The patch's first channel at atlas-rectangle texel (x, y).
  auto at = [&](uint32_t x, uint32_t y) {
    return pixels + ((size_t(p.atlas_y) + y) * atlas_width + p.atlas_x + x) * 4 + p.channel;
  };
  // Bilinear interpolation of channel offset k between the four taps.
  auto lerp2 = [table](const uint8_t* a, const uint8_t* b, const uint8_t* c, const uint8_t* d,
                       uint32_t k, T tx, T ty) {
    return magnify_blend<T>(table[a[k]], table[b[k]], table[c[k]], table[d[k]], tx, ty);
  };
  for (uint32_t y = 0; y < p.height; ++y) {
    const MagnifyTap<T> ty = magnify_tap<T>(y, ah, level);
    T* dst = map + ((size_t(p.dest_y) + y) * map_width + p.dest_x) * 3;
    for (uint32_t x = 0; x < p.width; ++x, dst += 3) {
      const MagnifyTap<T> tx = magnify_tap<T>(x, aw, level);
      const uint8_t* a = at(tx.i0, ty.i0);
      const uint8_t* b = at(tx.i1, ty.i0);
      const uint8_t* c = at(tx.i0, ty.i1);
      const uint8_t* d = at(tx.i1, ty.i1);
      const T v0 = lerp2(a, b, c, d, 0, tx.t, ty.t);
      if (destination >= 0) {
        dst[destination] += f[destination] * v0;
      } else if (f_b) {  // two tints: the second channel's value times the second tint
        const T v1 = lerp2(a, b, c, d, 1, tx.t, ty.t);
        dst[0] += f[0] * v0 + f_b[0] * v1;
        dst[1] += f[1] * v0 + f_b[1] * v1;
        dst[2] += f[2] * v0 + f_b[2] * v1;
      } else if (step == 0) {  // grey: one value for the three channels
        dst[0] += f[0] * v0;
        dst[1] += f[1] * v0;
        dst[2] += f[2] * v0;
      } else {
        dst[0] += f[0] * v0;
        dst[1] += f[1] * lerp2(a, b, c, d, 1, tx.t, ty.t);
        dst[2] += f[2] * lerp2(a, b, c, d, 2, tx.t, ty.t);
      }
    }
  }
}

// Adds factor * (signed decoded value) of every texel of patches [first, first + count) to
// `maps`: the pack's map set (pack_view.h: the light map, then the indirect map if the pack has
// one; RGB, 3 values per texel, row 0 = top), each patch into its own target. With `absolute`,
// adds |factor * value| (magnitude bounds). A grey patch (one channel) adds its value to all three
// channels, or to its one destination channel (pack::patch_destination); every value added to map
// channel c is multiplied by the patch's tint (patch_tint); a 2-channel patch adds its
// first value times its tint and its second times tint_b (patch_tint_b). The patches must be
// valid indices of a validated pack. A magnified patch (level > 0) is interpolated from its
// atlas rectangle; with `absolute`, from the absolute values (a bound of the magnitude).
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
    // The patch's tint is a factor on each map channel ("Decoding a patch texel").
    T f[3], f_b[3];
    for (int c = 0; c < 3; ++c) {
      const T k = absolute ? T(std::fabs(factor[c])) : factor[c];
      f[c] = k * patch_tint<T>(p, c);
      f_b[c] = k * patch_tint_b<T>(p, c);
    }
    const bool two = p.channel_count == 2;
    const uint32_t step = p.channel_count == 3 ? 1 : 0;
    const int destination = pack::patch_destination(p.flags);
    const uint32_t level = pack::patch_level(p.flags);
    if (level > 0) {
      add_magnified_patch(p, level, pixels, aw, table, f, step, destination, map, w,
                          two ? f_b : nullptr);
      continue;
    }
    if (two) {
      for (uint32_t y = 0; y < p.height; ++y) {
        const uint8_t* src = pixels + ((size_t(p.atlas_y) + y) * aw + p.atlas_x) * 4 + p.channel;
        T* dst = map + ((size_t(p.dest_y) + y) * w + p.dest_x) * 3;
        for (uint32_t x = 0; x < p.width; ++x, src += 4, dst += 3) {
          const T v0 = table[src[0]], v1 = table[src[1]];
          dst[0] += f[0] * v0 + f_b[0] * v1;
          dst[1] += f[1] * v0 + f_b[1] * v1;
          dst[2] += f[2] * v0 + f_b[2] * v1;
        }
      }
      continue;
    }
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
