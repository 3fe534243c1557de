#version 430 core
// Tree figure: box edges as screen-space quads of a fixed width in pixels (core profile gives
// no wide lines). One instance per edge, four vertices per instance (a triangle strip):
// vertices 0, 1 at endpoint p0, vertices 2, 3 at p1, on either side of the edge, each end
// pushed out along the edge by half the width so that the edges of a box meet at its corners.
layout(location = 0) in vec3 a_p0;
layout(location = 1) in vec3 a_p1;
layout(location = 2) in vec4 a_color;

uniform mat4 u_view_proj;
uniform vec2 u_viewport;     // panel size in pixels
uniform float u_half_width;  // pixels
uniform float u_depth_bias;  // NDC depth towards the viewer, so edges on the mesh win

out vec4 v_color;

void main() {
  vec4 c0 = u_view_proj * vec4(a_p0, 1.0);
  vec4 c1 = u_view_proj * vec4(a_p1, 1.0);
  vec2 s0 = c0.xy / c0.w * 0.5 * u_viewport;  // pixels from the panel centre
  vec2 s1 = c1.xy / c1.w * 0.5 * u_viewport;
  vec2 d = s1 - s0;
  float len = length(d);
  vec2 along = len > 1e-6 ? d / len : vec2(1.0, 0.0);  // an edge seen end-on: any direction
  vec2 across = vec2(-along.y, along.x);
  bool at_p1 = gl_VertexID >= 2;
  float side = (gl_VertexID & 1) == 0 ? -1.0 : 1.0;
  vec4 c = at_p1 ? c1 : c0;
  vec2 s = (at_p1 ? s1 : s0) + u_half_width * (side * across + (at_p1 ? along : -along));
  v_color = a_color;
  gl_Position = vec4(s / (0.5 * u_viewport) * c.w, c.z - u_depth_bias * c.w, c.w);
}
