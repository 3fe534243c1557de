// Swaps of whole subtrees across distant parents, on a finished tree: the step the merging
// sweeps cannot take (they regroup only under a common grandparent and turn only the parents).
// Derivation: docs/derivations.md, "Swaps of subtrees across distant parents".
//
// Two nodes u, v of one level k, whose boxes may meet (boxes_apart) and whose lowest common
// ancestor c is at level k - gap or above, trade places. Every node strictly between them and c
// (the two chains) gives up one's faces for the other's and is turned: the smaller of two
// descend_tight_volume boxes from its old axes, first turns 0.02 and 0.2 rad. A swap's gain is the
// change in the estimated e over the layers it changes: per layer, ω(l) times the two chain boxes'
// OBV less what they share with the layer's other boxes and with each other, which is that layer's
// change in OMV exactly (the union's outer volume, nothing dropped; docs/derivations.md, "Shared
// outer volume").
//
// Each round scores every candidate pair of a level at once and applies the best ones that
// touch no node an applied swap touched, each lowering the estimated e by `min_drop` of it or
// more; levels first_level..depth in turn, `passes` times, up to `rounds` rounds a level while
// a round applies a swap. A pair's score is kept for later rounds until a swap moves or changes
// a node it read, or changes a box of its chains' layers that meets a box whose share it asked:
// the estimators are functions of their queries, so a kept score is the score afresh.
//
// Contract:
// - The tree stays valid (validate_tree) with the same ids, levels and root; only the nodes of
//   applied swaps' chains change their faces, and they get fit_obb boxes (exactly conservative).
//   Every other node keeps its box bit for bit, and the two parents' children lists stay
//   sorted.
// - The estimated e falls with every round kept. A round whose swaps together gain less than
//   its best swap alone is replaced by that swap alone, and a round that leaves e no lower is
//   undone and ends its level.
// - Deterministic: the same tree, options and estimator values give the same tree on any
//   number of threads.
// - With out_of_time, asked before each round, between rows of the candidates' list, and
//   before each pair (and each chain pair's value before a swap) is scored afresh, it stops
//   within the scoring under way and keeps the rounds finished.
#pragma once

#include <cstddef>
#include <functional>
#include <vector>

#include "builder/variational_builder.h"
#include "common/mesh.h"
#include "common/tree.h"

namespace vobb {

struct ScoredPair {
  int32_t u = 0, v = 0;  // node ids, u < v
  double gain = 0;       // the change in the estimated e were they swapped (negative lowers it)
};

struct SubtreeSwapOptions {
  int first_level = 2;                // >= 1; beyond the tree's depth there is nothing to do
  int gap = 2;                        // the common ancestor at least this many levels up; >= 2
  int rounds = 4;                     // per level and pass; >= 0
  int passes = 2;                     // over the levels; >= 0
  double min_drop = 1e-4;             // of the estimated e, per swap; >= 0
  bool reuse_scores = true;           // false: every pair scored afresh each round (same tree)
  ObvEstimate estimate;               // required; called from several threads at once
  ShareEstimate share;                // required; likewise
  std::function<bool()> out_of_time;  // may be empty; called from several threads at once
  // May be empty; called once a round, on the calling thread, with the round's level and every
  // candidate pair's score, best first, before any swap is applied.
  std::function<void(int, const std::vector<ScoredPair>&)> scored;
};

struct SubtreeSwapReport {
  size_t candidates = 0;             // pairs scored, over all rounds
  size_t reused = 0;                 // of those, scores kept from an earlier round
  size_t rescored = 0;               // of those, scored again before a swap could apply them
  size_t swaps = 0;                  // applied
  size_t rounds = 0;                 // kept (each applied swaps and lowered e)
  size_t reverted = 0;               // rounds replaced by their best swap alone
  size_t undone = 0;                 // rounds undone: e no lower, as the estimators measure it
  double e_before = 0, e_after = 0;  // estimated
  bool stopped = false;              // out_of_time ended it
};

// Preconditions: the tree fits the mesh (check_tree_fits), its boxes have orthonormal axes, and
// the options are in range with estimate and share set (asserted).
void swap_subtrees(const Mesh& mesh, const SubtreeSwapOptions& options, Tree* tree,
                   SubtreeSwapReport* report = nullptr);

}  // namespace vobb
