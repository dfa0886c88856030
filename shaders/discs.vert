#version 330 core
// Flat discs for large clouds: one point sprite per point (one vertex each, one plain draw), sized
// to the projected sphere diameter; discs.frag cuts the square to a round, lightly shaded disc.
layout(location = 0) in vec3 a_center;  // world position, one per vertex
layout(location = 1) in vec3 a_color;   // per-point colour (u_color_mode 1)
layout(location = 2) in float a_scalar; // per-point scalar (u_color_mode 2)

uniform mat4 u_view;
uniform mat4 u_proj;
uniform float u_radius;
uniform float u_viewport_height;  // pixels
uniform int u_color_mode;  // 0 uniform colour, 1 per-point colour, 2 scalar through the colormap
uniform vec3 u_color;
uniform vec2 u_range;
uniform sampler2D u_colormap;

flat out vec3 v_color;
flat out int v_index;

void main() {
  vec4 center = u_view * vec4(a_center, 1.0);
  gl_Position = u_proj * center;
  // Projected diameter in pixels: proj[1][1] is cot(fov/2); the disc faces the camera.
  float diameter = 2.0 * u_radius * u_proj[1][1] * 0.5 * u_viewport_height / max(-center.z, 1e-6);
  gl_PointSize = clamp(diameter, 1.0, 255.0);
  v_index = gl_VertexID;
  if (u_color_mode == 1) {
    v_color = a_color;
  } else if (u_color_mode == 2) {
    float span = max(u_range.y - u_range.x, 1e-12);
    float t = clamp((a_scalar - u_range.x) / span, 0.0, 1.0);
    v_color = texture(u_colormap, vec2(t, 0.5)).rgb;
  } else {
    v_color = u_color;
  }
}
