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

// The decoded value of atlas texel t (all four channels), before scale and sign.
vec4 decode(ivec2 t) {
  vec4 q = texelFetch(u_atlas, t, 0);
  return v_square == 1 ? q * q : q;
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
  // The four channels are interpolated first (patch_accumulate.h's order, magnify_blend), then
  // combined by the masks once: the masks are linear, so this is the same value, and llvmpipe,
  // which computes a vector a channel at a time, pays three dot products instead of twelve.
  vec4 a = decode(t0), b = decode(ivec2(t1.x, t0.y));
  vec4 c = decode(ivec2(t0.x, t1.y)), d = decode(t1);
  vec4 top = a + f.x * (b - a);
  vec4 bottom = c + f.x * (d - c);
  vec4 q = top + f.y * (bottom - top);
  vec3 x = vec3(dot(q, v_mask_r), dot(q, v_mask_g), dot(q, v_mask_b));
  o_color = vec4(x * (v_scale * u_factor), 0.0);
}
