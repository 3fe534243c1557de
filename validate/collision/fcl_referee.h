// FCL 0.7 as an outside referee of the collision counts.
//
// A query pose replays through FCL's own mesh–shape traversal (MeshShapeCollisionTraversalNodeOBB
// with libccd's GJK solver), and FCL's own statistics counters (num_bv_tests, num_leaf_tests)
// are read back. Two kinds of model:
//  - `fcl_own`: FCL's BVHModel<OBB> built by its default splitter and fitter;
//  - `from_tree`: our tree loaded into a BVHModel<OBB> through a splitter and fitter that
//    reproduce our partition and boxes. FCL's tree is binary with one triangle per leaf, so our
//    tree is binarised: a node with K > 2 children becomes a chain whose extra inner nodes carry
//    the parent's box, and a leaf with k > 1 faces becomes a subtree of 2k - 2 nodes below it,
//    each carrying the leaf's box. These *padding* nodes pass whenever their owner passed, so
//    FCL's raw num_bv_tests counts them too; `tree_node_bv_tests` counts FCL's BV tests on the
//    nodes that are ours (FCL's traversal and FCL's overlap decisions, our tally of which node).
//    The loaded model is checked node by node against the tree (same boxes, same faces).
// FCL tests the collider's bounding OBB (for a sphere, its cube), not the collider, against
// each box, so its counts are not ours; the point is the ratio between trees. The traversal
// never stops early (num_max_contacts is unlimited), as ours.
#pragma once

#include <memory>
#include <vector>

#include "collision/contact_predicates.h"
#include "common/mesh.h"
#include "common/status.h"
#include "common/tree.h"

namespace vobb::collision {

struct FclQueryResult {
  bool collide = false;
  std::vector<int32_t> faces;       // the triangles FCL found touching, ascending
  uint64_t bv_tests = 0;            // FCL's num_bv_tests
  uint64_t leaf_tests = 0;          // FCL's num_leaf_tests
  uint64_t tree_node_bv_tests = 0;  // of bv_tests, those on nodes of the tree (all, for fcl_own)
};

class FclModel {
 public:
  ~FclModel();
  FclModel(const FclModel&) = delete;
  FclModel& operator=(const FclModel&) = delete;

  static std::unique_ptr<FclModel> fcl_own(const Mesh& mesh);
  // Fails (one line prefixed with `display`) when the tree has a node with a single child,
  // which a binary BVH with this build cannot hold, or when FCL's model comes out different.
  static Status from_tree(const Mesh& mesh, const Tree& tree, const std::string& display,
                          std::unique_ptr<FclModel>* out);

  FclQueryResult query(const Collider& c) const;
  size_t bv_count() const;

 private:
  struct Impl;
  explicit FclModel(std::unique_ptr<Impl> impl);
  std::unique_ptr<Impl> impl_;
};

}  // namespace vobb::collision
