#version 300 es
// One light patch's quad: copies an atlas rectangle to the same-size rectangle of the target
// (patch_frag), or magnifies a level-L patch's smaller one (patch_magnified_frag; pack_format.h,
// "Magnified patches": its atlas corners span width / 2^L, so v_atlas at a destination texel
// centre x is atlas_x + (x + 0.5) / 2^L). Both patch programs use this shader. Positions and
// atlas coordinates are in texels, row 0 = top (texture row 0); no flip anywhere.
precision highp float;
precision highp int;

layout(location = 0) in vec2 a_dest;    // target texel corner
layout(location = 1) in vec2 a_atlas;   // atlas texel corner
// x: scale * sign (shadow groups and kFlagNegative patches are negative), y: first channel,
// z: channel count (1, 2 or 3), or 4 + d for a 1-channel patch drawn into map channel d only
// (pack_format.h: kFlagDestinationMask), w: encoding (0 linear, 1 square)
layout(location = 2) in vec4 a_patch;
layout(location = 3) in float a_unit;   // texture unit of the patch's atlas (0..7)
// The patch's atlas rectangle, inclusive texels: x0, y0, x1 - 1, y1 - 1 (a magnified patch's
// bilinear taps are clamped to it: a patch never reads a neighbour's texels).
layout(location = 4) in vec4 a_rect;
layout(location = 5) in vec3 a_tint;    // the patch's tint per map channel (tint / 255)
layout(location = 6) in vec3 a_tint_b;  // a 2-channel patch's second tint (tint_b / 255)

uniform vec2 u_target_size;

out vec2 v_atlas;
flat out vec4 v_mask_r;
flat out vec4 v_mask_g;
flat out vec4 v_mask_b;
// Map channel c = dot(decoded texel, v_mask_c) * v_scale: the masks carry the tints.
flat out float v_scale;  // scale * sign
flat out int v_square;
flat out int v_unit;
flat out vec4 v_rect;

vec4 channel_mask(float c) { return vec4(equal(vec4(c), vec4(0.0, 1.0, 2.0, 3.0))); }

void main() {
  v_atlas = a_atlas;
  // Each map channel's first atlas channel: the patch's first for a grey or 2-channel patch.
  vec4 m0 = channel_mask(a_patch.y), m1 = channel_mask(a_patch.y + 1.0);
  vec4 r = m0, g = m0, b = m0;
  if (a_patch.z > 3.5) {  // one map channel: the others get a zero mask
    float d = a_patch.z - 4.0;
    r = d < 0.5 ? m0 : vec4(0.0);
    g = d > 0.5 && d < 1.5 ? m0 : vec4(0.0);
    b = d > 1.5 ? m0 : vec4(0.0);
  } else if (a_patch.z > 2.5) {  // RGB patches read three consecutive channels
    g = m1;
    b = channel_mask(a_patch.y + 2.0);
  }
  // Times the tint; a 2-channel patch's second channel times its second tint (zero on every
  // other patch: pack_format.h).
  v_mask_r = r * a_tint.r + m1 * a_tint_b.r;
  v_mask_g = g * a_tint.g + m1 * a_tint_b.g;
  v_mask_b = b * a_tint.b + m1 * a_tint_b.b;
  v_scale = a_patch.x;
  v_square = a_patch.w > 0.5 ? 1 : 0;
  v_unit = int(a_unit + 0.5);
  v_rect = a_rect;
  gl_Position = vec4(a_dest / u_target_size * 2.0 - 1.0, 0.0, 1.0);
}
