// Subtree swaps on a finished tree (builder/subtree_swaps.h): the tree stays valid and
// conservative, only the swapped chains change, the exact e drops with the estimated one, and
// the result is the same on any number of threads.
#include "builder/subtree_swaps.h"

#include <gtest/gtest.h>
#include <tbb/info.h>
#include <tbb/task_arena.h>

#include <atomic>
#include <cstdint>
#include <string>
#include <string_view>
#include <tuple>

#include "arena_threads.h"
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
// min_drop (1e-4) of it or more, far above the solvers' round-off and fit_obb's padding (both
// below 1e-12 of e): the exact e must drop too, decided as rationals. A node's faces change only
// where a swap's chain passes through it (the tree's faces follow from its leaves); every node
// whose faces are those it began with keeps its box bit for bit. (A chain node whose faces came
// back to their first set over two passes would be boxed again, so would fail this check though
// the contract allows it; on this tree none does.)
TEST(SubtreeSwaps, LowerTheExactErrorAndChangeOnlyTheSwappedChains) {
  const Mesh mesh = analytic::polygonal_torus().mesh;
  const Solvers solvers(mesh);
  const Tree before = baseline_torus(mesh);
  Tree after = before;
  SubtreeSwapReport r;
  const SubtreeSwapOptions o = solvers.options();
  swap_subtrees(mesh, o, &after, &r);
  ASSERT_GT(r.swaps, 0u);
  EXPECT_FALSE(r.stopped);
  EXPECT_LE(r.e_after, r.e_before * (1 - o.min_drop));
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
    // Where a second CPU is there, a worker must have joined: the swaps offered work in parallel.
    test::expect_on_threads(
        threads,
        [&] {
          Tree t = baseline_torus(mesh);
          swap_subtrees(mesh, solvers.options(), &t);
          EXPECT_EQ(tree_to_json(t), one) << threads << " threads";
        },
        "the swaps");
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

// A share estimator that errs: the polyhedral share times 1 + a·u, u in [-1, 1] drawn from a
// hash of the query's values. It is a function of the query alone, as ShareEstimate requires, but
// no longer additive: a box's share with a layer, asked as the scoring asks it (against all the
// layer's other boxes) and as e asks it (against those before it), no longer agree. That is the
// disagreement the step's two guards exist for.
struct NoisyShares {
  NoisyShares(const Mesh& mesh, double amplitude) : solver(mesh), a(amplitude) {}
  static uint64_t hash(const ShareQuery& q) {
    // FNV-1a over the values rounded to float, so that a box rebuilt with round-off (fit_obb
    // orthonormalizes the axes again) draws the same noise.
    uint64_t h = 1469598103934665603ull;
    auto eat = [&h](const Obb& b) {
      for (const Vec3* v : {&b.center, &b.half, &b.axes[0], &b.axes[1], &b.axes[2]})
        for (int k = 0; k < 3; ++k) {
          const float f = static_cast<float>((*v)[k]);
          for (const unsigned char c : std::string_view(reinterpret_cast<const char*>(&f), 4))
            h = (h ^ c) * 1099511628211ull;
        }
    };
    eat(q.box);
    for (const Obb& b : q.earlier) eat(b);
    return h;
  }
  std::vector<double> operator()(const std::vector<ShareQuery>& q) const {
    std::vector<double> s = solver.estimate(q);
    for (size_t i = 0; i < q.size(); ++i) s[i] *= 1 + a * (double(hash(q[i]) >> 11) * 0x1p-52 - 1);
    return s;
  }
  PolyOverlapSolver solver;
  double a;
};

// The estimated e of a tree as the step measures it: per layer, in id order, the tight boxes'
// OBV less each one's share with the boxes before it that it may meet, times the layer's weight.
double estimated_e(const Mesh& mesh, const Tree& t, const SubtreeSwapOptions& o) {
  double e = 0;
  for (int l = 0; l <= t.depth; ++l) {
    std::vector<Obb> boxes;
    for (int32_t i : layer(t, l))
      boxes.push_back(tight_box(mesh, t.nodes[i].faces, t.nodes[i].box.axes));
    const std::vector<double> obv = o.estimate(boxes);
    std::vector<ShareQuery> q;
    double sum = 0;
    for (size_t i = 0; i < boxes.size(); ++i) {
      sum += obv[i];
      std::vector<Obb> before(boxes.begin(), boxes.begin() + i);
      q.push_back({boxes[i], boxes_meeting(boxes[i], before)});
      if (q.back().earlier.empty()) q.pop_back();
    }
    for (double x : q.empty() ? std::vector<double>() : o.share(q)) sum -= x;
    e += layer_weight(t.depth, l) * sum;
  }
  return e;
}

// One round of level 4 (the deepest) alone, with shares that err by up to `noise`, on the
// torus baseline after `rounds` rounds a level in one pass with the same shares.
struct OneMoreRound {
  OneMoreRound(const Mesh& mesh, const Solvers& solvers, double noise, int rounds, int gap)
      : noisy(mesh, noise) {
    o = solvers.options();
    o.share = [this](const std::vector<ShareQuery>& q) { return noisy(q); };
    o.rounds = rounds;
    o.passes = 1;
    start = baseline_torus(mesh);
    swap_subtrees(mesh, o, &start);
    o.gap = gap;
    o.first_level = 4;
    o.rounds = 1;
    tree = start;
    swap_subtrees(mesh, o, &tree, &report);
  }
  OneMoreRound(const OneMoreRound&) = delete;  // o.share points at this one's noisy
  NoisyShares noisy;
  SubtreeSwapOptions o;
  Tree start, tree;
  SubtreeSwapReport report;
};

// Where the scoring errs, a round's swaps can together gain less than the best one alone, and
// the best one alone can leave e no lower. Over a small grid of erring searches, each single
// round must leave exactly the tree its outcome promises:
// - kept (replaced by its best swap or not): the tree whose e the report gives, lower than
//   before; replaced, it holds that one swap (two nodes moved);
// - undone: the tree it began with, byte for byte.
// Each outcome must occur somewhere in the grid, or the guards were not put to the test.
// The report's e_after was measured on the search's own boxes; estimated_e measures the tree's,
// whose changed nodes fit_obb turned again by orthonormalizing their axes, a change of a few
// ulps that moves e by about 1e-15 of it. The tolerance, 1e-9 of e, admits that round-off and
// nothing of the size of a swap (the step applies none that it scores below min_drop of e); the
// byte and move counts check the tree's swaps themselves.
TEST(SubtreeSwaps, EachRoundLeavesTheTreeItsOutcomePromises) {
  const Mesh mesh = analytic::polygonal_torus().mesh;
  const Solvers solvers(mesh);
  size_t kept = 0, replaced = 0, undone = 0, undone_after_replacing = 0;
  for (double noise : {0.05, 0.1, 0.2})
    for (int rounds : {2, 4})
      for (int gap : {2, 4}) {
        const OneMoreRound one(mesh, solvers, noise, rounds, gap);
        const SubtreeSwapReport& r = one.report;
        const std::string at = "noise " + std::to_string(noise) + ", rounds " +
                               std::to_string(rounds) + ", gap " + std::to_string(gap);
        ASSERT_FALSE(r.stopped) << at;
        EXPECT_EQ(estimated_e(mesh, one.start, one.o), r.e_before) << at;
        if (r.undone > 0) {
          ++undone;
          undone_after_replacing += r.reverted;
          EXPECT_EQ(r.undone, 1u) << at;
          EXPECT_EQ(r.swaps, 0u) << at;
          EXPECT_EQ(r.e_after, r.e_before) << at;
          EXPECT_EQ(tree_to_json(one.tree), tree_to_json(one.start)) << at;
        } else if (r.rounds > 0) {
          ++kept;
          ASSERT_TRUE(validate_tree(one.tree, "swapped")) << at;
          EXPECT_TRUE(check_conservative(mesh, one.tree).ok()) << at;
          EXPECT_NEAR(estimated_e(mesh, one.tree, one.o), r.e_after, 1e-9 * r.e_before) << at;
          EXPECT_LT(r.e_after, r.e_before) << at;
          size_t moved = 0;
          for (size_t i = 0; i < one.tree.nodes.size(); ++i)
            moved += one.tree.nodes[i].parent != one.start.nodes[i].parent;
          EXPECT_EQ(moved, 2 * r.swaps) << at;
          if (r.reverted > 0) {
            ++replaced;
            EXPECT_EQ(r.swaps, 1u) << at;
          }
        }
      }
  EXPECT_GT(kept, 0u);
  EXPECT_GT(replaced, 0u);
  EXPECT_GT(undone, 0u);
  EXPECT_GT(undone_after_replacing, 0u);
}

// Scores kept across rounds are the scores afresh: every round's list of scores, to the last bit
// (a kept score that clears the threshold is listed as scored again; the others as kept), and so
// the same tree, as scoring every pair in every round. With the exact shares, and with erring
// ones, whose rounds are also replaced and undone.
TEST(SubtreeSwaps, KeptScoresAreTheScoresAfresh) {
  const Mesh mesh = analytic::polygonal_torus().mesh;
  const Solvers solvers(mesh);
  const NoisyShares noisy(mesh, 0.1);
  for (const bool erring : {false, true}) {
    SubtreeSwapOptions o = solvers.options();
    if (erring) o.share = [&noisy](const std::vector<ShareQuery>& q) { return noisy(q); };
    auto run = [&](bool reuse, Tree* t, SubtreeSwapReport* r) {
      std::vector<std::tuple<int, int32_t, int32_t, double>> log;
      o.reuse_scores = reuse;
      o.scored = [&log](int level, const std::vector<ScoredPair>& list) {
        for (const ScoredPair& p : list) log.emplace_back(level, p.u, p.v, p.gain);
      };
      swap_subtrees(mesh, o, t, r);
      return log;
    };
    Tree kept = baseline_torus(mesh), afresh = kept;
    SubtreeSwapReport rk, ra;
    const auto with = run(true, &kept, &rk);
    const auto without = run(false, &afresh, &ra);
    // Some kept scores stand in the list as kept, not scored again: those the comparison with
    // the fresh scores puts to the test.
    EXPECT_GT(rk.reused, rk.rescored) << erring;
    EXPECT_EQ(ra.reused, 0u) << erring;
    EXPECT_EQ(ra.rescored, 0u) << erring;
    EXPECT_EQ(with.size(), rk.candidates) << erring;
    EXPECT_TRUE(with == without) << erring;
    EXPECT_GT(rk.swaps, 0u) << erring;
    EXPECT_EQ(tree_to_json(kept), tree_to_json(afresh)) << erring;
    if (erring) {
      EXPECT_GT(rk.undone, 0u);
      EXPECT_GT(rk.reverted, 0u);
    }
  }
}

}  // namespace
}  // namespace vobb
