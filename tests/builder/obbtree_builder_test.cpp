#include "builder/obbtree_builder.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <limits>
#include <numeric>

#include "common/io/mesh_io.h"
#include "common/tree_io.h"
#include "data/analytic_meshes.h"
#include "test_common.h"

namespace vobb {
namespace {

// Every node's faces lie in its box (exact predicates), the structure is valid, and each
// node at a level below `depth` with more than one face has children.
void expect_valid_conservative(const Mesh& m, const Tree& t, int depth) {
  const Status s = validate_tree(t, "tree");
  ASSERT_TRUE(s) << s.message();
  const ContainmentReport c = check_conservative(m, t);
  EXPECT_TRUE(c.ok()) << c.violations << " (node, face) pairs outside";
  EXPECT_EQ(c.checked_pairs, [&] {
    size_t n = 0;
    for (const TreeNode& node : t.nodes) n += node.faces.size();
    return n;
  }());
  for (const TreeNode& node : t.nodes) {
    if (node.level < depth && node.faces.size() > 1) {
      EXPECT_FALSE(node.is_leaf()) << node.id;
    }
  }
}

TEST(ObbTree, AnalyticMeshesGiveValidConservativeTrees) {
  for (const auto& a : analytic::all())
    for (int arity : {2, 3, 4}) {
      SCOPED_TRACE(a.name + " arity " + std::to_string(arity));
      ObbTreeOptions o;
      o.depth = 4;
      o.arity = arity;
      const Tree t = build_obbtree(a.mesh, o);
      expect_valid_conservative(a.mesh, t, o.depth);
      for (const TreeNode& n : t.nodes) EXPECT_LE(static_cast<int>(n.children.size()), arity);
    }
}

TEST(ObbTree, CovarianceMajorAxisFollowsTheLongSide) {
  Mesh m = analytic::cube().mesh;
  for (Vec3& v : m.vertices) v[1] *= 8;  // 1 x 8 x 1
  std::vector<int32_t> all(m.faces.size());
  std::iota(all.begin(), all.end(), 0);
  const auto axes = covariance_axes(m, all);
  // The major axis is y. Its tilt is bounded by the error of the computed covariance over the
  // gap between its two largest eigenvalues (Davis-Kahan): the entries are sums over 12
  // triangles of a few dozen rounded operations each, so their error is under 256 eps of the
  // largest eigenvalue; Eigen's 3x3 solver adds a few more (8 allowed). The surface's
  // covariance of the 1 x 8 x 1 box has eigenvalues 5.961 (y) and 0.1618 (x, z), so the gap
  // is 1 - 1 / 36.85 of the largest: tilt <= 264 eps / 0.9729. The off-axis components are
  // checked, since |a0.y| near 1 would allow a tilt of sqrt(2 tol), a thousand times more.
  const double tilt = 264 * std::numeric_limits<double>::epsilon() / (1 - 1 / 36.85);
  EXPECT_LE(std::abs(axes[0][0]), tilt);
  EXPECT_LE(std::abs(axes[0][2]), tilt);
  // A right-handed orthonormal frame: unit determinant to the rounding of its 9 products.
  EXPECT_NEAR(axes[0].cross(axes[1]).dot(axes[2]), 1.0,
              16 * std::numeric_limits<double>::epsilon());
}

// The root's split obeys the RAPID rule: every face of the first child has its centroid
// below the area-weighted mean along the major axis, every face of the second at or above.
TEST(ObbTree, RootSplitsAtTheAreaWeightedMean) {
  const Mesh m = analytic::polygonal_torus(1, 0.5, 3).mesh;
  ObbTreeOptions o;
  o.depth = 1;
  const Tree t = build_obbtree(m, o);
  ASSERT_EQ(t.nodes.size(), 3u);
  const auto axes = covariance_axes(m, t.nodes[0].faces);
  double area = 0, moment = 0;
  for (int32_t f : t.nodes[0].faces) {
    const double a = m.double_area(f);
    const Vec3 c = (m.corner(f, 0) + m.corner(f, 1) + m.corner(f, 2)) / 3;
    area += a;
    moment += a * c.dot(axes[0]);
  }
  const double mean = moment / area;
  auto proj = [&](int32_t f) {
    return ((m.corner(f, 0) + m.corner(f, 1) + m.corner(f, 2)) / 3).dot(axes[0]);
  };
  for (int32_t f : t.nodes[1].faces) EXPECT_LT(proj(f), mean);
  for (int32_t f : t.nodes[2].faces) EXPECT_GE(proj(f), mean);
}

// The tree depends on the faces' geometry and order, not on how the vertices are numbered:
// the vertex list reversed (and the faces renumbered to match) gives the same bytes.
TEST(ObbTree, VertexNumberingDoesNotChangeTheTree) {
  const Mesh m = analytic::polygonal_torus().mesh;
  Mesh renumbered = m;
  const int32_t n = static_cast<int32_t>(m.vertices.size());
  std::reverse(renumbered.vertices.begin(), renumbered.vertices.end());
  for (Face& f : renumbered.faces)
    for (int k = 0; k < 3; ++k) f[k] = n - 1 - f[k];
  ASSERT_EQ(renumbered.corner(5, 1), m.corner(5, 1));
  ObbTreeOptions o;
  o.depth = 5;
  EXPECT_EQ(tree_to_json(build_obbtree(renumbered, o)), tree_to_json(build_obbtree(m, o)));
}

class ObbTreeReal : public ::testing::TestWithParam<const char*> {};

// The acceptance: a depth-8 binary tree of 511 nodes on each real mesh (fewer only
// where a leaf holds a single face), every box conservative.
TEST_P(ObbTreeReal, Depth8IsConservativeWith511Nodes) {
  VOBB_REQUIRE_REAL_MESH(GetParam());
  LoadedMesh lm;
  ASSERT_TRUE(load_mesh(test::real_mesh(GetParam()), &lm));
  ObbTreeOptions o;
  o.depth = 8;
  const Tree t = build_obbtree(lm.mesh, o);
  // A full binary tree of depth 8 has 511 nodes; a leaf at level l < 8 (a single face, which
  // cannot be split) stands where a full subtree of 2^(9 - l) - 1 nodes would be.
  size_t missing = 0;
  for (const TreeNode& n : t.nodes)
    if (n.is_leaf() && n.level < 8) {
      EXPECT_EQ(n.faces.size(), 1u) << "leaf " << n.id << " above level 8";
      missing += (size_t{1} << (9 - n.level)) - 2;
    }
  EXPECT_EQ(t.nodes.size(), 511u - missing);
  EXPECT_EQ(t.depth, 8);
  expect_valid_conservative(lm.mesh, t, 8);
}

// The checker behind those assertions does catch a box that misses its faces.
TEST(ObbTree, ShrunkenBoxIsCaught) {
  const Mesh m = analytic::polygonal_torus().mesh;
  ObbTreeOptions o;
  o.depth = 3;
  Tree t = build_obbtree(m, o);
  ASSERT_TRUE(check_conservative(m, t).ok());
  t.nodes[2].box.half[0] *= 0.99;
  const ContainmentReport c = check_conservative(m, t);
  EXPECT_FALSE(c.ok());
  ASSERT_FALSE(c.first.empty());
  EXPECT_EQ(c.first[0].first, 2);
}

INSTANTIATE_TEST_SUITE_P(Meshes, ObbTreeReal, ::testing::Values("dino", "knot1", "elephant"));

}  // namespace
}  // namespace vobb
