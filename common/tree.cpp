#include "common/tree.h"

#include <algorithm>

#include "common/sha256.h"

namespace vobb {

std::vector<int32_t> layer(const Tree& tree, int level) {
  std::vector<int32_t> out;
  for (const TreeNode& n : tree.nodes)
    if (n.level == level || (n.level < level && n.is_leaf())) out.push_back(n.id);
  return out;
}

int32_t common_ancestor(const Tree& tree, int32_t a, int32_t b) {
  while (a != b) {
    if (tree.nodes[a].level >= tree.nodes[b].level) a = tree.nodes[a].parent;
    if (tree.nodes[b].level > tree.nodes[a].level) b = tree.nodes[b].parent;
  }
  return a;
}

Status validate_tree(const Tree& tree, const std::string& display) {
  auto fail = [&](const std::string& why) { return Status::error(display + ": " + why); };
  const int32_t n = static_cast<int32_t>(tree.nodes.size());
  if (n == 0) return fail("tree has no nodes");
  if (tree.arity < 2) return fail("arity must be at least 2");
  if (const std::string bad = depth_defect(tree.depth); !bad.empty()) return fail(bad);
  // How many times each node is listed as a child (in range): a count per node, not a search of
  // its parent's list, so a node of many children costs time in its children alone.
  std::vector<int32_t> listed(n, 0);
  for (const TreeNode& node : tree.nodes)
    for (int32_t c : node.children)
      if (c > 0 && c < n) ++listed[c];
  int max_level = 0;
  for (int32_t i = 0; i < n; ++i) {
    const TreeNode& node = tree.nodes[i];
    const std::string at = "node " + std::to_string(i) + ": ";
    if (node.id != i) return fail(at + "id " + std::to_string(node.id) + " out of order");
    if (i == 0 && (node.parent != -1 || node.level != 0))
      return fail("node 0 must be the root (parent -1, level 0)");
    if (i > 0) {
      if (node.parent < 0 || node.parent >= n || node.parent == i) return fail(at + "bad parent");
      const TreeNode& p = tree.nodes[node.parent];
      if (listed[i] > 1) return fail(at + "listed as a child more than once");
      // Listed once, by a node the child loop below holds to be its parent.
      if (listed[i] == 0) return fail(at + "parent does not list it as a child");
      if (node.level != p.level + 1) return fail(at + "level is not its parent's plus one");
    }
    if (static_cast<int>(node.children.size()) > tree.arity)
      return fail(at + "more children than the arity");
    for (int32_t c : node.children)
      if (c <= 0 || c >= n || tree.nodes[c].parent != i)
        return fail(at + "bad child " + std::to_string(c));
    if (!node.box.center.allFinite() || !node.box.half.allFinite() ||
        (node.box.half.array() < 0).any())
      return fail(at + "box has non-finite or negative values");
    for (const Vec3& a : node.box.axes)
      if (!a.allFinite()) return fail(at + "box has non-finite axes");
    if (!std::is_sorted(node.faces.begin(), node.faces.end()) ||
        std::adjacent_find(node.faces.begin(), node.faces.end()) != node.faces.end())
      return fail(at + "faces are not sorted and distinct");
    if (node.is_leaf() && node.faces.empty()) return fail(at + "leaf without faces");
    max_level = std::max(max_level, node.level);
  }
  if (max_level != tree.depth)
    return fail("depth " + std::to_string(tree.depth) + " but the deepest leaf is at level " +
                std::to_string(max_level));
  // Leaves partition the faces; inner faces are the union of the children's. The owners are
  // kept in a list of the faces listed, not an array of mesh_triangles entries, so a claimed
  // triangle count far beyond the faces listed costs no memory.
  std::vector<std::pair<int32_t, int32_t>> owner;  // (face, leaf)
  for (const TreeNode& node : tree.nodes) {
    if (!node.is_leaf()) continue;
    for (int32_t f : node.faces) {
      if (f < 0 || static_cast<size_t>(f) >= tree.mesh_triangles)
        return fail("node " + std::to_string(node.id) + ": face " + std::to_string(f) +
                    " out of range");
      owner.push_back({f, node.id});
    }
  }
  std::sort(owner.begin(), owner.end());
  for (size_t i = 1; i < owner.size(); ++i)
    if (owner[i].first == owner[i - 1].first)
      return fail("face " + std::to_string(owner[i].first) + " is in two leaves");
  for (const TreeNode& node : tree.nodes) {
    if (node.is_leaf()) continue;
    std::vector<int32_t> u;
    for (int32_t c : node.children)
      u.insert(u.end(), tree.nodes[c].faces.begin(), tree.nodes[c].faces.end());
    std::sort(u.begin(), u.end());
    if (u != node.faces)
      return fail("node " + std::to_string(node.id) +
                  ": faces are not the union of its children's");
  }
  // Distinct and in range: they cover [0, mesh_triangles) exactly when there are that many.
  for (size_t f = 0; f < tree.mesh_triangles; ++f) {
    if (f == owner.size())
      return fail("the leaves hold " +
                  (f == 0 ? std::string("no faces") : "faces 0 to " + std::to_string(f - 1)) +
                  ", but the tree says the mesh has " + std::to_string(tree.mesh_triangles) +
                  " triangles");
    if (owner[f].first != static_cast<int32_t>(f))
      return fail("face " + std::to_string(f) + " is in no leaf");
  }
  return Status::ok();
}

Status check_tree_fits(const Mesh& mesh, const Tree& tree, const std::string& display,
                       const std::string& sha) {
  if (const Status s = validate_tree(tree, display); !s) return s;
  if (tree.mesh_triangles != mesh.faces.size())
    return Status::error(display + ": tree indexes " + std::to_string(tree.mesh_triangles) +
                         " triangles but the mesh has " + std::to_string(mesh.faces.size()));
  if (!tree.mesh_sha256.empty() && tree.mesh_sha256 != (sha.empty() ? mesh_sha256(mesh) : sha))
    return Status::error(display + ": built for another mesh (sha256 differs)");
  return Status::ok();
}

ContainmentReport check_conservative(const Mesh& mesh, const Tree& tree, size_t max_examples) {
  ContainmentReport r;
  for (const TreeNode& node : tree.nodes) {
    ExactBoxContainment inside(node.box);
    for (int32_t f : node.faces) {
      ++r.checked_pairs;
      bool ok = true;
      for (int k = 0; k < 3 && ok; ++k) ok = inside.contains(mesh.corner(f, k));
      if (!ok) {
        ++r.violations;
        if (r.first.size() < max_examples) r.first.emplace_back(node.id, f);
      }
    }
  }
  return r;
}

}  // namespace vobb
