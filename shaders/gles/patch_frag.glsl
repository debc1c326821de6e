#version 300 es
// Decodes a patch texel (pack_format.h: x = q/255, linear or squared, times scale and sign) and
// outputs it times the draw's factor; the target adds it with blending (ONE, ONE). Linked twice:
// reading any of eight atlases by the patch's unit, and with LIGHTPATCH_ONE_ATLAS defined (the
// runtime adds it after the #version line) reading one.
precision highp float;
precision highp int;

#ifdef LIGHTPATCH_ONE_ATLAS
// A run of patches of one atlas (Runtime::open): the runtime points this sampler at its unit.
// (llvmpipe runs every side of the branch below: eight fetches a texel instead of one.)
uniform highp sampler2D u_atlas;
#else
uniform highp sampler2D u_atlas[8];
#endif
uniform vec3 u_factor;

in vec2 v_atlas;
flat in vec4 v_mask_r;
flat in vec4 v_mask_g;
flat in vec4 v_mask_b;
flat in float v_scale;  // scale * sign (the masks carry the tints)
flat in int v_square;
flat in int v_unit;

out vec4 o_color;

void main() {
  // v_atlas is at texel centres (n + 0.5); texelFetch needs no derivatives, so the branch on the
  // unit is fine (sampler arrays only take constant indices in GLSL ES 3.00).
  ivec2 t = ivec2(floor(v_atlas));
#ifdef LIGHTPATCH_ONE_ATLAS
  vec4 q = texelFetch(u_atlas, t, 0);
#else
  vec4 q;
  if (v_unit == 0) q = texelFetch(u_atlas[0], t, 0);
  else if (v_unit == 1) q = texelFetch(u_atlas[1], t, 0);
  else if (v_unit == 2) q = texelFetch(u_atlas[2], t, 0);
  else if (v_unit == 3) q = texelFetch(u_atlas[3], t, 0);
  else if (v_unit == 4) q = texelFetch(u_atlas[4], t, 0);
  else if (v_unit == 5) q = texelFetch(u_atlas[5], t, 0);
  else if (v_unit == 6) q = texelFetch(u_atlas[6], t, 0);
  else q = texelFetch(u_atlas[7], t, 0);
#endif
  // Decoded before the masks combine channels (a 2-channel patch's masks blend two).
  if (v_square == 1) q *= q;
  vec3 x = vec3(dot(q, v_mask_r), dot(q, v_mask_g), dot(q, v_mask_b));
  o_color = vec4(x * (v_scale * u_factor), 0.0);
}
