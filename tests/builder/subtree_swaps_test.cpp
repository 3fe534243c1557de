// Subtree swaps on a finished tree (builder/subtree_swaps.h): the tree stays valid and
// conservative, only the swapped chains change, the exact e drops with the estimated one, and
// the result is the same on any number of threads.
#include "builder/subtree_swaps.h"

#include <gtest/gtest.h>
#include <tbb/task_arena.h>

#include <atomic>
#include <string>

#include "builder/exact_drop.h"
#include "builder/obbtree_builder.h"
#include "common/tree_io.h"
#include "data/analytic_meshes.h"
#include "fast/poly_overlap.h"
#include "fast/poly_solver.h"
#include "test_common.h"

namespace vobb {
namespace {

struct Solvers {
  explicit Solvers(const Mesh& mesh) : obv(mesh), shares(mesh) {}
  SubtreeSwapOptions options() const {
    SubtreeSwapOptions o;
    o.estimate = [this](const std::vector<Obb>& b) { return obv.estimate(b); };
    o.share = [this](const std::vector<ShareQuery>& q) { return shares.estimate(q); };
    return o;
  }
  PolyObvSolver obv;
  PolyOverlapSolver shares;
};

// The OBB-Tree baseline of the torus at depth 4: a tree no search has touched, with pairs
// under distant parents that gain by trading places.
Tree baseline_torus(const Mesh& mesh) {
  ObbTreeOptions b;
  b.depth = 4;
  return build_obbtree(mesh, b);
}

// With the polyhedral solver (exact to round-off) every round kept lowers the estimated e by
// 1e-4 of it or more, far above the solvers' round-off and fit_obb's padding (both below 1e-12
// of e): the exact e must drop too, decided as rationals.
TEST(SubtreeSwaps, LowerTheExactErrorAndChangeOnlyTheSwappedChains) {
  const Mesh mesh = analytic::polygonal_torus().mesh;
  const Solvers solvers(mesh);
  const Tree before = baseline_torus(mesh);
  Tree after = before;
  SubtreeSwapReport r;
  swap_subtrees(mesh, solvers.options(), &after, &r);
  ASSERT_GT(r.swaps, 0u);
  EXPECT_FALSE(r.stopped);
  EXPECT_LE(r.e_after, r.e_before * (1 - 1e-4));
  ASSERT_TRUE(validate_tree(after, "swapped"));
  EXPECT_TRUE(check_conservative(mesh, after).ok());
  ASSERT_EQ(after.nodes.size(), before.nodes.size());
  size_t moved = 0, changed = 0;
  for (size_t i = 0; i < after.nodes.size(); ++i) {
    const TreeNode &a = after.nodes[i], &b = before.nodes[i];
    EXPECT_EQ(a.level, b.level);
    moved += a.parent != b.parent;
    if (a.faces == b.faces) {
      // Untouched nodes keep their boxes bit for bit.
      EXPECT_EQ(a.box.center, b.box.center) << "node " << i;
      EXPECT_EQ(a.box.half, b.box.half) << "node " << i;
      EXPECT_EQ(a.box.axes, b.box.axes) << "node " << i;
    } else {
      ++changed;
      EXPECT_GT(a.level, 0);  // the root holds every face
    }
  }
  // Each swap moves two nodes, and changes two nodes a level between them and their ancestor.
  EXPECT_GE(moved, 2u);
  EXPECT_GE(changed, 2u);
  test::expect_exact_e_below(mesh, after, before);
}

TEST(SubtreeSwaps, TheSameTreeOnAnyNumberOfThreads) {
  const Mesh mesh = analytic::polygonal_torus().mesh;
  const Solvers solvers(mesh);
  std::string one;
  tbb::task_arena(1).execute([&] {
    Tree t = baseline_torus(mesh);
    swap_subtrees(mesh, solvers.options(), &t);
    one = tree_to_json(t);
  });
  for (int threads : {2, 4}) {
    std::string got;
    tbb::task_arena(threads).execute([&] {
      Tree t = baseline_torus(mesh);
      swap_subtrees(mesh, solvers.options(), &t);
      got = tree_to_json(t);
    });
    EXPECT_EQ(got, one) << threads << " threads";
  }
  EXPECT_NE(one, tree_to_json(baseline_torus(mesh)));  // it did change the tree
}

// Out of time from the start: nothing is scored and the tree is as it was, byte for byte.
TEST(SubtreeSwaps, OutOfTimeKeepsTheTree) {
  const Mesh mesh = analytic::polygonal_torus().mesh;
  const Solvers solvers(mesh);
  SubtreeSwapOptions o = solvers.options();
  o.out_of_time = [] { return true; };
  Tree t = baseline_torus(mesh);
  SubtreeSwapReport r;
  swap_subtrees(mesh, o, &t, &r);
  EXPECT_TRUE(r.stopped);
  EXPECT_EQ(r.swaps, 0u);
  EXPECT_EQ(tree_to_json(t), tree_to_json(baseline_torus(mesh)));
}

// Out of time once the first round's scoring has begun: that round is dropped, the tree is as
// it was.
TEST(SubtreeSwaps, OutOfTimeWhileScoringDropsTheRound) {
  const Mesh mesh = analytic::polygonal_torus().mesh;
  const Solvers solvers(mesh);
  SubtreeSwapOptions o = solvers.options();
  std::atomic<int> asked{0};
  o.out_of_time = [&asked] { return ++asked > 1; };
  Tree t = baseline_torus(mesh);
  SubtreeSwapReport r;
  swap_subtrees(mesh, o, &t, &r);
  EXPECT_TRUE(r.stopped);
  EXPECT_GT(asked.load(), 1);
  EXPECT_EQ(r.swaps, 0u);
  EXPECT_EQ(r.e_after, r.e_before);
  EXPECT_EQ(tree_to_json(t), tree_to_json(baseline_torus(mesh)));
}

// Only pairs whose common ancestor is `gap` levels up or more are candidates: with the gap at
// the depth, only pairs of the deepest level under different children of the root are. In one
// round no node moves twice, so each that moves is of that level and changes its level-1
// ancestor.
TEST(SubtreeSwaps, TheGapBoundsTheCandidates) {
  const Mesh mesh = analytic::polygonal_torus().mesh;
  const Solvers solvers(mesh);
  SubtreeSwapOptions o = solvers.options();
  o.gap = 4;
  o.first_level = 1;
  o.rounds = o.passes = 1;
  const Tree b = baseline_torus(mesh);
  Tree t = b;
  SubtreeSwapReport r;
  swap_subtrees(mesh, o, &t, &r);
  EXPECT_GT(r.candidates, 0u);
  EXPECT_GT(r.swaps, 0u);
  ASSERT_TRUE(validate_tree(t, "swapped"));
  auto top = [](const Tree& tree, int32_t i) {
    while (tree.nodes[i].level > 1) i = tree.nodes[i].parent;
    return i;
  };
  size_t moved = 0;
  for (size_t i = 0; i < t.nodes.size(); ++i)
    if (t.nodes[i].parent != b.nodes[i].parent) {
      ++moved;
      EXPECT_EQ(t.nodes[i].level, 4);
      EXPECT_NE(top(t, i), top(b, i));
    }
  EXPECT_EQ(moved, 2 * r.swaps);
  o.first_level = 5;  // deeper than the tree: no level to search
  Tree same = b;
  swap_subtrees(mesh, o, &same, &r);
  EXPECT_EQ(r.candidates, 0u);
  EXPECT_EQ(tree_to_json(same), tree_to_json(b));
}

}  // namespace
}  // namespace vobb
