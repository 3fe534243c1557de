#version 430 core
// Pass 1, per texel: the ray from the box centre through the texel centre against one mesh
// face, in box-normalized coordinates; the hit's value is added into the texel (additive
// blending into an R32F atlas). The same test, in double, is texel_hit() in fast/texel_plan.h:
// keep the two in step.
flat in ivec3 v_meta;  // atlas pixel of texel (0, 0); flags: bits 0-2 cubemap face,
                       // bit 6 far-count mode
flat in vec3 v_edge0;
flat in vec3 v_edge1;
flat in vec3 v_edge2;
flat in vec4 v_plane;

uniform int u_m;

layout(location = 0) out float o_value;

// Exact zeros by simulation of simplicity, as edge_side() in fast/texel_plan.h: the first
// nonzero of E[a], E[b], E[k].
int edge_side(float e, vec3 E, int k) {
  if (e > 0.0) return 1;
  if (e < 0.0) return -1;
  const float first = E[(k + 1) % 3] != 0.0 ? E[(k + 1) % 3] : E[(k + 2) % 3] != 0.0 ? E[(k + 2) % 3] : E[k];
  return first > 0.0 ? 1 : first < 0.0 ? -1 : 0;
}

void main() {
  const int flags = v_meta.z;
  const ivec2 ij = ivec2(gl_FragCoord.xy) - v_meta.xy;
  const float fm = float(u_m);
  precise float u = -1.0 + float(2 * ij.x + 1) / fm;
  precise float v = -1.0 + float(2 * ij.y + 1) / fm;
  const int face = flags & 7;
  const int k = face >> 1;
  vec3 d;
  d[k] = (face & 1) == 0 ? 1.0 : -1.0;
  d[(k + 1) % 3] = u;
  d[(k + 2) % 3] = v;

  precise float e0 = dot(d, v_edge0);
  precise float e1 = dot(d, v_edge1);
  precise float e2 = dot(d, v_edge2);
  const int s0 = edge_side(e0, v_edge0, k);
  if (s0 == 0 || edge_side(e1, v_edge1, k) != s0 || edge_side(e2, v_edge2, k) != s0) discard;
  precise float nd = dot(v_plane.xyz, d);
  if (nd == 0.0) discard;  // the ray runs in the face's plane
  precise float zeta = v_plane.w / nd;
  if (!(zeta > 0.0)) discard;  // behind the centre, or at it
  const float s = nd > 0.0 ? 1.0 : -1.0;
  precise float z3 = zeta * zeta * zeta;
  if ((flags & 64) == 0) {
    if (!(zeta < 1.0)) discard;
    o_value = s * (1.0 - z3);
  } else {
    o_value = zeta < 1.0 ? -s * z3 : -s;
  }
}
