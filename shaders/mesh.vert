#version 330 core
// Triangle meshes: object-frame vertices posed by u_model; normals for smooth shading.
layout(location = 0) in vec3 a_position;
layout(location = 1) in vec3 a_normal;

uniform mat4 u_model;
uniform mat4 u_view;
uniform mat4 u_proj;

out vec3 v_pos_view;
out vec3 v_normal_view;

void main() {
  mat4 model_view = u_view * u_model;
  vec4 pos = model_view * vec4(a_position, 1.0);
  v_pos_view = pos.xyz;
  // Inverse-transpose keeps normals perpendicular under non-uniform object scale.
  v_normal_view = transpose(inverse(mat3(model_view))) * a_normal;
  gl_Position = u_proj * pos;
}
