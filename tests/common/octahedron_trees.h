// Small trees over the octahedron's 8 faces for the tree tests (common/tree.h, tree_io.h):
// each node given by its parent, level, children and faces; the boxes fitted on one frame.
#pragma once

#include <array>
#include <cstdint>
#include <vector>

#include "common/obb.h"
#include "common/tree.h"
#include "data/analytic_meshes.h"

namespace vobb::test {

struct NodeSpec {
  int32_t parent, level;
  std::vector<int32_t> children, faces;
};

// The tree whose node i is nodes[i] (node 0 the root), of the given depth, method "test".
inline Tree octahedron_tree(int depth, const std::vector<NodeSpec>& nodes) {
  const Mesh m = analytic::octahedron().mesh;
  const std::array<Vec3, 3> frame = {Vec3(0.6, 0.8, 0), Vec3(-0.8, 0.6, 0), Vec3(0, 0, 1)};
  Tree t;
  t.method = "test";
  t.arity = 2;
  t.depth = depth;
  t.mesh_triangles = m.faces.size();
  for (const NodeSpec& s : nodes) {
    TreeNode n;
    n.id = static_cast<int32_t>(t.nodes.size());
    n.parent = s.parent;
    n.level = s.level;
    n.children = s.children;
    n.faces = s.faces;
    n.box = fit_obb(m, n.faces, frame);
    t.nodes.push_back(n);
  }
  return t;
}

}  // namespace vobb::test
