#include "validate/collision/tree_traversal.h"

#include <algorithm>

namespace vobb::collision {

TreeTraversal::TreeTraversal(const Mesh& mesh, const Tree& tree) : mesh_(mesh), levels_(tree.depth + 1) {
  nodes_.resize(tree.nodes.size());
  for (size_t i = 0; i < tree.nodes.size(); ++i) {
    const TreeNode& t = tree.nodes[i];
    Node& n = nodes_[i];
    n.box = prepare_box(t.box);
    n.level = t.level;
    n.first_child = static_cast<int32_t>(children_.size());
    n.num_children = static_cast<int32_t>(t.children.size());
    children_.insert(children_.end(), t.children.begin(), t.children.end());
    if (t.is_leaf()) {
      n.first_face = static_cast<int32_t>(faces_.size());
      n.num_faces = static_cast<int32_t>(t.faces.size());
      faces_.insert(faces_.end(), t.faces.begin(), t.faces.end());
    }
  }
}

void TreeTraversal::query(const PreparedCollider& c, std::vector<int32_t>* faces, QueryCounts* counts) const {
  faces->clear();
  if (counts->box_tests_by_level.size() < static_cast<size_t>(levels_)) counts->box_tests_by_level.resize(levels_, 0);
  stack_.assign(1, 0);
  while (!stack_.empty()) {
    const Node& n = nodes_[stack_.back()];
    stack_.pop_back();
    ++counts->box_tests;
    ++counts->box_tests_by_level[n.level];
    if (!may_touch_box(c, n.box)) continue;
    // Children pushed in reverse so that they are visited in stored order (depth first).
    for (int32_t k = n.num_children - 1; k >= 0; --k) stack_.push_back(children_[n.first_child + k]);
    for (int32_t k = 0; k < n.num_faces; ++k) {
      const int32_t f = faces_[n.first_face + k];
      ++counts->leaf_tests;
      if (touches_triangle(c, mesh_.corner(f, 0), mesh_.corner(f, 1), mesh_.corner(f, 2))) faces->push_back(f);
    }
  }
  std::sort(faces->begin(), faces->end());
  counts->contacts += faces->size();
}

void brute_force_touching(const Mesh& mesh, const PreparedCollider& c, std::vector<int32_t>* faces) {
  faces->clear();
  for (size_t f = 0; f < mesh.faces.size(); ++f)
    if (touches_triangle(c, mesh.corner(f, 0), mesh.corner(f, 1), mesh.corner(f, 2)))
      faces->push_back(static_cast<int32_t>(f));
}

}  // namespace vobb::collision
