// The indirect map magnified onto the light map on the CPU, exactly as pack_format.h ("Two target
// maps") defines what a game samples: at the centre of light-map texel (x, y) the indirect map is
// interpolated bilinearly at indirect-texel coordinates ((x + 0.5) / s - 0.5, (y + 0.5) / s - 0.5),
// clamped to its edge texels. The CPU recomposer's combined map, `lightpatch recompose` (both
// backends), the inn's light probe and the cooker's pack builder (what the light map must hold
// besides the indirect map) all use these, so that every L + I in the project is the same sum.
//
// Header-only (templates on the value type), no allocation: usable from the runtime and the
// cooker alike.
#pragma once

#include <cstddef>
#include <cstdint>

namespace lightpatch {

// One axis of the interpolation at light-map texel `x`: indirect texels i0 <= i1 (clamped to
// [0, size - 1]) and the weight of i1. (x + 0.5) / s - 0.5 = (2x + 1 - s) / 2s, so the weight is a
// multiple of 1 / 2s (exact in float) and the floor is taken on integers.
struct IndirectTap {
  uint32_t i0, i1;
  float w1;
};
constexpr IndirectTap indirect_tap(uint32_t x, uint32_t scale, uint32_t size) {
  const int64_t n = 2 * int64_t(x) + 1 - int64_t(scale);
  const int64_t d = 2 * int64_t(scale);
  const int64_t i = n >= 0 ? n / d : -((-n + d - 1) / d);  // floor(n / d)
  const float w = float(n - i * d) / float(d);
  const int64_t last = int64_t(size) - 1;
  const auto clamp = [last](int64_t v) { return uint32_t(v < 0 ? 0 : v > last ? last : v); };
  return IndirectTap{clamp(i), clamp(i + 1), w};
}

// The indirect map's value at the centre of light-map texel (x, y), RGB into out[0..2].
// `indirect`: width * height texels of `stride` values each (RGB first), row 0 at the top.
// Preconditions: scale >= 1, width, height >= 1, x < width * scale, y < height * scale.
template <typename T>
void sample_indirect(const T* indirect, uint32_t stride, uint32_t width, uint32_t height,
                     uint32_t scale, uint32_t x, uint32_t y, T out[3]) {
  const IndirectTap tx = indirect_tap(x, scale, width);
  const IndirectTap ty = indirect_tap(y, scale, height);
  const T wx = T(tx.w1), wy = T(ty.w1);
  const T* r0 = indirect + size_t(ty.i0) * width * stride;
  const T* r1 = indirect + size_t(ty.i1) * width * stride;
  for (int c = 0; c < 3; ++c) {
    const T top = (T(1) - wx) * r0[tx.i0 * stride + c] + wx * r0[tx.i1 * stride + c];
    const T bottom = (T(1) - wx) * r1[tx.i0 * stride + c] + wx * r1[tx.i1 * stride + c];
    out[c] = (T(1) - wy) * top + wy * bottom;
  }
}

// Adds the magnified indirect map to every texel of `map`: (width * scale) x (height * scale)
// texels of `map_stride` values each (RGB first; other values untouched), row 0 at the top.
template <typename T>
void add_magnified_indirect(const T* indirect, uint32_t stride, uint32_t width, uint32_t height,
                            uint32_t scale, T* map, uint32_t map_stride) {
  const uint32_t w = width * scale, h = height * scale;
  for (uint32_t y = 0; y < h; ++y) {
    T* row = map + size_t(y) * w * map_stride;
    for (uint32_t x = 0; x < w; ++x) {
      T v[3];
      sample_indirect(indirect, stride, width, height, scale, x, y, v);
      for (int c = 0; c < 3; ++c) row[size_t(x) * map_stride + c] += v[c];
    }
  }
}

}  // namespace lightpatch
