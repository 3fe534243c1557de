// FCL as the outside referee (fcl_referee.h), on its own: the loaded model is FCL's binary tree
// of one triangle per leaf whatever our arity and leaf sizes, the padding nodes are counted by
// FCL but not as ours, FCL finds the faces brute force finds on poses where every face is
// clearly in or out, and a tree FCL cannot hold is refused in one line.
#include "validate/collision/fcl_referee.h"

#include <gtest/gtest.h>

#include <cmath>
#include <random>

#include "builder/obbtree_builder.h"
#include "data/analytic_meshes.h"
#include "validate/collision/collision_test_util.h"

namespace vobb::collision {
namespace {

using test_util::root_with_one_child;
using test_util::single_leaf;

Tree baseline(const Mesh& mesh, int depth, int arity = 2) {
  ObbTreeOptions opt;
  opt.depth = depth;
  opt.arity = arity;
  return build_obbtree(mesh, opt);
}

Collider sphere(const Vec3& c, double r) {
  Collider s;
  s.shape = ColliderShape::kSphere;
  s.center = c;
  s.radius = r;
  return s;
}

// A binary BVH with one triangle per leaf has exactly 2n - 1 nodes, however our tree groups the
// n faces: the loaded model must be that tree, for FCL's own build and for ours at arity 2 and
// 4, with leaves of one face or many.
TEST(FclReferee, LoadedModelsAreBinaryWithOneTrianglePerLeaf) {
  const Mesh mesh = analytic::polygonal_torus().mesh;
  const size_t want = 2 * mesh.faces.size() - 1;
  EXPECT_EQ(FclModel::fcl_own(mesh)->bv_count(), want);
  for (const Tree& t :
       {baseline(mesh, 2), baseline(mesh, 12), baseline(mesh, 3, 4), single_leaf(mesh)}) {
    SCOPED_TRACE(t.nodes.size());
    std::unique_ptr<FclModel> m;
    const Status s = FclModel::from_tree(mesh, t, "t.json", &m);
    ASSERT_TRUE(s) << s.message();
    EXPECT_EQ(m->bv_count(), want);
  }
}

// One leaf holding every face: FCL's padding nodes below it all carry the leaf's box, so when a
// collider meets that box FCL tests all 2n - 1 of them and all n triangles, of which one test
// (the root) is on a node of ours; a collider far from the box costs FCL one test and no
// triangle. FCL's own model counts every test as on its nodes.
TEST(FclReferee, PaddingNodesAreCountedByFclButNotAsOurs) {
  const Mesh mesh = analytic::polygonal_torus().mesh;
  const size_t n = mesh.faces.size();
  const Tree t = single_leaf(mesh);
  std::unique_ptr<FclModel> m;
  ASSERT_TRUE(FclModel::from_tree(mesh, t, "t.json", &m));
  // The ring spans z in [0, 1] and, on the positive x axis, x in [1.5, 3]: this sphere dips
  // into its top face.
  const Collider near = sphere(Vec3(2.2, 0, 1.1), 0.3);
  const FclQueryResult hit = m->query(near);
  EXPECT_TRUE(hit.collide);
  EXPECT_EQ(hit.bv_tests, 2 * n - 1);
  EXPECT_EQ(hit.leaf_tests, n);
  EXPECT_EQ(hit.tree_node_bv_tests, 1u);

  const Collider far = sphere(Vec3(100, 100, 100), 0.5);
  const FclQueryResult miss = m->query(far);
  EXPECT_FALSE(miss.collide);
  EXPECT_TRUE(miss.faces.empty());
  EXPECT_EQ(miss.bv_tests, 1u);
  EXPECT_EQ(miss.leaf_tests, 0u);
  EXPECT_EQ(miss.tree_node_bv_tests, 1u);

  const FclQueryResult own = FclModel::fcl_own(mesh)->query(near);
  EXPECT_TRUE(own.collide);
  EXPECT_EQ(own.tree_node_bv_tests, own.bv_tests);
  EXPECT_LT(own.bv_tests, 2 * n - 1) << "FCL's own tree should prune some of the torus";
}

// FCL's answers are brute force's. FCL decides a sphere against a triangle in its own floating
// point, so poses where a face lies within 1e-6 r of the sphere's surface (where the two
// roundings may legitimately differ) are drawn again: on the rest every face is in or out by a
// margin far above either rounding (both are a few ulps of the torus' size, about 1e-15), so the
// face sets must be equal, on FCL's own model and on ours at arity 2 and 4.
TEST(FclReferee, FindsTheFacesBruteForceFindsOnClearPoses) {
  const Mesh mesh = analytic::polygonal_torus().mesh;
  const double scale = mesh_scale(mesh);
  std::vector<std::unique_ptr<FclModel>> models;
  models.push_back(FclModel::fcl_own(mesh));
  for (const Tree& t : {baseline(mesh, 4), baseline(mesh, 3, 4)}) {
    models.emplace_back();
    ASSERT_TRUE(FclModel::from_tree(mesh, t, "t.json", &models.back()));
  }
  std::mt19937_64 rng(11);
  std::uniform_real_distribution<double> u(-3.5, 3.5), uz(-0.5, 1.5), ur(0.05, 0.8);
  int queries = 0, touching = 0;
  while (queries < 200) {
    const Collider c = sphere(Vec3(u(rng), u(rng), uz(rng)), ur(rng));
    std::vector<int32_t> want;
    bool clear = true;
    for (size_t f = 0; f < mesh.faces.size() && clear; ++f) {
      const Vec3 p = closest_point_on_triangle(c.center, mesh.corner(f, 0), mesh.corner(f, 1),
                                               mesh.corner(f, 2));
      const double d = (p - c.center).norm();
      clear = std::abs(d - c.radius) > 1e-6 * c.radius;
      if (d < c.radius) want.push_back(static_cast<int32_t>(f));
    }
    if (!clear) continue;
    ++queries;
    touching += !want.empty();
    // touches_triangle, the predicate of brute force and of our traversal, agrees on clear poses.
    const PreparedCollider pc = prepare_collider(c, scale);
    for (size_t f = 0; f < mesh.faces.size(); ++f)
      ASSERT_EQ(touches_triangle(pc, mesh.corner(f, 0), mesh.corner(f, 1), mesh.corner(f, 2)),
                std::binary_search(want.begin(), want.end(), static_cast<int32_t>(f)));
    for (size_t k = 0; k < models.size(); ++k) {
      SCOPED_TRACE(k);
      const FclQueryResult r = models[k]->query(c);
      ASSERT_EQ(r.collide, !want.empty());
      ASSERT_EQ(r.faces, want);
      ASSERT_LE(r.tree_node_bv_tests, r.bv_tests);
    }
  }
  // Not vacuous: both kinds of answer occurred.
  EXPECT_GT(touching, 20);
  EXPECT_LT(touching, queries - 20);
}

// A node with a single child cannot become a binary node: refused, in one line naming the file.
TEST(FclReferee, RefusesANodeWithASingleChild) {
  const Mesh mesh = analytic::polygonal_torus().mesh;
  const Tree t = root_with_one_child(mesh);
  std::unique_ptr<FclModel> m;
  const Status s = FclModel::from_tree(mesh, t, "single.json", &m);
  EXPECT_FALSE(s);
  EXPECT_EQ(s.message().rfind("single.json: ", 0), 0u) << s.message();
  EXPECT_EQ(s.message().find('\n'), std::string::npos);
  EXPECT_EQ(m, nullptr);
}

}  // namespace
}  // namespace vobb::collision
