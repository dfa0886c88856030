#version 330 core
// Ground grid: anti-aliased minor/major lines and x/y axes, fading out towards the edge.
in vec2 v_world;

uniform vec2 u_center;
uniform float u_extent;
uniform float u_spacing;
uniform vec3 u_line_color;

layout(location = 0) out vec4 o_color;

float line_strength(vec2 coord) {
  vec2 g = abs(fract(coord - 0.5) - 0.5) / max(fwidth(coord), vec2(1e-6));
  return 1.0 - min(min(g.x, g.y), 1.0);
}

void main() {
  float minor = line_strength(v_world / u_spacing) * 0.45;
  float major = line_strength(v_world / (u_spacing * 5.0));
  vec2 axis_px = abs(v_world) / max(fwidth(v_world), vec2(1e-6));
  float strength = max(minor, major);
  vec3 color = u_line_color;
  if (axis_px.y < 1.0) color = vec3(0.80, 0.25, 0.25);  // x axis (y = 0)
  if (axis_px.x < 1.0) color = vec3(0.25, 0.65, 0.25);  // y axis (x = 0)
  if (min(axis_px.x, axis_px.y) < 1.0) strength = 1.0;
  float fade = 1.0 - smoothstep(0.55 * u_extent, u_extent, length(v_world - u_center));
  float alpha = strength * fade;
  if (alpha <= 0.002) discard;
  o_color = vec4(color, alpha);
}
