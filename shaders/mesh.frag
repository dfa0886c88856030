#version 330 core
// Triangle meshes: flat (screen-space derivative normal) or smooth (interpolated normal) shading.
in vec3 v_pos_view;
in vec3 v_normal_view;

uniform vec3 u_color;
uniform float u_opacity;
uniform int u_flat;
uniform vec3 u_light_view;

layout(location = 0) out vec4 o_color;

vec3 shade(vec3 base, vec3 n, vec3 to_eye) {
  float key = max(dot(n, u_light_view), 0.0);
  float fill = max(dot(n, to_eye), 0.0);
  vec3 h = normalize(u_light_view + to_eye);
  float spec = pow(max(dot(n, h), 0.0), 48.0);
  return base * (0.22 + 0.58 * key + 0.25 * fill) + vec3(0.15 * spec);
}

void main() {
  vec3 to_eye = normalize(-v_pos_view);
  vec3 n = u_flat != 0 ? normalize(cross(dFdx(v_pos_view), dFdy(v_pos_view)))
                       : normalize(v_normal_view);
  // Two-sided: open or inside-out meshes still shade from the side the camera sees.
  if (dot(n, to_eye) < 0.0) n = -n;
  o_color = vec4(shade(u_color, n, to_eye), u_opacity);
}
