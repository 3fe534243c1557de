// Brute force, the check of every tree's answers in the collision experiment: its blocked
// screen of the faces' bounding boxes must give touches_triangle's answer on every face, and
// the tree traversal must give brute force's.
#include "collision/tree_traversal.h"

#include <gtest/gtest.h>

#include <cmath>
#include <random>

#include "builder/obbtree_builder.h"
#include "data/analytic_meshes.h"

namespace vobb::collision {
namespace {

// The definition: touches_triangle on every face, in mesh order.
std::vector<int32_t> every_face(const Mesh& mesh, const PreparedCollider& c) {
  std::vector<int32_t> out;
  for (size_t f = 0; f < mesh.faces.size(); ++f)
    if (touches_triangle(c, mesh.corner(f, 0), mesh.corner(f, 1), mesh.corner(f, 2)))
      out.push_back(static_cast<int32_t>(f));
  return out;
}

// A soup of 1,000 small triangles in [-1, 1]^3 (1,000 = 3 blocks of 256 and a partial one),
// and 2,000 random spheres and boxes from tiny to larger than the soup; at unit scale, and
// scaled by 2^-140 and 2^200, where the screen's floats are subnormal or beyond float's range.
class BruteForceAtScale : public ::testing::TestWithParam<double> {};

TEST_P(BruteForceAtScale, EqualsTouchesTriangleOnEveryFace) {
  const double s = GetParam();
  std::mt19937_64 rng(7);
  std::uniform_real_distribution<double> u(-1, 1);
  Mesh soup;
  for (int f = 0; f < 1000; ++f) {
    const Vec3 a(u(rng), u(rng), u(rng));
    for (int k = 0; k < 3; ++k)
      soup.vertices.push_back(s * (k == 0 ? a : Vec3(a + 0.05 * Vec3(u(rng), u(rng), u(rng)))));
    soup.faces.push_back({3 * f, 3 * f + 1, 3 * f + 2});
  }
  ASSERT_NE(soup.faces.size() % 256, 0u);
  const BruteForce brute(soup);
  const double scale = mesh_scale(soup);
  std::vector<int32_t> got;
  size_t touching = 0, big = 0;
  for (int q = 0; q < 2000; ++q) {
    Collider c;
    c.center = s * 1.2 * Vec3(u(rng), u(rng), u(rng));
    const double size = s * std::pow(10.0, 3 * (u(rng) + 1) / 2 - 3.0) * 2;  // 0.002 ... 2, times s
    if (q % 2) {
      c.shape = ColliderShape::kSphere;
      c.radius = size;
    } else {
      c.shape = ColliderShape::kBox;
      const Eigen::Matrix3d r =
          Eigen::Quaterniond(u(rng), u(rng), u(rng), u(rng)).normalized().toRotationMatrix();
      for (int k = 0; k < 3; ++k) {
        c.axes[k] = r.col(k);
        c.half[k] = size * (0.5 + 0.5 * (u(rng) + 1) / 2);
      }
    }
    const PreparedCollider pc = prepare_collider(c, scale);
    brute.touching(pc, &got);
    const std::vector<int32_t> want = every_face(soup, pc);
    ASSERT_EQ(got, want) << "query " << q;
    touching += !want.empty();
    big += want.size() > 256;
  }
  // Both kinds of answer occur, and some span more than a block.
  EXPECT_GT(touching, 200u);
  EXPECT_LT(touching, 1800u);
  EXPECT_GT(big, 10u);
}

INSTANTIATE_TEST_SUITE_P(Scales, BruteForceAtScale,
                         ::testing::Values(1.0, std::ldexp(1.0, -140), std::ldexp(1.0, 200)));

// The traversal finds what brute force finds, on the baseline tree of a torus.
TEST(TreeTraversal, FindsWhatBruteForceFinds) {
  const Mesh mesh = analytic::polygonal_torus().mesh;
  ObbTreeOptions o;
  o.depth = 4;
  const Tree tree = build_obbtree(mesh, o);
  const TreeTraversal walk(mesh, tree);
  const BruteForce brute(mesh);
  std::mt19937_64 rng(3);
  std::uniform_real_distribution<double> u(-2, 2);
  std::vector<int32_t> a, b;
  QueryCounts counts;
  size_t touching = 0, found = 0;
  for (int q = 0; q < 500; ++q) {
    Collider c;
    c.center = Vec3(u(rng), u(rng), 0.5 * u(rng));
    c.radius = 0.05 + 0.1 * (u(rng) + 2);
    const PreparedCollider pc = prepare_collider(c, mesh_scale(mesh));
    walk.query(pc, &a, &counts);
    brute.touching(pc, &b);
    ASSERT_EQ(a, b) << "query " << q;
    touching += !b.empty();
    found += b.size();
  }
  EXPECT_GT(touching, 50u);
  EXPECT_EQ(counts.contacts, found);
}

}  // namespace
}  // namespace vobb::collision
