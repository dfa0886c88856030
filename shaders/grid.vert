#version 330 core
// Ground grid: one quad in the plane z = u_height covering u_center +- u_extent (z up).
uniform mat4 u_view;
uniform mat4 u_proj;
uniform vec2 u_center;
uniform float u_extent;
uniform float u_height;

out vec2 v_world;

void main() {
  const vec2 kCorners[4] = vec2[4](vec2(-1.0, -1.0), vec2(1.0, -1.0), vec2(-1.0, 1.0), vec2(1.0, 1.0));
  v_world = u_center + kCorners[gl_VertexID] * u_extent;
  gl_Position = u_proj * u_view * vec4(v_world, u_height, 1.0);
}
