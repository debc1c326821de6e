#version 300 es
// Writes the accumulator into the light map the game samples: clamped at zero (light is never
// negative) unless the pack's maps keep their sign (u_signed: a pack with an indirect map, whose
// light map corrects it; the game clamps L + I), times the presentation scale, and rounded here to
// the nearest half float, ties to even (lightpatch/half_float.h does the same on the CPU), so the
// RGBA16F write is exact whatever rounding the target applies (llvmpipe truncates toward zero).
precision highp float;
precision highp int;

uniform highp sampler2D u_accumulator;
uniform float u_scale;
uniform bool u_signed;

out vec4 o_color;

float round_to_half(float v) {  // v >= 0, finite
  if (v < 6.103515625e-5) return roundEven(v * 16777216.0) / 16777216.0;  // subnormal: 2^-24 steps
  uint b = floatBitsToUint(v);
  b = (b + 0xFFFu + ((b >> 13) & 1u)) & ~0x1FFFu;  // keep 10 mantissa bits, nearest even
  return uintBitsToFloat(b);
}

void main() {
  vec3 v = texelFetch(u_accumulator, ivec2(gl_FragCoord.xy), 0).rgb * u_scale;
  if (!u_signed) v = max(v, vec3(0.0));
  // Round the magnitude: rounding to nearest is symmetric in the sign.
  vec3 m = abs(v);
  o_color = vec4(sign(v) * vec3(round_to_half(m.r), round_to_half(m.g), round_to_half(m.b)), 1.0);
}
