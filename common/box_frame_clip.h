// The box-frame clip formula for one box's OBV, written once over the number type
// (DESIGN §3, §4b; derivation in docs/derivations.md, "OBV in the box's frame").
//
// The map T(p) = W (p - c), with rows w_k = u_{k+1} x u_{k+2} (u_k = h_k a_k), sends the box's
// certified solid to the cube |T_k| <= R = |det U| and scales volumes by det(U)^2. In T-space
//   6 R^2 vol(X ∩ box) = sum over faces of face_term6(face),
// the signed prism decomposition of X along -T_2: each face adds 6 x the integral over its
// clipped shadow of clamp(z, -R, R) + R, signed by the shadow's orientation. So
//   OBV = 8 R - sum / (6 R^2).
//
// NT is one of: Rational (exact, common/exact_predicates.h), double (a point value, rounded),
// or an interval type (an enclosure). Every branch is a sign taken through a decider (SignOf,
// ClipTraits<NT>::sign, by default); for an interval type the caller's decider answers only
// what the enclosure or exact arithmetic decides. With the same decisions the three follow the
// same arithmetic, so they cannot drift apart.
#pragma once

#include <cmath>
#include <cstdint>
#include <utility>

#include "common/bvh.h"
#include "common/exact_predicates.h"
#include "common/mesh.h"
#include "common/obb.h"

namespace vobb::box_clip {

// sign(x) in {-1, 0, +1}. Specialised for double and Rational here; an interval type's
// specialisation throws where its enclosure holds 0 and other values.
template <class NT>
struct ClipTraits;

template <>
struct ClipTraits<double> {
  static int sign(double x) { return (x > 0) - (x < 0); }
};

template <>
struct ClipTraits<Rational> {
  static int sign(const Rational& x) { return sgn(x); }
};

// A vertex in T-space; `origin` is the mesh vertex it is (-1 for a point a clip made), so that
// a decider may settle its signs from the mesh's own coordinates.
template <class NT>
struct Point {
  NT x[3];
  int32_t origin = -1;
};

// A triangle clipped by the column's four sides and the slab's two planes has at most
// 3 + 6 vertices, when the signs are the exact ones (a convex polygon gains at most one vertex
// per clip). Rounded signs (NT = double) can be inconsistent and make more: clip() then throws
// PolygonOverflow, and the double caller falls back to a certified evaluation.
inline constexpr int kMaxPolygon = 9;
struct PolygonOverflow {};

template <class NT>
struct Polygon {
  Point<NT> v[kMaxPolygon];
  int n = 0;
};

// The box's frame in NT: centre c, edge vectors u_k = h_k a_k, Cramer rows
// w_k = u_{k+1} x u_{k+2} and det = det[u0 u1 u2] (ExactBoxFrame is the Rational one).
//
// A frame may be made in units scaled by 2^-e (make_frame's `e`): u_k = (2^-e h_k) a_k and
// to_frame takes 2^-e (p - c). Every T-coordinate and R then come out multiplied by 2^-3e,
// every face term by 2^-9e and the OBV by 2^-3e, exactly in rationals; in floating point the
// same numbers are rounded at the same places, so the results are the unscaled ones times
// those powers, bit for bit, wherever neither lies outside the normal range. frame_exponent()
// picks the e that brings R near 1, so that a box's evaluation does not depend on how far its
// size lies from 1 (docs/derivations.md, "Interval range").
template <class NT>
struct Frame {
  NT c[3];
  NT u[3][3];
  NT w[3][3];
  NT det;
  int e = 0;    // the units' exponent: lengths in units of 2^e
  NT scale{1};  // 2^-e
};

// The e of the box's scaled frame: the floor of the mean of the half extents' binary
// exponents, so that the scaled half extents' product lies in [1, 32) and R is that times
// |det[a0 a1 a2]| (about 1). For a box that passes box_defect (each half extent's exponent
// within [-1022, 242]) every scaled half extent lies within [2^-842, 2^844), so scaling is
// exact. 0 for a flat box.
int frame_exponent(const Obb& box);

template <class NT>
Frame<NT> make_frame(const Obb& box, int e = 0) {
  Frame<NT> f;
  f.e = e;
  f.scale = NT(std::ldexp(1.0, -e));
  auto& u = f.u;
  for (int k = 0; k < 3; ++k) {
    f.c[k] = NT(box.center[k]);
    for (int i = 0; i < 3; ++i) u[k][i] = NT(std::ldexp(box.half[k], -e)) * NT(box.axes[k][i]);
  }
  for (int k = 0; k < 3; ++k) {
    const NT* a = u[(k + 1) % 3];
    const NT* b = u[(k + 2) % 3];
    f.w[k][0] = a[1] * b[2] - a[2] * b[1];
    f.w[k][1] = a[2] * b[0] - a[0] * b[2];
    f.w[k][2] = a[0] * b[1] - a[1] * b[0];
  }
  f.det = u[0][0] * f.w[0][0] + u[0][1] * f.w[0][1] + u[0][2] * f.w[0][2];
  return f;
}

// T(p) for a mesh vertex p (its index `origin`, or -1), in the frame's units.
template <class NT>
Point<NT> to_frame(const Frame<NT>& f, const Vec3& p, int32_t origin = -1) {
  NT d[3] = {NT(p[0]) - f.c[0], NT(p[1]) - f.c[1], NT(p[2]) - f.c[2]};
  if (f.e != 0)
    for (NT& x : d) x = x * f.scale;
  Point<NT> q;
  for (int k = 0; k < 3; ++k) q.x[k] = d[0] * f.w[k][0] + d[1] * f.w[k][1] + d[2] * f.w[k][2];
  q.origin = origin;
  return q;
}

// Every branch of face_term6 is sign(side x_axis - bound R) for a point, with side and bound
// in {+1, -1}, given its value `val` in NT. The default decider takes ClipTraits' sign of it;
// another (fast/poly_solver.cpp) may settle a mesh vertex's sign exactly where NT cannot.
struct SignOf {
  template <class NT>
  int operator()(const Point<NT>&, int /*axis*/, int /*side*/, int /*bound*/, const NT& val) const {
    return ClipTraits<NT>::sign(val);
  }
};

namespace detail {

// side * x_axis - b, where b = bound * R: positive beyond the plane.
template <class NT>
NT side_value(const Point<NT>& p, int axis, int side, const NT& b) {
  return side > 0 ? NT(p.x[axis] - b) : NT(-p.x[axis] - b);
}

template <class NT, class Decide>
int side_sign(const Decide& decide, const Point<NT>& p, int axis, int side, int bound,
              const NT& R) {
  return decide(p, axis, side, bound, side_value(p, axis, side, bound > 0 ? R : NT(-R)));
}

// Twice the signed area of the shadow (x, y) of triangle abc.
template <class NT>
NT cross2(const Point<NT>& a, const Point<NT>& b, const Point<NT>& c) {
  return (b.x[0] - a.x[0]) * (c.x[1] - a.x[1]) - (b.x[1] - a.x[1]) * (c.x[0] - a.x[0]);
}

// The part of *in where side * x[axis] <= bound * R, by Sutherland-Hodgman, which keeps the
// cycle's orientation. Returns `in` itself when no vertex lies beyond (nothing to cut), else
// `out` filled (n = 0 when fewer than 3 vertices remain).
template <class NT, class Decide>
const Polygon<NT>* clip(const Decide& decide, const Polygon<NT>* in, int axis, int side, int bound,
                        const NT& R, Polygon<NT>* out) {
  const int n = in->n;
  if (n == 0) return in;
  int s[kMaxPolygon];
  NT val[kMaxPolygon];
  bool any_out = false, any_in = false;
  const NT b = bound > 0 ? R : NT(-R);
  for (int i = 0; i < n; ++i) {
    val[i] = side_value(in->v[i], axis, side, b);
    s[i] = decide(in->v[i], axis, side, bound, val[i]);
    any_out |= s[i] > 0;
    any_in |= s[i] <= 0;
  }
  if (!any_out) return in;
  out->n = 0;
  if (any_in) {
    for (int i = 0; i < n; ++i) {
      const int j = i + 1 < n ? i + 1 : 0;
      if (s[i] <= 0) {
        if (out->n == kMaxPolygon) throw PolygonOverflow{};
        out->v[out->n++] = in->v[i];
      }
      if (s[i] * s[j] < 0) {
        if (out->n == kMaxPolygon) throw PolygonOverflow{};
        const NT t = val[i] / (val[i] - val[j]);
        Point<NT>& p = out->v[out->n++];
        for (int k = 0; k < 3; ++k) p.x[k] = in->v[i].x[k] + t * (in->v[j].x[k] - in->v[i].x[k]);
        p.origin = -1;
      }
    }
  }
  if (out->n < 3) out->n = 0;
  return out;
}

}  // namespace detail

// 6 x the integral over the clipped shadow of `tri` (vertices in T-space) of
// clamp(z, -R, R) + R, signed by the shadow's orientation; R > 0. Returns false (and leaves
// *term alone) when the face adds nothing: its shadow misses the square, it lies below the
// slab, or its clipped shadow is degenerate. A face above the slab adds 2R x its shadow; a face
// inside the column and the slab is a closed form; only faces crossing them are clipped, and
// a face lying in z = R counts as above (the integrand is continuous there).
template <class NT, class Decide = SignOf>
bool face_term6(const Point<NT> (&tri)[3], const NT& R, NT* term, const Decide& decide = Decide()) {
  using detail::cross2;
  using detail::side_sign;
  auto clip = [&](const Polygon<NT>* in, int axis, int side, int bound, Polygon<NT>* out) {
    return detail::clip(decide, in, axis, side, bound, R, out);
  };
  auto beyond = [&](int k, int side) {  // all three vertices strictly beyond side * x_k = R
    for (int i = 0; i < 3; ++i)
      if (side_sign(decide, tri[i], k, side, 1, R) <= 0) return false;
    return true;
  };
  for (int k = 0; k < 2; ++k)
    if (beyond(k, 1) || beyond(k, -1)) return false;
  if (beyond(2, -1)) return false;
  Polygon<NT> buf[3];
  buf[0].n = 3;
  for (int i = 0; i < 3; ++i) buf[0].v[i] = tri[i];
  const Polygon<NT>* cur = &buf[0];
  for (int k = 0; k < 2; ++k)
    for (int side : {1, -1}) cur = clip(cur, k, side, 1, &buf[cur == &buf[1] ? 2 : 1]);
  if (cur->n < 3) return false;
  // Split at the slab's planes: the part above z = R, and the part between.
  bool all_mid = true, all_top = true;
  for (int i = 0; i < cur->n; ++i) {
    const int above = side_sign(decide, cur->v[i], 2, 1, 1, R);                       // sign(z - R)
    if (above > 0 || side_sign(decide, cur->v[i], 2, 1, -1, R) < 0) all_mid = false;  // z < -R
    if (above < 0) all_top = false;
  }
  const Polygon<NT>* top = nullptr;
  const Polygon<NT>* mid = nullptr;
  Polygon<NT> top_buf, mid_buf[2];
  if (all_top) {
    top = cur;
  } else if (all_mid) {
    mid = cur;
  } else {
    top = clip(cur, 2, -1, -1, &top_buf);                             // z >= R
    mid = clip(cur, 2, 1, 1, &mid_buf[0]);                            // z <= R
    mid = clip(mid, 2, -1, 1, &mid_buf[mid == &mid_buf[0] ? 1 : 0]);  // z >= -R
  }
  NT sum(0);
  bool any = false;
  if (top != nullptr && top->n >= 3) {
    NT area(0);
    for (int k = 1; k + 1 < top->n; ++k) area += cross2(top->v[0], top->v[k], top->v[k + 1]);
    sum += NT(6) * R * area;
    any = true;
  }
  if (mid != nullptr && mid->n >= 3) {
    for (int k = 1; k + 1 < mid->n; ++k)
      sum += cross2(mid->v[0], mid->v[k], mid->v[k + 1]) *
             (mid->v[0].x[2] + mid->v[k].x[2] + mid->v[k + 1].x[2] + NT(3) * R);
    any = true;
  }
  if (!any) return false;
  *term = std::move(sum);
  return true;
}

// OBV from the faces' sum: 8 R - sum6 / (6 R^2).
template <class NT>
NT obv_from_sum6(const NT& sum6, const NT& R) {
  return NT(8) * R - sum6 / (NT(6) * R * R);
}

// Which faces to visit: a conservative test, in double, of whether an axis-aligned box may
// reach the column {|T_0|, |T_1| <= R, T_2 >= -R} of a box. False means surely not, whatever
// the rounding of the double frame it is built from (the pad is derived in
// docs/derivations.md, "The column filter").
class ColumnFilter {
 public:
  explicit ColumnFilter(const Obb& box);
  bool operator()(const Aabb& b) const {
    double pad[3];
    return meets(b, pad);
  }
  // Where a triangle that `b` holds (its box) may lie: 0 surely outside the column (b is, by
  // the test above, or the three corners lie surely beyond one side, so that the whole
  // triangle, their convex hull, does), 1 in it but surely beyond the box's top side (T_2 = R),
  // 2 possibly in the box itself. A sliver's box may meet the column where the sliver does not.
  // The corners are tested with b's pads, which bound every point of b.
  int place(const Aabb& b, const Vec3& p0, const Vec3& p1, const Vec3& p2) const {
    double pad[3];
    if (!meets(b, pad)) return 0;
    unsigned beyond = ~0u;  // the sides every corner so far lies surely beyond
    for (const Vec3* p : {&p0, &p1, &p2}) {
      const double d[3] = {(*p)[0] - c_[0], (*p)[1] - c_[1], (*p)[2] - c_[2]};
      unsigned m = 0;
      for (int k = 0; k < 3; ++k) {
        const double t = d[0] * w_[k][0] + d[1] * w_[k][1] + d[2] * w_[k][2];
        if (t > R_ + pad[k]) m |= 1u << (2 * k);
        if (t < -R_ - pad[k]) m |= 1u << (2 * k + 1);
      }
      beyond &= m;
      if (beyond == 0) return 2;
    }
    return (beyond & ~kTopSide) != 0 ? 0 : 1;
  }
  bool flat() const { return flat_; }  // a half extent is 0: the box has no volume

 private:
  // operator()'s test, with the pad of each T_k over b in pad[k] (those up to the side that
  // rejects b, where one does).
  bool meets(const Aabb& b, double* pad) const {
    if (b.empty()) return false;
    double ctr[3], ext[3], size[3], coords = 0;
    for (int i = 0; i < 3; ++i) {
      ctr[i] = 0.5 * (b.lo[i] + b.hi[i]) - c_[i];
      ext[i] = 0.5 * (b.hi[i] - b.lo[i]);
      size[i] = std::abs(b.lo[i]) + std::abs(b.hi[i]) + abs_c_[i];
      coords += size[i];
    }
    for (int k = 0; k < 3; ++k) {
      const double mid = ctr[0] * w_[k][0] + ctr[1] * w_[k][1] + ctr[2] * w_[k][2];
      const double rad = abs_w_[k][0] * ext[0] + abs_w_[k][1] * ext[1] + abs_w_[k][2] * ext[2];
      const double scale = abs_w_[k][0] * size[0] + abs_w_[k][1] * size[1] + abs_w_[k][2] * size[2];
      // The double sums' own rounding, relative 1e-9 of the magnitudes, and 2^-1060 absolute
      // where they are subnormal; then the frame's: w off by w_err per component over
      // sum |p - c| <= coords, and R by R_err.
      pad[k] = 1e-9 * (scale + rad + R_) + 0x1p-1060 * (1 + coords) + w_err_[k] * coords + R_err_;
      if (mid - rad > R_ + pad[k] && k < 2) return false;  // beyond the +side
      if (mid + rad < -R_ - pad[k]) return false;          // beyond the -side (or below)
    }
    return true;
  }
  static constexpr unsigned kTopSide = 1u << 4;  // the +side of T_2: the box's, not the column's

  double c_[3], abs_c_[3];
  double w_[3][3], abs_w_[3][3];
  double R_;
  double w_err_[3];  // bound on |w - W| per row, each component
  double R_err_;
  bool flat_ = false;
};

// The same certified solid with its edge vectors relabelled ({c + sum t_k u_k} is the same set
// in any order) so that its column (T_2 >= -R, along u_0 x u_1) leaves `bounds` (the mesh's)
// soonest: fewer faces lie above the box, as a rule. A heuristic that costs the eight corners
// of `bounds` for each of the six orders; any order gives the same exact OBV.
Obb shortest_column(const Obb& box, const Aabb& bounds);

// A box labelled for its column, and the faces of that column: those that ColumnFilter::place
// puts in it, in the order AabbTree::visit_accepted gives them. A flat box has none.
struct Column {
  Obb box;
  std::vector<int32_t> faces;
  bool flat = false;  // a half extent is 0: no volume, inside or out
};

// The column of the box as labelled.
Column column_of(const Obb& box, const Mesh& mesh, const AabbTree& faces);

// The same relabelling chosen by the faces its column holds, for callers that visit those
// faces (returned with it). The first order as shortest_column ranks them is kept unless its
// faces, gathered nearest the box first, come to outnumber 4 n + 256, n those among them that
// may meet the box itself (which every column holds). Otherwise the order whose column holds the
// fewest, the first in rank among equals, counted in rounds with a doubling cap, so that the search
// costs O(that fewest) however many faces the other columns hold. Unlike shortest_column it is not
// misled by the mesh's shape (along a solid that lies on a diagonal of its bounds, the column that
// leaves the bounds soonest may run through most of the solid).
Column fewest_faces_column(const Obb& box, const Mesh& mesh, const AabbTree& faces);

// The exact OBV of one box by this formula, over the faces of its column (column_of) in `faces`
// (AabbTree::over_faces(mesh)). 0 for a flat box.
Rational box_obv_rational(const Mesh& mesh, const AabbTree& faces, const Obb& box);

}  // namespace vobb::box_clip
