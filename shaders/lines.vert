#version 330 core
// Line segments (neighbour edges, overlays): world positions with per-vertex colour.
layout(location = 0) in vec3 a_position;
layout(location = 1) in vec3 a_color;

uniform mat4 u_view;
uniform mat4 u_proj;

out vec3 v_color;

void main() {
  v_color = a_color;
  gl_Position = u_proj * u_view * vec4(a_position, 1.0);
}
