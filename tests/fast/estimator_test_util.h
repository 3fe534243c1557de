// Tolerance helpers shared by the estimator tests (CPU twin and GL).
#pragma once

#include <algorithm>
#include <array>
#include <cmath>
#include <random>

#include "common/mesh.h"
#include "common/obb.h"

namespace vobb::test {

// The plan's own rounding for an axis-aligned box over a mesh of surface area `area`: a local
// coordinate is (p - c) (1 rounding) times 1 / h from Eigen's inverse of diag(h) (cofactor,
// determinant and quotient: 4), a product (1): relative error gamma_6 in each coordinate, so
// the surface the plan encodes lies within gamma_6 |p - c| of the mesh's, and the volume it
// cuts from the box moves by at most area * sqrt(3) gamma_6 max|p - c| (first order; the
// second-order terms are 1e-16 times smaller and covered by taking gamma_7).
inline double aligned_plan_round_off(const Mesh& mesh, double area, const Obb& box) {
  double far = 0;
  for (const Vec3& v : mesh.vertices) far = std::max(far, (v - box.center).norm());
  const double u = 0x1p-53;
  return area * std::sqrt(3.0) * 7 * u / (1 - 7 * u) * far;
}

// A convex bipyramid over a k-gon whose apexes lie exactly on the ray along d, at 1/4 and 3/4
// of d (dyadic when d is), its rim around d / 2 with radius about 0.02 |d| and generic
// (seeded, not dyadic) vertices, faces outward. A ray along d passes through both apexes,
// each shared by k faces whose edge crosses are all rounded.
inline Mesh bipyramid_on_ray(const Vec3& d, int k, unsigned seed) {
  const Vec3 e1 = d.cross(Vec3(0, 0, 1)).normalized(), e2 = d.normalized().cross(e1);
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> jitter(0.0, 1.0);
  Mesh mesh;
  mesh.vertices.push_back(0.25 * d);
  mesh.vertices.push_back(0.75 * d);
  for (int i = 0; i < k; ++i) {
    const double a = 2 * M_PI * (i + 0.8 * jitter(rng)) / k,
                 r = 0.02 * d.norm() * (1 + 0.1 * jitter(rng));
    mesh.vertices.push_back(0.5 * d + r * std::cos(a) * e1 + r * std::sin(a) * e2);
  }
  for (int32_t i = 0; i < k; ++i) {
    const int32_t w0 = 2 + i, w1 = 2 + (i + 1) % k;
    mesh.faces.push_back({0, w1, w0});
    mesh.faces.push_back({1, w0, w1});
  }
  double vol = 0;  // six times the signed volume: positive when the faces point out
  for (const Face& f : mesh.faces)
    vol += mesh.vertices[f[0]].dot(mesh.vertices[f[1]].cross(mesh.vertices[f[2]]));
  if (vol < 0)
    for (Face& f : mesh.faces) std::swap(f[1], f[2]);
  return mesh;
}

// The review's generic rotation (three orthonormal axes to round-off) and the cube [-1, 1]^3
// in the frame (a2, a0, a1), its faces outward: a mesh none of whose faces is axis-aligned.
inline const Vec3 kTurnedA0(-0.8221300000911982, -0.511570111605987, -0.2497964848861659);
inline const Vec3 kTurnedA1(-0.4326647158294003, 0.8466302197288976, -0.30986854425395105);
inline const Vec3 kTurnedA2(0.3700047386538593, -0.14667410116730417, -0.9173784395877487);
// The 12 outward triangles of a cube whose vertex i is at corner (i & 1, i & 2, i & 4) of some
// right-handed frame.
inline void add_cube_faces(Mesh* cube) {
  for (const auto& q : {std::array<int32_t, 4>{0, 4, 6, 2},
                        {1, 3, 7, 5},
                        {0, 1, 5, 4},
                        {2, 6, 7, 3},
                        {0, 2, 3, 1},
                        {4, 5, 7, 6}}) {
    cube->faces.push_back({q[0], q[1], q[2]});
    cube->faces.push_back({q[0], q[2], q[3]});
  }
}

inline Mesh turned_cube() {
  Mesh cube;
  for (int i = 0; i < 8; ++i)
    cube.vertices.push_back((i & 1 ? 1 : -1) * kTurnedA2 + (i & 2 ? 1 : -1) * kTurnedA0 +
                            (i & 4 ? 1 : -1) * kTurnedA1);
  add_cube_faces(&cube);
  return cube;
}

}  // namespace vobb::test
