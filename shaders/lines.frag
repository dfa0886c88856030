#version 330 core
// Unlit colour for line primitives (lines.vert and box.vert).
in vec3 v_color;

uniform float u_opacity;

layout(location = 0) out vec4 o_color;

void main() { o_color = vec4(v_color, u_opacity); }
