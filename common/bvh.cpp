#include "common/bvh.h"

#include <algorithm>

namespace vobb {
namespace {
constexpr int32_t kLeafSize = 4;
}

AabbTree::AabbTree(std::vector<Aabb> boxes) : boxes_(std::move(boxes)) {
  const int32_t n = static_cast<int32_t>(boxes_.size());
  order_.resize(n);
  std::vector<Vec3> centroids(n);
  for (int32_t i = 0; i < n; ++i) {
    order_[i] = i;
    // An empty box (a primitive of no extent: a flat box's empty cell) has infinite bounds the
    // wrong way round; its centroid would be NaN, which no ordering can sort. It overlaps
    // nothing, so any finite centroid will do.
    centroids[i] = boxes_[i].empty() ? Vec3::Zero() : Vec3(0.5 * (boxes_[i].lo + boxes_[i].hi));
  }
  if (n > 0) {
    nodes_.reserve(2 * (n / kLeafSize + 1));
    nodes_.push_back({});
    build(0, 0, n, centroids);
  }
}

AabbTree AabbTree::over_faces(const Mesh& mesh) {
  std::vector<Aabb> boxes(mesh.faces.size());
  for (size_t f = 0; f < boxes.size(); ++f) boxes[f] = mesh.face_bounds(f);
  return AabbTree(std::move(boxes));
}

void AabbTree::build(int32_t node, int32_t begin, int32_t end, const std::vector<Vec3>& centroids) {
  Aabb bounds, cbounds;
  for (int32_t i = begin; i < end; ++i) {
    bounds.extend(boxes_[order_[i]]);
    cbounds.extend(centroids[order_[i]]);
  }
  nodes_[node].bounds = bounds;
  if (end - begin <= kLeafSize) {
    nodes_[node].first = begin;
    nodes_[node].count = end - begin;
    return;
  }
  int axis;
  (cbounds.hi - cbounds.lo).maxCoeff(&axis);
  const int32_t mid = begin + (end - begin) / 2;
  std::nth_element(order_.begin() + begin, order_.begin() + mid, order_.begin() + end,
                   [&](int32_t a, int32_t b) {
                     if (centroids[a][axis] != centroids[b][axis])
                       return centroids[a][axis] < centroids[b][axis];
                     return a < b;  // ties by index: the same tree on every run
                   });
  const int32_t left = static_cast<int32_t>(nodes_.size());
  nodes_[node].first = left;
  nodes_[node].count = 0;
  nodes_.push_back({});
  nodes_.push_back({});
  build(left, begin, mid, centroids);
  build(left + 1, mid, end, centroids);
}

void AabbTree::for_each_overlap(const Aabb& query,
                                const std::function<void(int32_t)>& visit) const {
  for_each_accepted([&](const Aabb& b) { return b.overlaps(query); }, visit);
}

void AabbTree::for_each_accepted(const std::function<bool(const Aabb&)>& accept,
                                 const std::function<void(int32_t)>& visit) const {
  visit_accepted(accept, visit);
}

}  // namespace vobb
