// vobb::exact::ConvexCell — a bounded convex polyhedron with rational vertices, clipped by
// half-spaces exactly. The building block of the clipping path (path b) of the exact solver.
//
// Faces are vertex cycles, counter-clockwise seen from outside. Clipping by {x : n.x <= d}
// keeps that side and closes the cut with a cap face; every decision is an exact sign.
// Degenerate contacts (a vertex or an edge on the plane) are handled. A cell clipped to
// nothing, or to a flat remainder, becomes empty.
#pragma once

#include <algorithm>
#include <array>
#include <utility>
#include <vector>

#include "common/exact_predicates.h"
#include "common/mesh.h"
#include "common/obb.h"

namespace vobb::exact {

// The cap's vertex cycle from its edges: next[b] = a for each kept edge a -> b on the plane (-1
// where none), `edges` of them.
std::vector<int> cap_cycle(const std::vector<int>& next, size_t edges);

// The combinatorial step of clipping a cell, shared by every number type's cell (ConvexCell
// here, the filter's in exact/filtered_solver.cpp). Given the faces (vertex cycles, counter-
// clockwise from outside) of a cell with `n` vertices and each vertex's side of a plane (-1 in,
// 0 on, +1 out; some -1 and some +1), returns the faces of the part on the closed inner side,
// the cut closed by a cap face. `cut(a, b)` (a < b) is called once per edge that crosses the
// plane and returns the id of the crossing point it made (n and upward). Vertex ids are those
// of the cell, then the cut points; compact_faces() renumbers them.
template <class Cut>
std::vector<std::vector<int>> clipped_faces(const std::vector<std::vector<int>>& faces, const std::vector<int>& side,
                                            int n, Cut&& cut) {
  std::vector<std::pair<long long, int>> made;  // edge (a, b), a < b -> its crossing point: few
  auto cut_point = [&](int a, int b) {
    const long long key = static_cast<long long>(std::min(a, b)) * (1LL << 31) + std::max(a, b);
    for (const auto& [k, id] : made)
      if (k == key) return id;
    const int id = cut(std::min(a, b), std::max(a, b));
    made.emplace_back(key, id);
    return id;
  };
  auto on_plane = [&](int id) { return id >= n || side[id] == 0; };
  std::vector<std::vector<int>> kept;
  std::vector<int> cap_next;  // cap edge b -> a for each kept edge a -> b on the plane
  size_t cap_edges = 0;
  for (const std::vector<int>& f : faces) {
    std::vector<int> poly;
    const size_t m = f.size();
    for (size_t k = 0; k < m; ++k) {
      const int a = f[k], b = f[(k + 1) % m];
      if (side[a] <= 0) poly.push_back(a);
      if (side[a] * side[b] < 0) poly.push_back(cut_point(a, b));
    }
    if (poly.size() < 3) continue;
    for (size_t k = 0; k < poly.size(); ++k) {
      const int a = poly[k], b = poly[(k + 1) % poly.size()];
      if (!on_plane(a) || !on_plane(b)) continue;
      if (static_cast<size_t>(b) >= cap_next.size()) cap_next.resize(b + 1, -1);
      cap_edges += cap_next[b] < 0 ? 1 : 0;
      cap_next[b] = a;
    }
    kept.push_back(std::move(poly));
  }
  if (cap_edges >= 3) kept.push_back(cap_cycle(cap_next, cap_edges));
  return kept;
}

// Renumbers the faces' vertex ids 0, 1, ... in order of first use; returns each new id's old
// id (the vertices to keep, in their new order).
std::vector<int> compact_faces(std::vector<std::vector<int>>* faces, size_t n_ids);

struct QPoint {
  Rational x[3];
};

// The closed half-space n . x <= d. `set_shadow()` caches double copies for the filter.
struct HalfSpace {
  Rational n[3];
  Rational d;
  double nd[3] = {0, 0, 0};
  double dd = 0;
  void set_shadow();
  HalfSpace complement() const;  // n . x >= d, as (-n) . x <= -d
};

// Where a cell lies relative to a half-space, as far as a double filter can tell.
enum class Side { kInside, kOutside, kCrossing };

// The six half-spaces whose intersection is the certified solid of the box (DESIGN §1):
// |t_k| <= 1 with t = [h0 a0, h1 a1, h2 a2]^-1 (p - c), in Cramer form. Precondition: the
// box has nonzero volume.
std::array<HalfSpace, 6> box_half_spaces(const Obb& box);

class ConvexCell {
 public:
  ConvexCell() = default;
  // The certified solid of the box: 8 exact corners c + sum_k (+-h_k) a_k. A box of zero
  // volume gives the empty cell.
  static ConvexCell from_box(const Obb& box);

  bool empty() const { return faces_.empty(); }
  // kInside: every vertex surely in h; kOutside: every vertex surely strictly out;
  // kCrossing: anything else (the exact clip decides). Never wrong, sometimes undecided.
  Side classify(const HalfSpace& h) const;
  // Keeps the part of the cell in h.
  void clip(const HalfSpace& h);
  // Exact volume (divergence theorem over the faces, fans from one vertex).
  Rational volume() const;
  // Axis-aligned bounds in double, rounded outward so that they contain the cell.
  Aabb bounds() const;

 private:
  void refresh_shadow();

  std::vector<QPoint> v_;
  std::vector<Vec3> vd_;  // double copies of v_ (truncated: within one ulp)
  std::vector<std::vector<int>> faces_;
};

}  // namespace vobb::exact
