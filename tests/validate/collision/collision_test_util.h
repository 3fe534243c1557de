// Trees the collision tests share.
#pragma once

#include "builder/obbtree_builder.h"
#include "common/tree.h"

namespace vobb::collision::test_util {

// The whole mesh in one leaf, in the baseline's root box (which holds every face).
inline Tree single_leaf(const Mesh& mesh) {
  ObbTreeOptions opt;
  opt.depth = 0;
  return build_obbtree(mesh, opt);
}

// That leaf below a root of the same box and faces, its only child: a valid tree for our
// traversal, and one FCL's binary BVH cannot hold.
inline Tree root_with_one_child(const Mesh& mesh) {
  Tree t = single_leaf(mesh);
  TreeNode child = t.nodes[0];
  child.id = 1;
  child.parent = 0;
  child.level = 1;
  t.nodes[0].children = {1};
  t.nodes.push_back(child);
  t.depth = 1;
  return t;
}

}  // namespace vobb::collision::test_util
