#version 300 es
// Writes the accumulator into the light map the game samples: clamped at zero (light is never
// negative), times the presentation scale, and rounded here to the nearest half float, ties to
// even (lightpatch/half_float.h does the same on the CPU), so the RGBA16F write is exact whatever
// rounding the target applies (llvmpipe truncates toward zero).
precision highp float;
precision highp int;

uniform highp sampler2D u_accumulator;
uniform float u_scale;

out vec4 o_color;

float round_to_half(float v) {  // v >= 0, finite
  if (v < 6.103515625e-5) return roundEven(v * 16777216.0) / 16777216.0;  // subnormal: 2^-24 steps
  uint b = floatBitsToUint(v);
  b = (b + 0xFFFu + ((b >> 13) & 1u)) & ~0x1FFFu;  // keep 10 mantissa bits, nearest even
  return uintBitsToFloat(b);
}

void main() {
  vec3 v = max(texelFetch(u_accumulator, ivec2(gl_FragCoord.xy), 0).rgb * u_scale, vec3(0.0));
  o_color = vec4(round_to_half(v.r), round_to_half(v.g), round_to_half(v.b), 1.0);
}
