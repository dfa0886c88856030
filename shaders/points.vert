#version 330 core
// Sphere impostors: one camera-facing quad per point (instanced); points.frag ray-casts the sphere.
layout(location = 0) in vec3 a_center;  // world position, one per instance
layout(location = 1) in vec3 a_color;   // per-point colour (u_color_mode 1)
layout(location = 2) in float a_scalar; // per-point scalar (u_color_mode 2)

uniform mat4 u_view;
uniform mat4 u_proj;
uniform float u_radius;
uniform int u_color_mode;  // 0 uniform colour, 1 per-point colour, 2 scalar through the colormap
uniform vec3 u_color;
uniform vec2 u_range;  // scalar mapped to the colormap's ends
uniform sampler2D u_colormap;

out vec3 v_pos_view;
flat out vec3 v_center_view;
flat out vec3 v_color;
flat out int v_index;

void main() {
  const vec2 kCorners[4] = vec2[4](vec2(-1.0, -1.0), vec2(1.0, -1.0), vec2(-1.0, 1.0), vec2(1.0, 1.0));
  vec3 center = (u_view * vec4(a_center, 1.0)).xyz;
  // The quad sits on the sphere's front and is enlarged so that the perspective silhouette,
  // which grows off-axis, stays inside it; the fragment shader discards what misses the sphere.
  vec3 front = center + normalize(-center) * u_radius;
  vec3 pos = front + vec3(kCorners[gl_VertexID] * u_radius * 1.5, 0.0);
  v_pos_view = pos;
  v_center_view = center;
  v_index = gl_InstanceID;
  if (u_color_mode == 1) {
    v_color = a_color;
  } else if (u_color_mode == 2) {
    float span = max(u_range.y - u_range.x, 1e-12);
    float t = clamp((a_scalar - u_range.x) / span, 0.0, 1.0);
    v_color = texture(u_colormap, vec2(t, 0.5)).rgb;
  } else {
    v_color = u_color;
  }
  gl_Position = u_proj * vec4(pos, 1.0);
}
