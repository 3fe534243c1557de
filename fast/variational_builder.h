// The variational hierarchical OBB builder (paper §4.2, DESIGN §5).
//
// Top-down, level by level: each node's faces are split among `arity` children by Lloyd
// iterations that minimise the sum of the children's OBV, measured by an OBV estimator (the
// cubemap estimator, GL or CPU twin):
//  - start: the baseline's split (obbtree_builder.h), so the search starts where OBB-Tree ends;
//  - partition (flooding): seeds are the faces nearest the boxes' centres; a priority queue
//    grows the regions over face adjacency in order of distance to the box centres; a face that
//    neighbours several regions goes to the one whose box grows least in OBV (dOBV; a face that
//    does not enlarge a box costs nothing and needs no estimate);
//  - box update: per group, the orientation minimising the estimated OBV of the group's tight
//    box: the best of the current axes, the covariance axes and seeded random orientations (32
//    for levels 0-3, 4 below), then a pattern search over rotations about the box axes (step
//    0.2 rad halving to 0.0125 rad). The issue speaks of 6 parameters, centre and orientation;
//    but for fixed axes the tight fit of the faces is contained in every other box that holds
//    them, and OBV grows with the box, so the optimal centre and extents follow from the axes:
//    only the 3 rotation parameters are searched, and the centre is the tight fit's;
//  - adjustment (off by default, `adjust`): for children at levels 1-4, Lloyd iterations are
//    also started from other planar splits of the node (each covariance axis, cut into equal
//    counts and equal extents; the two best by a cheap screen), and the lowest sum is kept.
//    It is off because, measured exactly on dino at depth 8 (docs/BENCHMARKS.md), it raised e:
//    the sum of OBV it lowers counts overlaps twice, and the splits it finds overlap more, so
//    their OMV, and their subtrees', is worse. The re-seeding of the least important box
//    (moved to the farthest face of the largest box) was worse still (e +19 %), and is gone;
//  - the best state seen is kept, so a node's children never have a larger estimated sum of
//    OBV than the baseline split with optimised boxes.
// Then bottom-up merging sweeps (multigrid-like, paper §4.2): for each level l from the deepest
// parents up to 1, the children of each level-l node are the units, and the units under one
// level-(l-1) node are re-grouped among its children by swapping (or moving) units between
// them, with the changed parents' orientations searched again. A move is kept only when the
// estimated sum of OBV of the changed parents drops by 0.1 % or more, i.e. when the estimated
// e drops: only layer l changes, and it weighs ω(l) = D - l + 1 in e. Each move's candidates are
// screened with fixed orientations; the two best get the full search. Sweeps repeat while the
// estimated e drops by 0.1 % or more, at most `max_sweeps` times.
// What a search already knows is not worked out again (`reuse_known`): a regrouping is not run
// while its inputs are those with which it last found no move, and a box measured before in
// the same search (a node's split, the root's, a regrouping) takes the value it got. Both rest
// on the estimator being a function of the box alone (ObvEstimate), and change no tree.
//
// Objective (`objective`). kObv, the paper's: each set of boxes is scored by the sum of their
// estimated OBV, which counts a region that two boxes share twice. kOmv scores them by their
// estimated OMV, the measure the certificate charges: the sum of OBV less, for each box in
// order, what it shares outside the solid with the boxes before it (the `share` estimate),
// which is the union's outer volume exactly, with no inclusion-exclusion term dropped. Where a
// set's boxes change while other boxes of the layer stay (the context), they are scored by what
// they add to the layer's OMV: their shares are taken against the context too. It applies
// everywhere the search compares: each group's orientation (the box's OBV less its share with
// the other groups' boxes and the context), a node's Lloyd states and adjusted splits, and the
// merging sweeps, where a regrouped pair's context is its layer's other boxes that may meet it,
// cousins included, as they stood when the level's regroupings began. The flooding partition
// still grows regions by dOBV. Why the score is the union's and not the pairwise truncation
// (a lower bound on OMV): docs/derivations.md, "Shared outer volume".
// Collider margin (off by default, `margin` > 0): every box the builder measures is first
// grown by `margin` on each side, so the search minimises the sum of OBV(O ⊕ cube(margin))
// instead of OBV(O). A collider of radius r whose centre lies outside the solid meets O only
// from inside O ⊕ B(r) ⊆ O ⊕ cube(r), so with margin ≈ r the objective measures the free space
// from which colliders reach each box, and with it the collider-box tests a box causes; the
// paper's OBV (margin 0) leaves out the shell around the box that grows with its surface area.
// It is an extension beyond the paper, measured on the collision experiment in
// docs/BENCHMARKS.md; the tree's boxes stay the tight fits of their faces.
// Boxes are written through fit_obb (exactly conservative). Deterministic: ties go by face id,
// box index and node id, and the orientation starts are seeded per group; the same mesh,
// options and estimator values give the same tree, whether the nodes of a level are searched
// one after another on the calling thread or at once (concurrent_estimates), and whether the
// estimator evaluates a batch in parallel, as the CPU twin does (its values do not depend on
// the thread count). The build state after each level and each sweep can be saved
// (checkpoint) and a build resumed from it gives the same tree as an uninterrupted one.
// A time budget ends the search early. It is asked before every call to the estimator: under a
// budget a batch is estimated in chunks of about budget_check_seconds at the pace measured at
// the current level (one box per thread until that pace is known), so the search ends within
// the call under way, not after a node's whole search. The node being searched (each of them,
// with concurrent_estimates) keeps the best complete state found (its start if none), the
// nodes not yet split get the baseline split, and no further sweep starts; a regrouping move
// whose evaluation it cuts short is not applied (one evaluated in full before it may be). A
// state saved after the budget was spent keeps it spent when resumed. A budget that is not
// reached changes nothing: the chunks' estimates are the whole batch's, so the tree is the
// unbudgeted one.
#pragma once

#include <array>
#include <cstdint>
#include <functional>
#include <string>
#include <utility>
#include <vector>

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
  int level = 0;        // level of the children being made, or of the parents being merged
  int sweep = 0;        // 0 in the top-down pass, then the merging sweep (1, 2, ...)
  size_t node = 0;      // nodes done at that level
  size_t nodes = 0;     // nodes to do at that level
  int iteration = 0;    // Lloyd iteration within the node
  double sum_obv = 0;   // the objective of the finished children at this level (estimated sum of
                        // OBV, less their pairs' overlap under kOmv; of the boxes grown by the
                        // margin, when there is one)
  size_t estimates = 0; // boxes estimated so far
  double done = 0;      // rough fraction of the top-down pass done, for a remaining-time guess
  double sweep_done = 0;  // in a merging sweep: rough fraction of it done (each level re-groups
                          // about every face once, so levels weigh alike; within a level, by faces)
};

// The state of a build between two steps: what a checkpoint holds.
struct VariationalState {
  int split_levels = 0;   // levels made by the top-down pass (0: only the root)
  int sweeps = 0;         // merging sweeps done
  bool sweeping_done = false;
  bool budget_spent = false;
  std::vector<TreeNode> nodes;              // boxes unset; faces sorted ascending
  std::vector<std::array<Vec3, 3>> axes;    // per node: the searched orientation
};

struct VariationalOptions {
  int depth = 8;             // >= 0
  int arity = 2;             // >= 2
  int lloyd_iterations = 4;  // most partition + update rounds per node (and per adjustment)
  bool optimise_axes = true; // ablation: false keeps the groups' covariance axes
  bool adjust = false;       // the adjustment step (see above: measured to hurt, so off)
  bool merge = true;         // ablation: the bottom-up merging sweeps
  int max_sweeps = 3;
  // What the search already knows is not worked out again: a regrouping whose inputs are those
  // with which it last found no move is not run (VariationalReport::regroups_skipped), and a
  // box measured before in the same search takes the value it got (VariationalReport::reused).
  // false works everything out, to check that the tree is the same (test
  // ReusingWhatIsKnownChangesNothing), or for an estimator that is not a function of the box
  // alone (see ObvEstimate).
  bool reuse_known = true;
  uint64_t seed = 1;         // the random starts of the orientation search
  double margin = 0;         // collider margin, world units, finite and >= 0 (see above)
  Objective objective = Objective::kObv;
  ShareEstimate share;       // required for kOmv, unused for kObv
  // Whether `estimate` may be called from several threads at once (the CPU twin and the GL
  // estimator may: GL draws the calls waiting at once together). Then the nodes of a level are
  // split, and the nodes of a sweep's level regrouped, in parallel (TBB, in the caller's arena); the
  // tree is the same either way. Then out_of_time and progress are called from TBB's threads
  // too, and the builder's own arithmetic runs there: like the CPU twin's, it needs the
  // default floating-point environment (cpu_estimator.h).
  bool concurrent_estimates = false;
  // Called often, from any thread the search runs on but never from two at once (under a
  // lock: it must not wait for TBB work, which could be another node's search on its thread);
  // may be empty. With concurrent searches, `iteration` is that of the node that reported.
  std::function<void(const VariationalProgress&)> progress;
  std::function<bool()> out_of_time;  // may be empty: no budget
  // Under a budget, about how many seconds of estimates go in one estimator call (> 0): the
  // budget is asked this often at the least. 0.25 s keeps a batch of 33 boxes one call at the
  // usual m even on llvmpipe's GL (about 5 ms a box), where chunks of 50 ms cost 15 %.
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
  size_t reused = 0;          // boxes a search measured again, given the value it had (not estimated)
  size_t overlaps = 0;        // shares estimated (kOmv)
  // Regroupings of a sweep not run: their inputs were those with which they last found no
  // move (see build_variational), so they would find none again.
  size_t regroups_skipped = 0;
};

// Precondition: the mesh is a solid. Fills every field of the tree but mesh_sha256. `resume`,
// when given, is a state saved by the checkpoint callback of a build with the same mesh,
// options and estimator; the build goes on from it.
Tree build_variational(const Mesh& mesh, const VariationalOptions& options, const ObvEstimate& estimate,
                       const VariationalState* resume = nullptr, VariationalReport* report = nullptr);

// The tight box of the faces' vertices along the given (orthonormal) axes, in double, without
// the conservative padding of fit_obb: what the optimiser measures.
Obb tight_box(const Mesh& mesh, const std::vector<int32_t>& faces, const std::array<Vec3, 3>& axes);

// Checkpoint files: JSON with a `fingerprint` naming everything the build depends on (the
// caller's: mesh hash, options, estimator and m) and a SHA-256 of the rest. Doubles round-trip
// bit for bit. Writes are atomic (temp file + rename). Reading checks the checksum (a state
// without one, from before checksums, is read unchecked), the fingerprint and the state's
// structure.
Status write_variational_state(const VariationalState& state, const std::string& fingerprint, const std::string& path);
// Not found: ok with *found = false. Wrong fingerprint or a damaged file: an error. The state
// must fit the build it resumes: faces below mesh_faces, at most `arity` children per node and
// no node below level `depth` (a state edited by hand could otherwise pass the fingerprint).
Status read_variational_state(const std::string& path, const std::string& fingerprint, size_t mesh_faces,
                              int arity, int depth, VariationalState* state, bool* found);

}  // namespace vobb
