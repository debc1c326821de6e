#version 300 es
// Outputs a constant: open() blends it onto a known value to see how the accumulator rounds.
precision highp float;

uniform vec4 u_value;

out vec4 o_color;

void main() {
  o_color = u_value;
}
