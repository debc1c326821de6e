#version 300 es
// A magnified patch (pack_format.h, "Magnified patches"): the bilinear interpolation of the
// decoded values (x = q/255, linear or squared) of four texels of the patch's own atlas
// rectangle, times scale, sign and the draw's factor; the target adds it with blending (ONE, ONE).
// Level-0 patches are drawn by patch_frag: these four taps would cost them twice the time on
// llvmpipe, which runs both sides of a branch.
precision highp float;
precision highp int;

// The patch's atlas alone: a run of magnified patches shares one atlas (Runtime::open), and the
// runtime points this sampler at its unit. (An 8-way branch on the unit, as patch_frag has, cost
// llvmpipe all eight fetches for each of the four taps: magnified patches drew at 1.4x the fill
// floor instead of 1.0x.)
uniform highp sampler2D u_atlas;
uniform vec3 u_factor;

in vec2 v_atlas;
flat in vec4 v_mask_r;
flat in vec4 v_mask_g;
flat in vec4 v_mask_b;
flat in float v_scale;  // scale * sign (the masks carry the tints)
flat in int v_square;
flat in vec4 v_rect;

out vec4 o_color;

vec4 fetch(ivec2 t) {
  return texelFetch(u_atlas, t, 0);
}

// The decoded value of atlas texel t, before scale and sign.
vec3 decode(ivec2 t) {
  vec4 q = fetch(t);
  // Decoded before the masks combine channels (a 2-channel patch's masks blend two).
  if (v_square == 1) q *= q;
  return vec3(dot(q, v_mask_r), dot(q, v_mask_g), dot(q, v_mask_b));
}

void main() {
  // v_atlas = atlas corner + (destination texel + 0.5) / 2^L: taps i and i + 1 around
  // v_atlas - 0.5, each clamped to the patch's own rectangle (never a neighbour's texel).
  vec2 s = v_atlas - 0.5;
  vec2 i = floor(s);
  vec2 f = s - i;
  ivec2 lo = ivec2(v_rect.xy), hi = ivec2(v_rect.zw);
  ivec2 t0 = clamp(ivec2(i), lo, hi);
  ivec2 t1 = clamp(ivec2(i) + 1, lo, hi);
  vec3 top = mix(decode(t0), decode(ivec2(t1.x, t0.y)), f.x);
  vec3 bottom = mix(decode(ivec2(t0.x, t1.y)), decode(t1), f.x);
  vec3 x = mix(top, bottom, f.y);
  o_color = vec4(x * (v_scale * u_factor), 0.0);
}
