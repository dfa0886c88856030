#version 330 core
// Sphere impostors: exact ray-sphere hit per fragment, lit like a mesh, with the true sphere depth.
in vec3 v_pos_view;
flat in vec3 v_center_view;
flat in vec3 v_color;
flat in int v_index;

uniform mat4 u_proj;
uniform float u_radius;
uniform float u_opacity;
uniform vec3 u_light_view;  // unit direction towards the key light, view space

layout(location = 0) out vec4 o_color;

vec3 shade(vec3 base, vec3 n, vec3 to_eye) {
  float key = max(dot(n, u_light_view), 0.0);
  float fill = max(dot(n, to_eye), 0.0);
  vec3 h = normalize(u_light_view + to_eye);
  float spec = pow(max(dot(n, h), 0.0), 48.0);
  return base * (0.22 + 0.58 * key + 0.25 * fill) + vec3(0.25 * spec);
}

void main() {
  vec3 dir = normalize(v_pos_view);
  float b = dot(dir, v_center_view);
  float c = dot(v_center_view, v_center_view) - u_radius * u_radius;
  float disc = b * b - c;
  if (disc < 0.0) discard;
  vec3 hit = (b - sqrt(disc)) * dir;
  vec3 n = (hit - v_center_view) / u_radius;
  vec4 clip = u_proj * vec4(hit, 1.0);
  gl_FragDepth = 0.5 * clip.z / clip.w + 0.5;
  o_color = vec4(shade(v_color, n, -dir), u_opacity);
}
