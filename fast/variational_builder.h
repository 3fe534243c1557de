// The variational hierarchical OBB builder (paper §4.2, DESIGN §5), top-down part.
//
// Each node's faces are split among `arity` children by Lloyd iterations that minimise the sum
// of the children's OBV, measured by an OBV estimator (the cubemap estimator, GL or CPU twin):
//  - start: the baseline's split (obbtree_builder.h), so the search starts where OBB-Tree ends;
//  - partition (flooding): seeds are the faces nearest the boxes' centres; a priority queue
//    grows the regions over face adjacency in order of distance to the box centres; a face that
//    neighbours several regions goes to the one whose box grows least in OBV (dOBV; a face that
//    does not enlarge a box costs nothing and needs no estimate);
//  - box update: per group, the orientation minimising the estimated OBV of the group's tight
//    box: the best of the current axes, the covariance axes and seeded random orientations (32
//    for levels 0-3, 4 below), then a pattern search over rotations about the box axes (step
//    0.2 rad halving to 0.0125 rad). The issue speaks of 6 parameters, centre and orientation; but for fixed axes
//    the tight fit of the faces is contained in every other box that holds them, and OBV grows
//    with the box, so the optimal centre and extents follow from the axes: only the 3 rotation
//    parameters are searched, and the centre is the tight fit's;
//  - the iterations stop when the sum of OBV improves by less than 0.1 % or after
//    `lloyd_iterations`; the best state seen is kept, so a node's children never have a larger
//    estimated sum of OBV than the baseline split with optimised boxes.
// Boxes are written through fit_obb (exactly conservative). Deterministic: one thread, ties by
// face id and box index; the same mesh, options and estimator values give the same tree.
// Not yet here (issue 5): the adjustment (re-seeding) step, bottom-up merging across levels,
// checkpoints and the time budget.
#pragma once

#include <cstdint>
#include <functional>
#include <vector>

#include "common/mesh.h"
#include "common/obb.h"
#include "common/tree.h"

namespace vobb {

// Estimated OBV of each box, in world volume units.
using ObvEstimate = std::function<std::vector<double>(const std::vector<Obb>&)>;

struct VariationalProgress {
  int level = 0;        // level of the children being made
  size_t node = 0;      // nodes done at that level
  size_t nodes = 0;     // nodes to split at that level
  int iteration = 0;    // Lloyd iteration within the node
  double sum_obv = 0;   // estimated sum of OBV of the finished children at this level
  size_t estimates = 0; // boxes estimated so far
};

struct VariationalOptions {
  int depth = 8;             // >= 0
  int arity = 2;             // >= 2
  int lloyd_iterations = 4;  // most partition + update rounds per node
  bool optimise_axes = true; // ablation: false keeps the groups' covariance axes
  uint64_t seed = 1;         // the random starts of the orientation search
  std::function<void(const VariationalProgress&)> progress;  // called often; may be empty
};

// Precondition: the mesh is a solid. Fills every field but mesh_sha256.
Tree build_variational(const Mesh& mesh, const VariationalOptions& options, const ObvEstimate& estimate);

// The tight box of the faces' vertices along the given (orthonormal) axes, in double, without
// the conservative padding of fit_obb: what the optimiser measures.
Obb tight_box(const Mesh& mesh, const std::vector<int32_t>& faces, const std::array<Vec3, 3>& axes);

}  // namespace vobb
