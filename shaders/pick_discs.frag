#version 330 core
// Picking for flat discs: the same round cut as discs.frag, writing (point index + 1, layer) into
// an RGBA8 id buffer like pick.frag.
flat in vec3 v_color;
flat in int v_index;

uniform int u_layer;  // 0..254

layout(location = 0) out vec4 o_id;

void main() {
  vec2 d = 2.0 * gl_PointCoord - 1.0;
  if (dot(d, d) > 1.0) discard;
  int id = v_index + 1;
  o_id = vec4(float(id & 255), float((id >> 8) & 255), float((id >> 16) & 255), float(u_layer)) / 255.0;
}
