// Collider–triangle and collider–box tests of the collision experiment (paper §5).
//
// A collider is a sphere or a box, given in the model's frame (the mesh's own coordinates).
// Two kinds of test:
//  - `touches_triangle`: does the collider touch a mesh face? Brute force and every tree's
//    leaves call this same function, so their answers can be compared with `==`.
//      box:    exact. The closed parallelepiped c + sum_k t_k half_k axes_k (t in [-1,1]^3, the
//              stored doubles taken as exact rationals) meets the closed triangle. A separating-
//              axis test in outward-rounded interval arithmetic decides the easy cases and GMP
//              rationals the rest.
//      sphere: in double (closest point on the triangle, squared distance <= r^2). Not exact,
//              but one-sided bounded: when it says "touches", the true distance from the centre
//              to the triangle is at most r + `sphere_slack` (derivation in the .cpp).
//  - `may_touch_box`: the pruning test of a tree node. Conservative: it never rejects a node
//    box whose certified solid (DESIGN §1) holds a face for which `touches_triangle` is true.
//    It tests the box itself, not a bounding volume of the collider, with a round-off margin
//    derived in the .cpp; the margin is a few ulps of the scene's size.
// So a tree whose boxes contain their faces (check_conservative) finds exactly the faces that
// brute force finds, whatever the float rounding.
#pragma once

#include <array>
#include <cstdint>

#include "common/mesh.h"
#include "common/obb.h"

namespace vobb::collision {

enum class ColliderShape { kSphere, kBox };

struct Collider {
  ColliderShape shape = ColliderShape::kSphere;
  Vec3 center = Vec3::Zero();
  double radius = 0;  // sphere, > 0
  // Box: axes (unit, nearly orthonormal; world = model frame) and half extents (> 0).
  std::array<Vec3, 3> axes = {Vec3::UnitX(), Vec3::UnitY(), Vec3::UnitZ()};
  Vec3 half = Vec3::Zero();
};

// A collider with what every test of one query shares. `mesh_scale` is the largest vertex
// norm of the mesh (it bounds every triangle coordinate in the round-off margins).
struct PreparedCollider {
  Collider c;
  Aabb bounds;              // outward-rounded: holds the collider's solid
  double sphere_slack = 0;  // sphere: touches_triangle's one-sided distance bound; box: 0
  double extent = 0;        // radius, or sum_k half_k |axes_k|: bounds |x - centre| over the solid
};
PreparedCollider prepare_collider(const Collider& c, double mesh_scale);

// Largest vertex norm of the mesh.
double mesh_scale(const Mesh& mesh);

bool touches_triangle(const PreparedCollider& c, const Vec3& p0, const Vec3& p1, const Vec3& p2);

// A tree node's box with what every query of it shares.
struct PreparedBox {
  Obb box;
  double orth_error = 0;  // max |a_i . a_j - delta_ij| over the stored axes, as computed
  double extent = 0;      // |centre| + sum_k half_k |axes_k|
  double half_norm = 0;   // |half|
};
PreparedBox prepare_box(const Obb& box);

bool may_touch_box(const PreparedCollider& c, const PreparedBox& b);

// For contact generation in the dynamic scene: the closest point of the triangle to p.
Vec3 closest_point_on_triangle(const Vec3& p, const Vec3& a, const Vec3& b, const Vec3& c);

// Counters of how often the exact fallback of the box test ran (all threads; for reports).
uint64_t exact_fallbacks();

}  // namespace vobb::collision
