#include "collision/tree_traversal.h"

#include <algorithm>
#include <cmath>
#include <limits>

namespace vobb::collision {

TreeTraversal::TreeTraversal(const Mesh& mesh, const Tree& tree)
    : mesh_(mesh), levels_(tree.depth + 1) {
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

void TreeTraversal::query(const PreparedCollider& c, std::vector<int32_t>* faces,
                          QueryCounts* counts) const {
  faces->clear();
  if (counts->box_tests_by_level.size() < static_cast<size_t>(levels_))
    counts->box_tests_by_level.resize(levels_, 0);
  stack_.assign(1, 0);
  while (!stack_.empty()) {
    const Node& n = nodes_[stack_.back()];
    stack_.pop_back();
    ++counts->box_tests;
    ++counts->box_tests_by_level[n.level];
    if (!may_touch_box(c, n.box)) continue;
    // Children pushed in reverse so that they are visited in stored order (depth first).
    for (int32_t k = n.num_children - 1; k >= 0; --k)
      stack_.push_back(children_[n.first_child + k]);
    for (int32_t k = 0; k < n.num_faces; ++k) {
      const int32_t f = faces_[n.first_face + k];
      ++counts->leaf_tests;
      if (touches_triangle(c, mesh_.corner(f, 0), mesh_.corner(f, 1), mesh_.corner(f, 2)))
        faces->push_back(f);
    }
  }
  std::sort(faces->begin(), faces->end());
  counts->contacts += faces->size();
}

namespace {
// Why the screen is safe: it drops a face when float_up(h) < float_down(l), h the top of the
// face's range and l the bottom of the collider's (or the mirror case), and then
// h <= float_up(h) < float_down(l) <= l: the exact prefilter's h < l holds too. (Rounding both
// to nearest would also be safe, being monotone; outward rounding makes it evident.)
// A float at most x (float_down) or at least x (float_up), the nearest such one; a double beyond
// float's range goes to +-FLT_MAX or +-inf on the safe side (explicitly: converting it is
// undefined in C++).
float float_down(double x) {
  constexpr float kMax = std::numeric_limits<float>::max();
  if (x > kMax) return kMax;
  if (x < -kMax) return -std::numeric_limits<float>::infinity();
  float f = static_cast<float>(x);
  if (static_cast<double>(f) > x) f = std::nextafter(f, -std::numeric_limits<float>::infinity());
  return f;
}
float float_up(double x) { return -float_down(-x); }
}  // namespace

BruteForce::BruteForce(const Mesh& mesh) : mesh_(mesh) {
  for (int i = 0; i < 3; ++i) {
    lo_[i].resize(mesh.faces.size());
    hi_[i].resize(mesh.faces.size());
  }
  for (size_t f = 0; f < mesh.faces.size(); ++f)
    for (int i = 0; i < 3; ++i) {
      const double a = mesh.corner(f, 0)[i], b = mesh.corner(f, 1)[i], c = mesh.corner(f, 2)[i];
      lo_[i][f] = float_down(std::min(std::min(a, b), c));
      hi_[i][f] = float_up(std::max(std::max(a, b), c));
    }
}

void BruteForce::touching(const PreparedCollider& c, std::vector<int32_t>* faces) const {
  faces->clear();
  constexpr size_t kBlock = 256;
  unsigned char pass[kBlock];
  const size_t n = mesh_.faces.size();
  float lo[3], hi[3];
  for (int i = 0; i < 3; ++i) lo[i] = float_down(c.bounds.lo[i]), hi[i] = float_up(c.bounds.hi[i]);
  const float *lx = lo_[0].data(), *hx = hi_[0].data();
  for (size_t start = 0; start < n; start += kBlock) {
    const size_t len = std::min(kBlock, n - start);
    // Branch-free, so that the compiler can vectorise it.
    for (size_t k = 0; k < len; ++k) pass[k] = !((hx[start + k] < lo[0]) | (lx[start + k] > hi[0]));
    for (size_t k = 0; k < len; ++k) {
      if (!pass[k]) continue;
      const size_t f = start + k;
      if (hi_[1][f] < lo[1] || lo_[1][f] > hi[1] || hi_[2][f] < lo[2] || lo_[2][f] > hi[2])
        continue;
      if (touches_triangle(c, mesh_.corner(f, 0), mesh_.corner(f, 1), mesh_.corner(f, 2)))
        faces->push_back(static_cast<int32_t>(f));
    }
  }
}

}  // namespace vobb::collision
