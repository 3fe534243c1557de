// The collider tests of the collision experiment: the box–triangle test is exact on its
// boundary (touching counts), and the node test never prunes a box that holds a face the
// triangle test accepts.
#include "collision/contact_predicates.h"

#include <gtest/gtest.h>

#include <cmath>
#include <random>

namespace vobb::collision {
namespace {

Collider unit_box_at(const Vec3& c) {
  Collider b;
  b.shape = ColliderShape::kBox;
  b.center = c;
  b.half = Vec3::Constant(0.5);
  return b;
}

// A box whose top face lies exactly in the triangle's plane touches it; one ulp lower it
// does not. Both cases sit inside the interval filter's doubt, so the rational path decides.
TEST(ContactPredicates, BoxTouchingATriangleExactlyOnItsPlane) {
  const Vec3 p0(-1, -1, 1), p1(1, -1, 1), p2(0, 1, 1);
  uint64_t before = exact_fallbacks();
  EXPECT_TRUE(touches_triangle(prepare_collider(unit_box_at(Vec3(0, 0, 0.5)), 2), p0, p1, p2));
  EXPECT_GT(exact_fallbacks(), before);  // each case decided in rationals
  before = exact_fallbacks();
  const double below = std::nextafter(0.5, 0.0);
  EXPECT_FALSE(touches_triangle(prepare_collider(unit_box_at(Vec3(0, 0, below)), 2), p0, p1, p2));
  EXPECT_GT(exact_fallbacks(), before);
  // Edge against edge: the triangle's corner touches the box's edge exactly.
  const Vec3 q0(0.5, 0.5, 0.0), q1(2, 0.5, 0.0), q2(2, 2, 0.0);
  EXPECT_TRUE(touches_triangle(prepare_collider(unit_box_at(Vec3(0, 0, 0)), 2), q0, q1, q2));
  const Vec3 r0(std::nextafter(0.5, 1.0), 0.5, 0.0);
  EXPECT_FALSE(touches_triangle(prepare_collider(unit_box_at(Vec3(0, 0, 0)), 2), r0, q1, q2));
}

TEST(ContactPredicates, SphereAgainstTriangle) {
  Collider s;
  s.radius = 0.5;
  s.center = Vec3(0, 0, 1.25);
  const Vec3 p0(-1, -1, 1), p1(1, -1, 1), p2(0, 1, 1);
  EXPECT_TRUE(touches_triangle(prepare_collider(s, 2), p0, p1, p2));
  s.center = Vec3(0, 0, 1.75);
  EXPECT_FALSE(touches_triangle(prepare_collider(s, 2), p0, p1, p2));
  s.center = Vec3(3, 3, 1);  // beside the triangle, in its plane
  EXPECT_FALSE(touches_triangle(prepare_collider(s, 2), p0, p1, p2));
}

// Property: for random boxes, random triangles inside them and random colliders, whenever the
// triangle test says "touches", the node test keeps the box. Triangles are drawn inside the
// box's solid, so this is the conservativeness that the tree traversal relies on; colliders
// are drawn so that about half of them touch.
TEST(ContactPredicates, NodeTestNeverPrunesATouchedFace) {
  std::mt19937_64 rng(7);
  std::uniform_real_distribution<double> u(-1, 1);
  int touched = 0, pruned_untouched = 0;
  for (int trial = 0; trial < 20000; ++trial) {
    Obb box;
    box.center = Vec3(u(rng), u(rng), u(rng)) * 10;
    const Eigen::Quaterniond q(u(rng), u(rng), u(rng), u(rng));
    const Eigen::Matrix3d R = q.normalized().toRotationMatrix();
    for (int k = 0; k < 3; ++k) box.axes[k] = R.col(k);
    box.half = Vec3(0.1 + std::abs(u(rng)), 0.1 + std::abs(u(rng)), 0.01 + std::abs(u(rng)));
    Vec3 p[3];
    for (Vec3& v : p) {
      v = box.center;
      for (int k = 0; k < 3; ++k) v += 0.999 * u(rng) * box.half[k] * box.axes[k];
    }
    Collider c;
    const double size = 0.05 + 0.5 * std::abs(u(rng));
    c.center = p[0] + Vec3(u(rng), u(rng), u(rng)) * 0.8;
    if (trial % 2) {
      c.shape = ColliderShape::kSphere;
      c.radius = size;
    } else {
      c.shape = ColliderShape::kBox;
      const Eigen::Quaterniond qc(u(rng), u(rng), u(rng), u(rng));
      const Eigen::Matrix3d Rc = qc.normalized().toRotationMatrix();
      for (int k = 0; k < 3; ++k)
        c.axes[k] = Rc.col(k), c.half[k] = size * (0.5 + std::abs(u(rng)));
    }
    const PreparedCollider pc = prepare_collider(c, 20);
    const bool touches = touches_triangle(pc, p[0], p[1], p[2]);
    const bool kept = may_touch_box(pc, prepare_box(box));
    if (touches) {
      ++touched;
      ASSERT_TRUE(kept) << "trial " << trial;
    } else if (!kept) {
      ++pruned_untouched;
    }
  }
  // Both outcomes occur, so the property is not vacuous.
  EXPECT_GT(touched, 1000);
  EXPECT_GT(pruned_untouched, 1000);
}

// The same property where the margins matter: a collider tangent to the box from outside. A
// triangle has a corner on a face of the box (exactly, on axis-aligned boxes of dyadic sizes;
// within rounding on turned ones), every corner in the box exactly (ExactBoxContainment). A
// collider beyond that face, its point nearest the face (a sphere's, or a box's vertex or, for
// a box turned as the node box is, its face) placed over that corner, is moved along the
// face's normal to where the triangle test's answer turns (bisection, to adjacent doubles):
// there it touches the triangle, and so the box, only at the box's surface, where the node
// test's answer rests on its round-off margins; it must keep the box.
TEST(ContactPredicates, NodeTestKeepsABoxTouchedAtItsSurface) {
  std::mt19937_64 rng(11);
  std::uniform_real_distribution<double> u(-1, 1);
  int tangent = 0;
  for (int trial = 0; trial < 4000; ++trial) {
    Obb box;
    const bool aligned = trial % 2 == 0;
    if (aligned) {
      box.center = Vec3(std::round(8 * u(rng)), std::round(8 * u(rng)), std::round(8 * u(rng)));
      box.half = Vec3(0.5, 0.25, 1.0);
    } else {
      box.center = Vec3(u(rng), u(rng), u(rng)) * 10;
      const Eigen::Quaterniond q(u(rng), u(rng), u(rng), u(rng));
      const Eigen::Matrix3d R = q.normalized().toRotationMatrix();
      for (int k = 0; k < 3; ++k) box.axes[k] = R.col(k);
      box.half = Vec3(0.1 + std::abs(u(rng)), 0.1 + std::abs(u(rng)), 0.01 + std::abs(u(rng)));
    }
    const ExactBoxContainment in_box(box);
    const int face = trial / 2 % 3;
    const double side = trial / 6 % 2 ? 1.0 : -1.0;
    Vec3 p[3];
    bool inside = true;
    for (int i = 0; i < 3; ++i) {
      p[i] = box.center;
      for (int k = 0; k < 3; ++k) {
        // Corner 0 on the face (t = +-1; dyadic multiples of 1/8 elsewhere on aligned boxes).
        double t = k == face && i == 0 ? side : 0.9 * u(rng);
        if (aligned && !(k == face && i == 0)) t = std::round(8 * t) / 8;
        p[i] += t * box.half[k] * box.axes[k];
      }
      inside = inside && in_box.contains(p[i]);
    }
    if (!inside) continue;  // a turned box's corner rounded outside it: no claim to test
    const Vec3 n = side * box.axes[face];
    Collider c;
    const double size = 0.05 + 0.5 * std::abs(u(rng));
    Vec3 over = p[0];  // where the centre goes at distance 0, before the move along n
    if (trial % 4 < 2) {
      c.shape = ColliderShape::kSphere;
      c.radius = size;
      over += size * n;
    } else {
      c.shape = ColliderShape::kBox;
      const Eigen::Quaterniond qc(u(rng), u(rng), u(rng), u(rng));
      const Eigen::Matrix3d Rc = qc.normalized().toRotationMatrix();
      for (int k = 0; k < 3; ++k) {
        c.axes[k] = trial % 8 < 4 ? box.axes[k] : Vec3(Rc.col(k));  // face to face, or a vertex
        c.half[k] = size * (0.5 + std::abs(u(rng)));
        over += (c.axes[k].dot(n) >= 0 ? 1.0 : -1.0) * c.half[k] * c.axes[k];
      }
    }
    auto at = [&](double g) {
      Collider moved = c;
      moved.center = over + g * n;
      return prepare_collider(moved, 20);
    };
    auto touches = [&](double g) { return touches_triangle(at(g), p[0], p[1], p[2]); };
    double lo = -0.5 * size, hi = size;  // reaching into the box, and clear of it
    if (!touches(lo) || touches(hi)) continue;
    while (true) {
      const double mid = 0.5 * (lo + hi);
      if (mid <= lo || mid >= hi) break;
      (touches(mid) ? lo : hi) = mid;
    }
    ++tangent;
    ASSERT_TRUE(may_touch_box(at(lo), prepare_box(box)))
        << "trial " << trial << (c.shape == ColliderShape::kSphere ? " sphere" : " box");
  }
  // Most trials reach a tangent collider: the kinds (a sphere, a box face to face, a box's
  // vertex; on an aligned or a turned box) are each tested hundreds of times.
  EXPECT_GT(tangent, 2000);
}

}  // namespace
}  // namespace vobb::collision
