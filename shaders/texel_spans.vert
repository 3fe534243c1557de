#version 430 core
// The GL cubemap estimator (fast/gl_estimator.h), pass 1: one instance per texel span, that is
// one (mesh face, cubemap face) pair of one box, drawn as a quad over the span's texels in the
// atlas. The quad only chooses which texels to test; texel_spans.frag decides each texel with
// the same ray test as the CPU twin (fast/texel_plan.h), so the rasterizer's coverage rules
// play no part in the result.
layout(location = 0) in ivec4 a_span;   // i0, j0, i1, j1: texels of the span
layout(location = 1) in ivec4 a_meta;   // atlas pixel of texel (0, 0) of this cubemap face; flags; unused
layout(location = 2) in vec3 a_edge0;   // +-(p0 x p1), see fast/texel_plan.h
layout(location = 3) in vec3 a_edge1;   // +-(p1 x p2)
layout(location = 4) in vec3 a_edge2;   // +-(p2 x p0)
layout(location = 5) in vec4 a_plane;   // normal, normal . p0

uniform vec2 u_atlas_size;

flat out ivec3 v_meta;
flat out vec3 v_edge0;
flat out vec3 v_edge1;
flat out vec3 v_edge2;
flat out vec4 v_plane;

void main() {
  // Triangle strip over the corners (i0, j0), (i1 + 1, j0), (i0, j1 + 1), (i1 + 1, j1 + 1).
  const int x = (gl_VertexID & 1) != 0 ? a_span.z + 1 : a_span.x;
  const int y = (gl_VertexID & 2) != 0 ? a_span.w + 1 : a_span.y;
  const vec2 pixel = vec2(a_meta.xy + ivec2(x, y));
  gl_Position = vec4(pixel / u_atlas_size * 2.0 - 1.0, 0.0, 1.0);
  v_meta = a_meta.xyz;
  v_edge0 = a_edge0;
  v_edge1 = a_edge1;
  v_edge2 = a_edge2;
  v_plane = a_plane;
}
