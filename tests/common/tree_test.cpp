// The tree's structure (common/tree.h): layers, common ancestors, and the check that a tree
// fits its mesh.
#include "common/tree.h"

#include <gtest/gtest.h>

#include "common/sha256.h"
#include "data/analytic_meshes.h"
#include "octahedron_trees.h"

namespace vobb {
namespace {

// An unbalanced tree of depth 3 over the octahedron's 8 faces:
//   0 ─┬─ 1 ─┬─ 3 ─┬─ 5 {0}
//      │     │     └─ 6 {1}
//      │     └─ 4 {2, 3}
//      └─ 2 {4, 5, 6, 7}
Tree unbalanced_tree() {
  return test::octahedron_tree(3, {{-1, 0, {1, 2}, {0, 1, 2, 3, 4, 5, 6, 7}},
                                   {0, 1, {3, 4}, {0, 1, 2, 3}},
                                   {0, 1, {}, {4, 5, 6, 7}},
                                   {1, 2, {5, 6}, {0, 1}},
                                   {1, 2, {}, {2, 3}},
                                   {3, 3, {}, {0}},
                                   {3, 3, {}, {1}}});
}

TEST(Tree, TheUnbalancedTreeIsValid) {
  const Status s = validate_tree(unbalanced_tree(), "t.json");
  EXPECT_TRUE(s) << s.message();
}

// Each node but the root is listed once, by its parent; a structure where that fails is
// refused with the node named.
TEST(Tree, EachChildIsListedOnceByItsParent) {
  Tree twice = unbalanced_tree();
  twice.nodes[3].children = {5, 5};
  Status s = validate_tree(twice, "t.json");
  ASSERT_FALSE(s);
  EXPECT_EQ(s.message(), "t.json: node 5: listed as a child more than once");
  Tree unlisted = unbalanced_tree();
  unlisted.nodes[3].children = {5};  // node 6 still names node 3 as its parent
  s = validate_tree(unlisted, "t.json");
  ASSERT_FALSE(s);
  EXPECT_EQ(s.message(), "t.json: node 6: parent does not list it as a child");
}

// Layer i: the nodes at level i and every leaf above it (DESIGN §1), ascending.
TEST(Tree, LayersFollowTheDesignDefinition) {
  const Tree t = unbalanced_tree();
  EXPECT_EQ(layer(t, 0), std::vector<int32_t>({0}));
  EXPECT_EQ(layer(t, 1), std::vector<int32_t>({1, 2}));
  EXPECT_EQ(layer(t, 2), std::vector<int32_t>({2, 3, 4}));
  EXPECT_EQ(layer(t, 3), std::vector<int32_t>({2, 4, 5, 6}));
}

TEST(Tree, CommonAncestorOfAnyTwoNodes) {
  const Tree t = unbalanced_tree();
  const struct {
    int32_t a, b, ancestor;
  } cases[] = {
      {5, 5, 5},  // a node is its own
      {5, 6, 3},  // siblings
      {5, 4, 1},  // cousins at different levels
      {5, 2, 0},  // across the root, a leaf two levels up
      {3, 5, 3},  // an ancestor and its descendant
      {0, 6, 0},  // the root and a leaf
      {4, 6, 1},
  };
  for (const auto& c : cases) {
    EXPECT_EQ(common_ancestor(t, c.a, c.b), c.ancestor) << c.a << ", " << c.b;
    EXPECT_EQ(common_ancestor(t, c.b, c.a), c.ancestor) << c.b << ", " << c.a;
  }
}

// A tree fits the mesh it indexes: its triangle count, and its SHA-256 where it records one.
TEST(Tree, FitsOnlyTheMeshItIndexes) {
  const Mesh octahedron = analytic::octahedron().mesh;
  Tree t = unbalanced_tree();
  t.mesh_sha256 = mesh_sha256(octahedron);
  EXPECT_TRUE(check_tree_fits(octahedron, t, "t.json"));
  // Another mesh of the same triangle count: the recorded SHA-256 tells them apart.
  Mesh moved = octahedron;
  for (Vec3& v : moved.vertices) v += Vec3(1, 0, 0);
  Status s = check_tree_fits(moved, t, "t.json");
  EXPECT_EQ(s.message(), "t.json: built for another mesh (sha256 differs)");
  // A caller's hash of the mesh is used as given: the moved mesh's own hash is refused, the
  // octahedron's is accepted whatever mesh comes with it.
  EXPECT_FALSE(check_tree_fits(octahedron, t, "t.json", mesh_sha256(moved)));
  EXPECT_TRUE(check_tree_fits(moved, t, "t.json", t.mesh_sha256));
  // Without a recorded SHA-256 the mesh is taken as the tree's where its count agrees.
  t.mesh_sha256.clear();
  EXPECT_TRUE(check_tree_fits(moved, t, "t.json"));
  // Another count is refused, recorded SHA-256 or not.
  const Mesh cube = analytic::cube().mesh;  // 12 triangles
  s = check_tree_fits(cube, t, "t.json");
  EXPECT_EQ(s.message(), "t.json: tree indexes 8 triangles but the mesh has 12");
  // A broken structure is refused before the mesh is looked at.
  t.nodes[2].faces = {4, 5, 6};
  s = check_tree_fits(octahedron, t, "t.json");
  EXPECT_FALSE(s);
  EXPECT_EQ(s.message().rfind("t.json: ", 0), 0u) << s.message();
}

}  // namespace
}  // namespace vobb
