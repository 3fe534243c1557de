// A box and a mesh in special position, shared by the filter's tests: the box's +T_0 face
// passes exactly through a mesh vertex, by construction (the vertex is the box's edge vector
// u_0 itself, with c = 0 and h_0 = 1). Its side value T_0(v) - R is 0 exactly, but with the
// axes turned about a general axis T_0(v) and R are sums of products of five doubles (265
// bits), which 128 and 256 bits both round, so an enclosure holds 0 and other values and the
// filter must fall back to rationals.
#pragma once

#include <utility>
#include <vector>

#include "common/exact_predicates.h"
#include "common/mesh.h"
#include "common/obb.h"

namespace vobb::test {

inline Obb box_through_vertex() {
  return rotated_box(Vec3(0, 0, 0), Vec3(1, 0.7, 0.3), 0.4, Vec3(1, 2, 3));
}

// A tetrahedron inside `b` (its other vertices within 0.15 of the centre, well inside the
// smallest half extent 0.3) with vertex 0 at b's axis 0, on its +T_0 face; outward oriented.
inline Mesh tetrahedron_touching(const Obb& b) {
  Mesh m;
  m.vertices = {b.axes[0], Vec3(-0.1, 0.05, 0.1), Vec3(-0.05, -0.1, -0.1), Vec3(0.1, -0.1, 0.05)};
  m.faces = {{0, 2, 1}, {0, 1, 3}, {0, 3, 2}, {1, 2, 3}};
  if (exact_signed_volume(m) < 0)
    for (Face& f : m.faces) std::swap(f[1], f[2]);
  return m;
}

// Two boxes whose overlap is a sliver: b is a turned by 1e-11 rad more about the same axis and
// moved along a's axis 0 by 2 h_0, so that b's -T_0 face meets a's +T_0 face at that angle. The
// cut points on edges that nearly parallel a plane carry the angle's inverse square into their
// enclosures: 128 bits enclose the sliver's volume (about 4e-13) only to about 1e-15 of itself,
// too wide to round it, and 256 bits to about 1e-54 (measured;
// tests/exact/filtered_solver_test.cpp).
inline std::vector<Obb> sliver_pair() {
  const Obb a = rotated_box(Vec3(0.3, 0.2, 0.1), Vec3(0.5, 0.4, 0.3), 0.3, Vec3(1, 2, 3));
  Obb b = rotated_box(Vec3(0.3, 0.2, 0.1), Vec3(0.5, 0.4, 0.3), 0.3 + 1e-11, Vec3(1, 2, 3));
  b.center = a.center + a.axes[0] * (2 * a.half[0]);
  return {a, b};
}

}  // namespace vobb::test
