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

#include "common/cell_clip.h"
#include "common/exact_predicates.h"
#include "common/mesh.h"
#include "common/obb.h"

namespace vobb::exact {

using cell_clip::clipped_faces;  // the combinatorial step, shared with every number type's cell
using cell_clip::compact_faces;

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
