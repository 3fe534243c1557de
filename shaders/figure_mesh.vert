#version 430 core
// Tree figure (fast/tree_figure.h): the mesh, flat-shaded. Positions are already centred and
// scaled into the unit ball on the CPU; each vertex carries its face's normal.
layout(location = 0) in vec3 a_pos;
layout(location = 1) in vec3 a_normal;

uniform mat4 u_view_proj;

out vec3 v_normal;

void main() {
  v_normal = a_normal;
  gl_Position = u_view_proj * vec4(a_pos, 1.0);
}
