// The variational hierarchical OBB builder (paper §4.2, DESIGN §5): top-down Lloyd iterations
// per node on an estimated objective, then bottom-up merging sweeps across levels. The method,
// its choices and their measurements: docs/derivations.md, "The variational builder".
//
// Contract:
// - The tree is valid, its boxes are fit_obb's (exactly conservative), and every field but
//   mesh_sha256 is filled.
// - Deterministic: the same mesh, options and estimator values give the same tree, serially
//   or with concurrent_estimates, on any number of threads.
// - A build resumed from a state saved by `checkpoint` gives the tree of an uninterrupted one.
// - Under a time budget the search ends within the estimator call under way; the nodes not
//   yet split get the baseline split. A budget that is not reached changes nothing.
// - A node's children never have a larger estimated objective than the baseline split with
//   optimised boxes.
// - Under kOmv with `refit`, the last step turns boxes of the top levels (0-4) with their faces
//   fixed (the partition stays the sweeps'), each turn kept only where it lowers the estimated
//   e: a box's part of it is, over the layers it is in, ω(l) times its OBV less its share with
//   the layer's other boxes as they stand. The checkpoints are the states before it, the same
//   with it or without.
#pragma once

#include <array>
#include <cstdint>
#include <functional>
#include <string>
#include <utility>
#include <vector>

#include "builder/variational_state.h"
#include "common/mesh.h"
#include "common/obb.h"
#include "common/status.h"
#include "common/tree.h"

namespace vobb {

// Estimated OBV of each box, in world volume units. A function of the box alone: the same
// bits give the same value whatever batch they arrive in and whenever they are asked (the CPU
// twin and the GL estimator are; fast/cpu_estimator.h, fast/gl_estimator.h). The builder
// relies on it: it does not ask again for a box its search measured before (reuse_known).
using ObvEstimate = std::function<std::vector<double>(const std::vector<Obb>&)>;

// Per query, the estimated vol((B ∩ (E_0 ∪ ... ∪ E_{k-1})) \ X) of its box B and earlier boxes
// E, in world volume units: what B adds to a layer's overlap term (fast/poly_overlap.h gives
// it). A function of the query alone, like ObvEstimate.
using ShareEstimate = std::function<std::vector<double>(const std::vector<ShareQuery>&)>;

// What the search minimises for a set of boxes (see build_variational).
enum class Objective {
  kObv,  // the sum of their estimated OBV (the paper's)
  kOmv,  // their estimated OMV: that sum less each box's share with the boxes before it
};

struct VariationalProgress {
  int level = 0;          // level of the children being made, or of the parents being merged
  int sweep = 0;          // 0 in the top-down pass, then the merging sweep (1, 2, ...)
  size_t node = 0;        // nodes done at that level
  size_t nodes = 0;       // nodes to do at that level
  int iteration = 0;      // Lloyd iteration within the node
  double sum_obv = 0;     // the objective of the finished children at this level (estimated sum of
                          // OBV, less their pairs' overlap under kOmv; of the boxes grown by the
                          // margin, when there is one)
  size_t estimates = 0;   // boxes estimated so far
  double done = 0;        // rough fraction of the top-down pass done, for a remaining-time guess
  double sweep_done = 0;  // in a merging sweep: rough fraction of it done (each level re-groups
                          // about every face once, so levels weigh alike; within a level, by faces)
};

struct VariationalOptions {
  int depth = 8;              // >= 0
  int arity = 2;              // >= 2
  int lloyd_iterations = 4;   // most partition + update rounds per node (and per adjustment)
  bool optimise_axes = true;  // ablation: false keeps the groups' covariance axes
  bool adjust = false;        // the adjustment step (see above; off: docs/BENCHMARKS.md)
  bool merge = true;          // ablation: the bottom-up merging sweeps
  int max_sweeps = 3;
  // Under kOmv, the last step: each box of the top levels turned, its faces fixed, where that
  // lowers the estimated e (see build_variational). Ablation: false.
  bool refit = true;
  // What the search already knows is not worked out again: a regrouping whose inputs are those
  // with which it last found no move is not run (VariationalReport::regroups_skipped), and a
  // box measured before in the same search, or under kOmv in the same node's regrouping in an
  // earlier sweep, takes the value it got (VariationalReport::reused).
  // false works everything out, to check that the tree is the same (test
  // ReusingWhatIsKnownChangesNothing), or for an estimator that is not a function of the box
  // alone (see ObvEstimate).
  bool reuse_known = true;
  uint64_t seed = 1;  // the random starts of the orientation search
  double margin = 0;  // collider margin, world units, finite and >= 0 (see above)
  Objective objective = Objective::kObv;
  ShareEstimate share;  // required for kOmv, unused for kObv
  // Whether `estimate` may be called from several threads at once (the CPU twin and the GL
  // estimator may: GL draws the calls waiting at once together). Then the nodes of a level are
  // split, and the nodes of a sweep's level regrouped, in parallel (TBB, in the caller's arena);
  // the tree is the same either way. Then out_of_time and progress are called from TBB's threads
  // too, and the builder's own arithmetic runs there: like the CPU twin's, it needs the
  // default floating-point environment (cpu_estimator.h).
  bool concurrent_estimates = false;
  // Called often, from any thread the search runs on but never from two at once (under a
  // lock: it must not wait for TBB work, which could be another node's search on its thread);
  // may be empty. With concurrent searches, `iteration` is that of the node that reported.
  std::function<void(const VariationalProgress&)> progress;
  std::function<bool()> out_of_time;  // may be empty: no budget
  // Under a budget, about how many seconds of estimates go in one estimator call (> 0): the
  // budget is asked this often at the least (the default's measured cost: docs/history/
  // benchmarks-early.md, "The time budget, asked before every estimator call").
  double budget_check_seconds = 0.25;
  // Called after each level and each sweep with the state to save; may be empty.
  std::function<void(const VariationalState&)> checkpoint;
};

struct VariationalReport {
  bool budget_spent = false;  // the time budget ended the search early
  int sweeps = 0;             // merging sweeps done
  size_t merges = 0;          // unit swaps or moves kept by the sweeps
  size_t adjustments = 0;     // adjusted splits kept
  size_t estimates = 0;       // boxes estimated
  size_t reused = 0;  // boxes a search measured again, given the value it had (not estimated)
  size_t reused_earlier = 0;  // of those, boxes that the node's regrouping in an earlier sweep
                              // measured (kOmv)
  size_t overlaps = 0;        // shares estimated (kOmv)
  // Regroupings of a sweep not run: their inputs were those with which they last found no
  // move (see build_variational), so they would find none again.
  size_t regroups_skipped = 0;
  size_t refitted = 0;  // boxes the final refit turned (kOmv)
};

// Precondition: the mesh is a solid. Fills every field of the tree but mesh_sha256. `resume`,
// when given, is a state saved by the checkpoint callback of a build with the same mesh,
// options and estimator; the build goes on from it.
Tree build_variational(const Mesh& mesh, const VariationalOptions& options,
                       const ObvEstimate& estimate, const VariationalState* resume = nullptr,
                       VariationalReport* report = nullptr);

// The tight box of the faces' vertices along the given (orthonormal) axes, in double, without
// the conservative padding of fit_obb: what the optimiser measures.
Obb tight_box(const Mesh& mesh, const std::vector<int32_t>& faces, const std::array<Vec3, 3>& axes);

// Axes, reached from `axes` (orthonormal), along which the faces' tight box is no larger: the
// optimiser's descent on that volume, by turns of +-step about each axis, the same step again
// while one gains, then half of it, while the step is above 1e-4 rad.
std::array<Vec3, 3> descend_tight_volume(const Mesh& mesh, const std::vector<int32_t>& faces,
                                         const std::array<Vec3, 3>& axes, double step);

}  // namespace vobb
