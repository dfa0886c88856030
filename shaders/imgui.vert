#version 330 core
// Dear ImGui draw lists: 2D vertices in display pixels, texture coordinates and packed colour.
layout(location = 0) in vec2 a_position;
layout(location = 1) in vec2 a_uv;
layout(location = 2) in vec4 a_color;

uniform vec2 u_display_pos;
uniform vec2 u_display_size;

out vec2 v_uv;
out vec4 v_color;

void main() {
  // Pixels (origin top-left, y down) to clip space (y up).
  vec2 ndc = (a_position - u_display_pos) / u_display_size * 2.0 - 1.0;
  gl_Position = vec4(ndc.x, -ndc.y, 0.0, 1.0);
  v_uv = a_uv;
  v_color = a_color;
}
