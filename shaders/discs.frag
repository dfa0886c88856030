#version 330 core
// Flat discs: round cut of the point sprite with a cheap radial shade; depth stays the centre's so
// early depth tests keep large clouds fast.
flat in vec3 v_color;
flat in int v_index;

uniform float u_opacity;

layout(location = 0) out vec4 o_color;

void main() {
  vec2 d = 2.0 * gl_PointCoord - 1.0;
  float r2 = dot(d, d);
  if (r2 > 1.0) discard;
  o_color = vec4(v_color * (1.0 - 0.35 * r2), u_opacity);
}
