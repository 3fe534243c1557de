// vobb::AabbTree — a bounding-volume hierarchy of axis-aligned boxes over primitives
// (usually the faces of a Mesh).
//
// Built once by median splits of the primitive centroids along the longest axis; queried for
// every primitive whose box overlaps a query box (closed intervals: touching counts).
// The tree stores primitive indices only; the caller keeps the primitives.
#pragma once

#include <cstdint>
#include <functional>
#include <vector>

#include "common/mesh.h"

namespace vobb {

class AabbTree {
 public:
  AabbTree() = default;
  // One box per primitive; primitive i is reported as index i.
  explicit AabbTree(std::vector<Aabb> boxes);
  static AabbTree over_faces(const Mesh& mesh);

  // Calls visit(i) for every primitive i whose box overlaps `query`, in a fixed order.
  void for_each_overlap(const Aabb& query, const std::function<void(int32_t)>& visit) const;
  // General form: descends into every node, and reports every primitive, whose box passes
  // `accept`. `accept` must be conservative: true for any box that may hold a wanted
  // primitive.
  void for_each_accepted(const std::function<bool(const Aabb&)>& accept,
                         const std::function<void(int32_t)>& visit) const;
  // The same, with both calls inlined (for inner loops).
  template <class Accept, class Visit>
  void visit_accepted(const Accept& accept, Visit&& visit) const {
    visit_accepted_until(accept, [&](int32_t i) {
      visit(i);
      return true;
    });
  }
  // The same, until visit (which returns bool) returns false; false if it did.
  template <class Accept, class Visit>
  bool visit_accepted_until(const Accept& accept, Visit&& visit) const {
    if (nodes_.empty()) return true;
    int32_t stack[128];
    int top = 0;
    stack[top++] = 0;
    while (top > 0) {
      const Node& n = nodes_[stack[--top]];
      if (!accept(n.bounds)) continue;
      if (n.count > 0) {
        for (int32_t i = n.first; i < n.first + n.count; ++i)
          if (accept(boxes_[order_[i]]) && !visit(order_[i])) return false;
      } else {
        stack[top++] = n.first + 1;
        stack[top++] = n.first;
      }
    }
    return true;
  }
  const Aabb& primitive_bounds(int32_t i) const { return boxes_[i]; }
  size_t size() const { return boxes_.size(); }
  // Bounds of all primitives (empty for an empty tree).
  Aabb bounds() const { return nodes_.empty() ? Aabb() : nodes_[0].bounds; }

  // The nodes, for callers that keep data of their own per node or walk the tree themselves.
  // Node 0 is the root (when there are primitives); a child's index is larger than its
  // parent's, so a pass from the last node to the first sees children before parents.
  struct Node {
    Aabb bounds;
    int32_t first;  // leaf: offset into order(); inner: index of left child (right = left+1)
    int32_t count;  // > 0 for a leaf, whose primitives are order()[first .. first + count)
  };
  const std::vector<Node>& nodes() const { return nodes_; }
  const std::vector<int32_t>& order() const { return order_; }

 private:
  void build(int32_t node, int32_t begin, int32_t end, const std::vector<Vec3>& centroids);

  std::vector<Aabb> boxes_;
  std::vector<int32_t> order_;
  std::vector<Node> nodes_;
};

}  // namespace vobb
