// vobb::Tree — a k-ary hierarchy of OBBs over a mesh's faces (DESIGN §1, §7).
//
// nodes[i].id == i and nodes[0] is the root at level 0. A leaf lists its faces; an inner
// node's faces are the union of its leaves' faces. Layer i is the cut at level i: the nodes
// at level i plus every leaf above level i, so every layer bounds every face once.
#pragma once

#include <cstdint>
#include <string>
#include <utility>
#include <vector>

#include "common/mesh.h"
#include "common/obb.h"
#include "common/status.h"

namespace vobb {

struct TreeNode {
  int32_t id = 0;
  int32_t parent = -1;  // -1 for the root
  int32_t level = 0;
  Obb box;
  std::vector<int32_t> children;
  std::vector<int32_t> faces;  // sorted ascending
  bool is_leaf() const { return children.empty(); }
};

struct Tree {
  std::string method;  // "obbtree", "variational", ...
  int arity = 2;       // the most children a node may have
  int depth = 0;       // the deepest leaf's level
  size_t mesh_triangles = 0;
  std::string mesh_sha256;  // see sha256.h
  std::vector<TreeNode> nodes;
};

// The deepest tree vobb reads or checks (the builders make at most 30 levels): a reader fills in
// each inner node's faces from its children's, at most the depth times the faces a file lists.
inline constexpr int kMaxTreeDepth = 64;
// "" for a depth in 0..kMaxTreeDepth, else what is wrong with it.
inline std::string depth_defect(long long depth) {
  if (depth >= 0 && depth <= kMaxTreeDepth) return "";
  return "depth " + std::to_string(depth) + " is outside 0.." + std::to_string(kMaxTreeDepth);
}

// The weight ω(l) = D - l + 1 of layer l (0 <= l <= D) in the error of a tree of depth D,
// e = Σ_l ω(l) OMV(layer l) (DESIGN §1): the one place it is written.
inline int layer_weight(int depth, int level) { return depth - level + 1; }

// Node ids of layer `level` (0 <= level <= depth), ascending.
std::vector<int32_t> layer(const Tree& tree, int level);

// The lowest common ancestor of nodes a and b (ids) of a valid tree.
int32_t common_ancestor(const Tree& tree, int32_t a, int32_t b);

// Structural check: ids, parent/child links, levels, arity, depth (at most kMaxTreeDepth), and
// that the leaves partition the faces [0, mesh_triangles) with each inner node's faces the
// union of its children's. Messages are one line prefixed with `display`.
Status validate_tree(const Tree& tree, const std::string& display);

// validate_tree, and that the tree indexes this mesh: its triangle count and, where the tree
// records one, the mesh's SHA-256 (sha256.h). Messages are one line prefixed with `display`.
// `mesh_sha256`, where not empty, is taken as mesh_sha256(mesh) instead of hashing the mesh again
// (a caller that checks several trees of one mesh hashes it once).
Status check_tree_fits(const Mesh& mesh, const Tree& tree, const std::string& display,
                       const std::string& mesh_sha256 = {});

// Conservativeness by exact predicates: each face of each node lies in that node's box.
// Precondition: the tree fits the mesh (check_tree_fits).
struct ContainmentReport {
  size_t checked_pairs = 0;  // (node, face) pairs tested
  size_t violations = 0;     // (node, face) pairs with a vertex outside the box
  std::vector<std::pair<int32_t, int32_t>> first;  // up to `max_examples` (node, face)
  bool ok() const { return violations == 0; }
};
ContainmentReport check_conservative(const Mesh& mesh, const Tree& tree, size_t max_examples = 8);

}  // namespace vobb
