// One vobb tree prepared for collision queries: the traversal whose tests the collision
// experiment counts (paper §5).
//
// A query walks the tree from the root. Each visited node costs one collider–box test
// (`may_touch_box`, conservative); a node that may touch is opened, and at a leaf each face
// costs one leaf triangle test (`touches_triangle`). There is no early exit: a query finds
// every touching face. Preconditions: the tree is well formed (validate_tree) and its boxes contain
// their faces (check_conservative);
// then the faces found equal brute force's (`BruteForce`).
#pragma once

#include <cstdint>
#include <vector>

#include "collision/contact_predicates.h"
#include "common/mesh.h"
#include "common/tree.h"

namespace vobb::collision {

struct QueryCounts {
  uint64_t box_tests = 0;   // collider–box tests (every visited node, the root included)
  uint64_t leaf_tests = 0;  // collider–triangle tests at the leaves
  uint64_t contacts = 0;    // touching faces found
  // box_tests split by the tested node's level (root = 0); sums to box_tests. Level 0 counts
  // one test per query, whatever the tree below it.
  std::vector<uint64_t> box_tests_by_level;
};

class TreeTraversal {
 public:
  // Keeps references to `mesh`; copies what it needs of `tree`.
  TreeTraversal(const Mesh& mesh, const Tree& tree);
  // Sets `faces` to the touching faces, ascending, and adds to `counts`.
  void query(const PreparedCollider& c, std::vector<int32_t>* faces, QueryCounts* counts) const;

 private:
  struct Node {
    PreparedBox box;
    int32_t first_child = 0, num_children = 0;  // into children_
    int32_t first_face = 0, num_faces = 0;      // into faces_ (leaves only)
    int32_t level = 0;                          // root = 0 (the tree's, checked by validate_tree)
  };
  const Mesh& mesh_;
  std::vector<Node> nodes_;
  std::vector<int32_t> children_, faces_;
  int32_t levels_;  // tree.depth + 1
  mutable std::vector<int32_t> stack_;
};

// Brute force, the traversal's check: every face of the mesh against the collider, in mesh
// order, by touches_triangle. A first screen drops the faces whose x range misses the
// collider's bounding box, reading two floats per face from flat arrays (a vectorised scan);
// a second one does the same for y and z on the faces that pass. The floats are the ranges
// rounded outward (the face's and the collider's), so a face is dropped only when
// touches_triangle's own exact bounding-box prefilter drops it as well. The faces that pass go
// to touches_triangle, so the answer is touches_triangle's on every face. Keeps a reference
// to `mesh`.
class BruteForce {
 public:
  explicit BruteForce(const Mesh& mesh);
  // Sets `faces` to the touching faces, ascending.
  void touching(const PreparedCollider& c, std::vector<int32_t>* faces) const;

 private:
  const Mesh& mesh_;
  std::vector<float> lo_[3], hi_[3];  // per face and axis: its range, rounded outward
};

}  // namespace vobb::collision
