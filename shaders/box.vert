#version 330 core
// Wire boxes (voxels): 24 vertices (12 edges) per instance generated from gl_VertexID.
layout(location = 0) in vec3 a_min;  // per instance, world
layout(location = 1) in vec3 a_max;
layout(location = 2) in vec3 a_color;

uniform mat4 u_view;
uniform mat4 u_proj;

out vec3 v_color;

void main() {
  // Corner c has bit 0 -> x, bit 1 -> y, bit 2 -> z taken from a_max.
  const int kEdges[24] = int[24](0, 1, 2, 3, 4, 5, 6, 7,   // along x
                                 0, 2, 1, 3, 4, 6, 5, 7,   // along y
                                 0, 4, 1, 5, 2, 6, 3, 7);  // along z
  int c = kEdges[gl_VertexID];
  vec3 p = vec3((c & 1) != 0 ? a_max.x : a_min.x, (c & 2) != 0 ? a_max.y : a_min.y,
                (c & 4) != 0 ? a_max.z : a_min.z);
  v_color = a_color;
  gl_Position = u_proj * u_view * vec4(p, 1.0);
}
