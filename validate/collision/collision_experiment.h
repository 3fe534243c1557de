// The collision experiment of the paper's §5: colliders against a model, counting
// the collider–box tests that each tree costs.
//
// Scene (dynamic mode): the model spins about the vertical axis through its root box's centre,
// and `colliders` spheres and boxes of mixed sizes drop from random points above it under
// gravity, for `seconds` of simulated time (ODE, step `step`). A collider that falls past the
// model is dropped again from above. The model is a custom ODE geom: for each collider whose
// bounding box meets the model's, its collider function runs one *query* — brute force over
// all faces and every tree's traversal on the same pose — and returns contacts from the faces
// found. Every tree sees the same query stream (one simulation serves all of them).
// Static mode: `colliders` poses sampled on and near the surface (area-weighted points, offset
// along the normal), no dynamics; exactly repeatable.
// Per query, each tree's set of touching faces must equal brute force's; FCL replays the same
// pose on FCL's own OBB tree and on each of our trees (fcl_referee.h).
// Units: lengths in mesh units. The scene is defined relative to the model's bounding radius R
// (sizes, drop heights, gravity 2 R/s^2, the bounce threshold; masses do not grow with R^3), so
// the model's units do not change it: scaling mesh and trees by a power of two gives the same
// counts exactly.
// Deterministic: same inputs and seed, same counts (wall times aside).
#pragma once

#include <cstdint>
#include <functional>
#include <string>
#include <vector>

#include "collision/tree_traversal.h"
#include "common/mesh.h"
#include "common/status.h"
#include "common/tree.h"

namespace vobb::collision {

// The most colliders of the dynamic scene (bodies alive at once); static poses, made one at a
// time, are not limited here.
constexpr int kMaxDynamicColliders = 1000000;

struct ExperimentOptions {
  bool dynamic = true;    // false: static poses on and near the surface
  int colliders = 1000;   // bodies (dynamic) or poses (static); >= 1
  double seconds = 10.0;  // simulated time (dynamic)
  double step = 0.01;     // ODE time step, s
  uint64_t seed = 1;
  // Multiplies every collider's size: spheres of radius 0.02–0.08 R and boxes of half sides
  // 0.015–0.06 R at 1 (R: half the diagonal of the first tree's root box). Finite, in
  // [0.01, 10]. The random draws (drop points, shapes, orientations, relative sizes) do not
  // depend on it; in the dynamic scene, which body a later re-drop goes to does.
  double collider_scale = 1.0;
  bool fcl = true;  // replay through FCL
  // Called, and must not return, when ODE stops on an internal error (its assertions fire at
  // some scales of the model: its tolerances are absolute). The message is one line. Unset:
  // the message goes to stderr and the process aborts, as ODE itself would.
  std::function<void(const std::string&)> on_physics_failure;
  // For tests of the check itself: called with the tree's index, the query's number (from 1)
  // and that tree's answer (its touching faces, sorted) before the answer is compared with
  // brute force; it may change the answer. Empty: answers are compared as found.
  std::function<void(size_t tree, uint64_t query, std::vector<int32_t>* faces)> tamper_answer;
  // Called with every query's collider (model frame), in query order, before it is tested; may
  // be empty. For recording the scene's query stream (query_objective.h).
  std::function<void(const Collider&)> on_query;
};

struct FclCounts {
  bool available = false;  // false when the tree could not be loaded into FCL (see note)
  std::string note;
  uint64_t bv_tests = 0, leaf_tests = 0, tree_node_bv_tests = 0;
  uint64_t answer_disagreements = 0;  // queries where FCL's yes/no differs from brute force
  uint64_t face_disagreements = 0;    // queries where FCL's set of touching faces differs
};

struct TreeResult {
  std::string name;  // as given (the file)
  std::string method;
  int depth = 0, arity = 0;
  size_t nodes = 0;
  QueryCounts counts;
  double narrow_phase_seconds = 0;  // wall time of this tree's traversals
  uint64_t disagreements = 0;       // queries whose faces differ from brute force
  FclCounts fcl;
};

struct ExperimentReport {
  bool dynamic = true;
  uint64_t queries = 0;
  uint64_t touching_queries = 0;  // queries with at least one touching face
  double simulated_seconds = 0;
  uint64_t ode_contacts = 0;  // contact joints created (dynamic)
  bool brute_force_agrees = true;
  std::string first_disagreement;  // one line, empty when all agree
  double brute_force_seconds = 0;
  uint64_t exact_fallbacks = 0;  // box–triangle tests decided by rationals
  std::vector<TreeResult> trees;
  FclCounts fcl_own;  // FCL's own OBB tree
};

struct NamedTree {
  std::string name;
  const Tree* tree = nullptr;
};

// Checks each tree against the mesh (structure, face count, conservative boxes) and the options
// (dynamic: 0 < step <= 1 s, at most 10^9 steps), and runs the experiment. A failed Status
// names the tree or the option; a run in which no collider reached the model fails too (too
// short to test anything). A disagreement with brute force is not a failed Status but
// `report->brute_force_agrees == false`.
Status run_collision_experiment(const Mesh& mesh, const std::vector<NamedTree>& trees,
                                const ExperimentOptions& options, ExperimentReport* report);

// Tests per unit (per simulated second, or per query in static mode) and the reduction in %
// of tree i relative to tree 0 (positive: fewer tests).
double reduction_pct(double first, double other);

}  // namespace vobb::collision
