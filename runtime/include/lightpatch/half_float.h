// IEEE 754 binary16 ("half float", the format of the light map the game samples): conversions
// that round to nearest, ties to even, whatever the FPU or the GL driver does. The GLES resolve
// shader (shaders/gles/resolve_frag.glsl) rounds the same way before its write.
#pragma once

#include <cstdint>
#include <cstring>

namespace lightpatch {

constexpr float kHalfMax = 65504.0f;               // largest finite half
constexpr float kHalfMinNormal = 6.103515625e-5f;  // 2^-14

// Round to nearest even; values beyond the half range become infinities, NaN stays NaN.
inline uint16_t float_to_half(float value) {
  uint32_t f;
  std::memcpy(&f, &value, sizeof f);
  const uint32_t sign = (f >> 16) & 0x8000u;
  const uint32_t magnitude = f & 0x7FFFFFFFu;
  if (magnitude >= 0x7F800000u) {  // inf or NaN
    return uint16_t(sign | 0x7C00u | (magnitude > 0x7F800000u ? 0x200u : 0u));
  }
  if (magnitude >= 0x477FF000u) return uint16_t(sign | 0x7C00u);  // rounds past 65504
  if (magnitude >= 0x38800000u) {                                 // normal half
    const uint32_t rounded = magnitude + 0x0FFFu + ((magnitude >> 13) & 1u);
    return uint16_t(sign | ((rounded - 0x38000000u) >> 13));
  }
  // Subnormal half (or zero): multiples of 2^-24.
  if (magnitude < 0x33000000u) return uint16_t(sign);  // below half of 2^-24
  const uint32_t exponent = magnitude >> 23;
  const uint32_t mantissa = (magnitude & 0x7FFFFFu) | 0x800000u;
  const uint32_t shift = 126u - exponent;  // 14..24 for exponents 102..112
  const uint32_t half_bit = 1u << (shift - 1);
  uint32_t q = mantissa >> shift;
  const uint32_t rest = mantissa & ((1u << shift) - 1u);
  if (rest > half_bit || (rest == half_bit && (q & 1u))) ++q;
  return uint16_t(sign | q);
}

inline float half_to_float(uint16_t h) {
  const uint32_t sign = uint32_t(h & 0x8000u) << 16;
  const uint32_t exponent = (h >> 10) & 0x1Fu;
  const uint32_t mantissa = h & 0x3FFu;
  uint32_t f;
  if (exponent == 0x1Fu) {
    f = sign | 0x7F800000u | (mantissa << 13);
  } else if (exponent != 0) {
    f = sign | ((exponent + 112u) << 23) | (mantissa << 13);
  } else if (mantissa == 0) {
    f = sign;
  } else {  // subnormal: mantissa * 2^-24
    const float v = float(mantissa) * (1.0f / 16777216.0f);
    std::memcpy(&f, &v, sizeof f);
    f |= sign;
  }
  float out;
  std::memcpy(&out, &f, sizeof out);
  return out;
}

}  // namespace lightpatch
