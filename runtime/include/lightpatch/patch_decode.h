// Decoding one 8-bit patch texel (pack_format.h, "Decoding a patch texel"). The CPU recomposer,
// the cooker's quantizer (which measures its error with this very function) and the GLES shader
// (which samples an RGBA8 UNORM texture, i.e. x = q / 255, then applies the same curve) agree.
#pragma once

#include <cstdint>

#include "lightpatch/pack_format.h"

namespace lightpatch {

// The encoding's curve on x = q / 255, in [0, 1]: x (linear) or x * x (square, sqrt-encoded).
inline float patch_decode_unit(uint8_t q, uint8_t encoding) {
  const float x = static_cast<float>(q) / 255.0f;
  return encoding == pack::kEncodingSquare ? x * x : x;
}

// The signed value a patch texel carries: +-scale * curve(q / 255).
inline float patch_decode(const pack::PatchRecord& patch, uint8_t q) {
  const float v = patch.scale * patch_decode_unit(q, patch.encoding);
  return (patch.flags & pack::kFlagNegative) ? -v : v;
}

// The factor of a patch's tint on map channel c (0..2): tint[c] / 255, exactly 1 for 255.
template <typename T>
inline T patch_tint(const pack::PatchRecord& patch, int c) {
  return T(patch.tint[c]) / T(255);
}

// The factor of a 2-channel patch's second tint on map channel c: tint_b[c] / 255.
template <typename T>
inline T patch_tint_b(const pack::PatchRecord& patch, int c) {
  return T(patch.tint_b[c]) / T(255);
}

// Worst-case absolute decoding error of a texel, in units of the patch scale, when the encoder
// rounds to the nearest code: linear 1/510 (half a step of 1/255); square: s * |x^2 - x'^2| with
// |x - x'| <= 1/510 and x + x' <= 2, i.e. 1/255. Float rounding adds a few ulps of the scale.
constexpr float kLinearErrorBound = 1.0f / 510.0f;
constexpr float kSquareErrorBound = 1.0f / 255.0f;

}  // namespace lightpatch
