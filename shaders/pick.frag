#version 330 core
// Picking: the same sphere hit as points.frag, writing (point index + 1, layer) into an RGBA8 id buffer.
in vec3 v_pos_view;
flat in vec3 v_center_view;
flat in vec3 v_color;
flat in int v_index;

uniform mat4 u_proj;
uniform float u_radius;
uniform int u_layer;  // 0..254; alpha 255 marks "no point"

layout(location = 0) out vec4 o_id;

void main() {
  vec3 dir = normalize(v_pos_view);
  float b = dot(dir, v_center_view);
  float c = dot(v_center_view, v_center_view) - u_radius * u_radius;
  float disc = b * b - c;
  if (disc < 0.0) discard;
  vec3 hit = (b - sqrt(disc)) * dir;
  vec4 clip = u_proj * vec4(hit, 1.0);
  gl_FragDepth = 0.5 * clip.z / clip.w + 0.5;
  // 24 bits of index + 1 in RGB (0 = background), the layer in alpha.
  int id = v_index + 1;
  o_id = vec4(float(id & 255), float((id >> 8) & 255), float((id >> 16) & 255), float(u_layer)) / 255.0;
}
