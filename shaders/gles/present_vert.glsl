#version 300 es
// A present step's quad: a patch's destination rectangle (or the whole map), in texels, row 0 =
// top (texture row 0), the same vertex buffer as the patch draws (attribute 0 only).
precision highp float;

layout(location = 0) in vec2 a_dest;  // target texel corner

uniform vec2 u_target_size;

void main() {
  gl_Position = vec4(a_dest / u_target_size * 2.0 - 1.0, 0.0, 1.0);
}
