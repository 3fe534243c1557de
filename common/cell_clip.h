// A convex cell's outer volume, vol(C \ X), for a cell C cut out of boxes by half-spaces,
// written once over the number type (DESIGN §2, §4b; derivation in docs/derivations.md,
// "The overlap of two boxes").
//
//   vol(C ∩ X) = sum over the mesh's faces f of sign(f) * vol(C ∩ prism(f)),
// prism(f) the region below f (its shadow's three vertical sides and f's own plane), sign(f)
// the sign of f's normal along the column direction: the signed prism decomposition that the
// exact clipping path runs (exact/clip_solver.cpp), along whichever of ±x, ±y, ±z has the fewest
// faces in the column above C (an orientation-preserving relabelling: the same exact volume).
// Only the faces whose bounds meet that column are visited.
//
// NT is double (a point value, rounded), an interval type (an enclosure) or Rational (exact).
// Every branch is a sign taken through box_clip::ClipTraits<NT>::sign; an interval type's
// specialisation throws where its enclosure does not decide, and the caller then asks again
// in rationals. The interval and rational types clip the cell by each prism in space and,
// with the same decisions, follow the same arithmetic; double takes each prism's volume in the
// plane instead (ChordMap), the builder's estimate.
// Degenerate contacts (a vertex or an edge on a plane) are handled; a cell clipped to nothing
// or to a flat remainder is empty.
#pragma once

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <optional>
#include <type_traits>
#include <utility>
#include <vector>

#include "common/box_frame_clip.h"
#include "common/bvh.h"
#include "common/exact_predicates.h"
#include "common/mesh.h"
#include "common/obb.h"

namespace vobb::cell_clip {

// Thrown where a clip's sides are not those of any plane: the cap's edges do not close into one
// cycle. Exact signs (rationals, or decided enclosures) never make it; rounded doubles can.
struct InconsistentSides {};

// The cap's vertex cycle from its edges: next[b] = a for each kept edge a -> b on the plane (-1
// where none), `edges` of them. Throws InconsistentSides where they do not form one cycle.
std::vector<int> cap_cycle(const std::vector<int>& next, size_t edges);

// The combinatorial step of clipping a cell, shared by every number type's cell. Given the
// faces (vertex cycles, counter-clockwise from outside) of a cell with `n` vertices and each
// vertex's side of a plane (-1 in, 0 on, +1 out; some -1 and some +1), returns the faces of the
// part on the closed inner side, the cut closed by a cap face. `cut(a, b)` (a < b) is called
// once per edge that crosses the plane and returns the id of the crossing point it made (n and
// upward). Vertex ids are those of the cell, then the cut points; compact_faces() renumbers.
template <class Cut>
std::vector<std::vector<int>> clipped_faces(const std::vector<std::vector<int>>& faces,
                                            const std::vector<int>& side, int n, Cut&& cut) {
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

// The volume of a closed convex cell: vertices `v`, faces as vertex cycles counter-clockwise
// from outside. A sum of cones from the first face's first vertex, each a triple product over
// 6; a face through that vertex is a cone of height 0 and adds exactly nothing.
template <class NT>
NT cell_volume(const std::vector<std::array<NT, 3>>& v,
               const std::vector<std::vector<int>>& faces) {
  if (faces.empty()) return NT(0);
  const int apex = faces[0][0];
  const std::array<NT, 3>& p = v[apex];
  NT sum(0);
  for (const std::vector<int>& f : faces) {
    if (std::find(f.begin(), f.end(), apex) != f.end()) continue;
    NT a[3];
    for (int i = 0; i < 3; ++i) a[i] = v[f[0]][i] - p[i];
    for (size_t k = 1; k + 1 < f.size(); ++k) {
      NT b[3], c[3];
      for (int i = 0; i < 3; ++i) {
        b[i] = v[f[k]][i] - p[i];
        c[i] = v[f[k + 1]][i] - p[i];
      }
      sum += a[0] * (b[1] * c[2] - b[2] * c[1]) - a[1] * (b[0] * c[2] - b[2] * c[0]) +
             a[2] * (b[0] * c[1] - b[1] * c[0]);
    }
  }
  return sum / NT(6);
}

// A double interval [lo, hi] holding a value of NT (the value itself for double; see
// NumberBounds' specialisations where NT is declared).
template <class NT>
struct NumberBounds;
template <>
struct NumberBounds<double> {
  static std::pair<double, double> of(double x) { return {x, x}; }
};
template <>
struct NumberBounds<Rational> {
  static std::pair<double, double> of(const Rational& x);  // outward
};

// The closed half-space n . x <= d.
template <class NT>
struct Plane {
  NT n[3];
  NT d;
  Plane complement() const {  // n . x >= d, as (-n) . x <= -d
    return Plane{{-n[0], -n[1], -n[2]}, -d};
  }
};

// The six half-spaces of a box's certified solid (DESIGN §1): |t_k| <= 1 with
// t = [u0 u1 u2]^-1 (p - c), in Cramer form, for the frame's sign sigma = sign(det) != 0.
template <class NT>
std::array<Plane<NT>, 6> box_planes(const box_clip::Frame<NT>& f, int sigma) {
  const NT abs_det = sigma > 0 ? f.det : NT(-f.det);
  std::array<Plane<NT>, 6> out;
  for (int k = 0; k < 3; ++k) {
    NT wc = f.w[k][0] * f.c[0] + f.w[k][1] * f.c[1] + f.w[k][2] * f.c[2];
    if (sigma < 0) wc = -wc;
    Plane<NT>& plus = out[2 * k];
    Plane<NT>& minus = out[2 * k + 1];
    for (int i = 0; i < 3; ++i) {
      plus.n[i] = sigma > 0 ? f.w[k][i] : NT(-f.w[k][i]);
      minus.n[i] = -plus.n[i];
    }
    plus.d = abs_det + wc;
    minus.d = abs_det - wc;
  }
  return out;
}

// Column direction d: 0 +z, 1 -z, 2 +x, 3 -x, 4 +y, 5 -y. The orientation-preserving map that
// sends it to +z (coordinates permuted, one negated where needed: exact in any number type).
template <class T>
std::array<T, 3> to_direction(int d, const T& x, const T& y, const T& z) {
  switch (d) {
    case 0:
      return {x, y, z};
    case 1:
      return {y, x, T(-z)};
    case 2:
      return {y, z, x};
    case 3:
      return {z, y, T(-x)};
    case 4:
      return {z, x, y};
    default:
      return {x, z, T(-y)};
  }
}

// The column above `b` along direction d.
inline Aabb column_of(Aabb b, int d) {
  static constexpr int kAxis[6] = {2, 2, 0, 0, 1, 1};
  if (d % 2 == 0)
    b.hi[kAxis[d]] = INFINITY;
  else
    b.lo[kAxis[d]] = -INFINITY;
  return b;
}

// A bounded convex polyhedron: vertices in NT, faces as vertex cycles counter-clockwise seen
// from outside.
template <class NT>
class Cell {
 public:
  // NT = double only: a vertex whose value n . v - d is within `snap` of the magnitude
  // |n_0 v_0| + |n_1 v_1| + |n_2 v_2| + |d| counts as on the plane. 0 takes the rounded signs as
  // they are; a snap makes rounded signs that contradict each other (InconsistentSides) near a
  // degenerate contact agree, at the price of a volume off by about that much. Kept by every
  // cell made from this one.
  double snap = 0;

  // The box's certified solid, its 8 corners c + sum_k (+-u_k); `orientation` = sign(det).
  static Cell from_box(const box_clip::Frame<NT>& f, int orientation) {
    Cell cell;
    cell.v_.resize(8);
    for (int c = 0; c < 8; ++c)
      for (int i = 0; i < 3; ++i) {
        NT x = f.c[i];
        for (int k = 0; k < 3; ++k) x = ((c >> k) & 1) ? NT(x + f.u[k][i]) : NT(x - f.u[k][i]);
        cell.v_[c][i] = x;
      }
    for (const auto& q : kBoxQuads) {
      if (orientation > 0)
        cell.faces_.push_back({q[0], q[1], q[2], q[3]});
      else
        cell.faces_.push_back({q[3], q[2], q[1], q[0]});
    }
    return cell;
  }
  bool empty() const { return faces_.empty(); }
  const std::vector<std::array<NT, 3>>& vertices() const { return v_; }
  const std::vector<std::vector<int>>& faces() const { return faces_; }

  // Each vertex's side of h: -1 in, 0 on, +1 out; their values n . v - d in *value.
  void sides(const Plane<NT>& h, std::vector<int>* side, std::vector<NT>* value, bool* any_pos,
             bool* any_neg) const {
    const size_t n = v_.size();
    side->resize(n);
    value->resize(n);
    *any_pos = *any_neg = false;
    for (size_t i = 0; i < n; ++i) {
      (*value)[i] = h.n[0] * v_[i][0] + h.n[1] * v_[i][1] + h.n[2] * v_[i][2] - h.d;
      (*side)[i] = box_clip::ClipTraits<NT>::sign((*value)[i]);
      if constexpr (std::is_same_v<NT, double>) {
        if (snap > 0 && (*side)[i] != 0) {
          double mag = std::abs(h.d);
          for (int k = 0; k < 3; ++k) mag += std::abs(h.n[k] * v_[i][k]);
          if (std::abs((*value)[i]) <= snap * mag) (*side)[i] = 0;
        }
      }
      *any_pos |= (*side)[i] > 0;
      *any_neg |= (*side)[i] < 0;
    }
  }

  // The part in h.
  Cell clipped(const Plane<NT>& h) const {
    if (faces_.empty()) return Cell();
    std::vector<int> side;
    std::vector<NT> value;
    bool any_pos, any_neg;
    sides(h, &side, &value, &any_pos, &any_neg);
    return clipped_with(side, value, any_pos, any_neg);
  }

  // The same, with the vertices' sides known (sides()).
  Cell clipped_with(const std::vector<int>& side, const std::vector<NT>& value, bool any_pos,
                    bool any_neg) const {
    if (!any_pos) return *this;
    Cell out;
    out.snap = snap;
    if (!any_neg) return out;  // nothing strictly inside: empty, or flat on the plane
    const int n = static_cast<int>(v_.size());
    std::vector<std::array<NT, 3>> made;  // the cut points, ids n and upward
    std::vector<std::vector<int>> kept = clipped_faces(faces_, side, n, [&](int lo, int hi) {
      const NT t = value[lo] / (value[lo] - value[hi]);
      std::array<NT, 3>& p = made.emplace_back();
      for (int i = 0; i < 3; ++i) p[i] = v_[lo][i] + t * (v_[hi][i] - v_[lo][i]);
      return n + static_cast<int>(made.size()) - 1;
    });
    if (kept.size() < 4) return out;  // cannot enclose volume
    const std::vector<int> old = compact_faces(&kept, n + made.size());
    out.v_.reserve(old.size());
    for (int k : old) out.v_.push_back(k < n ? v_[k] : made[k - n]);
    out.faces_ = std::move(kept);
    return out;
  }

  // The cell under to_direction(d).
  Cell mapped(int d) const {
    Cell out;
    out.snap = snap;
    out.faces_ = faces_;
    out.v_.reserve(v_.size());
    for (const auto& p : v_) out.v_.push_back(to_direction(d, p[0], p[1], p[2]));
    return out;
  }

  NT volume() const { return cell_volume(v_, faces_); }

  // Axis-aligned bounds holding the cell's vertices as NumberBounds encloses them.
  Aabb bounds() const {
    Aabb b;
    for (const auto& p : v_)
      for (int i = 0; i < 3; ++i) {
        const auto [lo, hi] = NumberBounds<NT>::of(p[i]);
        b.lo[i] = std::min(b.lo[i], lo);
        b.hi[i] = std::max(b.hi[i], hi);
      }
    return b;
  }

 private:
  std::vector<std::array<NT, 3>> v_;
  std::vector<std::vector<int>> faces_;
};

// The double path's prism volumes, in the plane (docs/derivations.md, "Shared outer volume"):
// over the cell's shadow the chord runs from z_b to z_t, and a face's prism holds
// clamp(z_f - z_b, 0, z_t - z_b) = min(z_f, z_t) - min(z_f, z_b) of it. The upper facets'
// shadows tile the cell's shadow, and z_t is linear on each, as z_b is on the lower facets'. So
// the face's term is the sum over the upper facets of the integral of min(z_f, z_t) over the
// facet's shadow clipped to the face's, less the same over the lower facets; each is cut by the
// line z_f = z_t into two convex parts with a linear integrand, whose integral is a fan's
// triangles' areas times the means at their corners. Only the face's edges and that line clip:
// a facet's noisy short edges (rounded cut points of the cell) never do. Decisions are taken in
// rounded doubles: an estimate (the interval and rational paths clip the cell in space).
class ChordMap {
 public:
  explicit ChordMap(const Cell<double>& cell) {
    const auto& v = cell.vertices();
    z_ref_ = INFINITY;
    for (const auto& p : v) z_ref_ = std::min(z_ref_, p[2]);
    for (const std::vector<int>& f : cell.faces()) {
      // The facet's normal by Newell's sum; its z sign says upper (> 0) or lower (< 0).
      double n[3] = {0, 0, 0};
      for (size_t k = 0; k < f.size(); ++k) {
        const auto& a = v[f[k]];
        const auto& b = v[f[(k + 1) % f.size()]];
        n[0] += (a[1] - b[1]) * (a[2] + b[2]);
        n[1] += (a[2] - b[2]) * (a[0] + b[0]);
        n[2] += (a[0] - b[0]) * (a[1] + b[1]);
      }
      const double len = std::abs(n[0]) + std::abs(n[1]) + std::abs(n[2]);
      if (!(std::abs(n[2]) > 1e-9 * len)) continue;  // (nearly) vertical: its shadow is no area
      if (f.size() + 5 > kCapacity) throw InconsistentSides();  // no facet of a clipped box
      Facet facet;
      facet.upper = n[2] > 0;
      // The shadow's corners, counter-clockwise (a lower facet's are seen from below), with the
      // facet's height there.
      facet.shadow.n = static_cast<int>(f.size());
      for (size_t k = 0; k < f.size(); ++k) {
        const auto& a = v[f[facet.upper ? k : f.size() - 1 - k]];
        facet.shadow.p[k] = {a[0], a[1], a[2] - z_ref_, 0};
        if (k == 0) facet.lo = facet.hi = {a[0], a[1]};
        for (int i = 0; i < 2; ++i) {
          facet.lo[i] = std::min(facet.lo[i], a[i]);
          facet.hi[i] = std::max(facet.hi[i], a[i]);
        }
      }
      facets_.push_back(facet);
    }
  }

  // The face's signed vol(cell ∩ prism(face)): q its corners (the column along +z), `sign` the
  // sign of its normal's z (+-1).
  double prism_volume(const Vec3 (&q)[3], int sign) const {
    double lo[2], hi[2];
    for (int i = 0; i < 2; ++i) {
      lo[i] = std::min({q[0][i], q[1][i], q[2][i]});
      hi[i] = std::max({q[0][i], q[1][i], q[2][i]});
    }
    // The face's height over the plane, from its first corner: accurate within its shadow.
    const double e1x = q[1][0] - q[0][0], e1y = q[1][1] - q[0][1], e1z = q[1][2] - q[0][2];
    const double e2x = q[2][0] - q[0][0], e2y = q[2][1] - q[0][1], e2z = q[2][2] - q[0][2];
    const double nz = e1x * e2y - e1y * e2x;
    // Rounded to 0 only where the shadow's area is round-off of the face's: nothing to add.
    if (nz == 0) return 0;
    const double gx = -(e1y * e2z - e1z * e2y) / nz, gy = -(e1z * e2x - e1x * e2z) / nz;
    const double z0 = q[0][2] - z_ref_;
    // The face's edges as lines a x + b y + c >= 0 on its inner side.
    double line[3][3];
    for (int k = 0; k < 3; ++k) {
      const Vec3& a = q[k];
      const Vec3& b = q[(k + 1) % 3];
      line[k][0] = -sign * (b[1] - a[1]);
      line[k][1] = sign * (b[0] - a[0]);
      line[k][2] = -(line[k][0] * a[0] + line[k][1] * a[1]);
    }
    double sum = 0;
    Poly buf[2];
    for (const Facet& facet : facets_) {
      if (hi[0] < facet.lo[0] || lo[0] > facet.hi[0] || hi[1] < facet.lo[1] || lo[1] > facet.hi[1])
        continue;
      // The facet's shadow within the face's.
      const Poly* part = &facet.shadow;
      for (int k = 0; k < 3 && part->n > 0; ++k) {
        const double* l = line[k];
        Poly* cut = part == &buf[0] ? &buf[1] : &buf[0];
        if (part->clip([l](const Pt& p) { return l[0] * p.x + l[1] * p.y + l[2]; }, cut))
          part = cut;
      }
      if (part->n == 0) continue;
      Poly* with_face = part == &buf[0] ? &buf[0] : &buf[1];
      if (part != with_face) {  // the whole facet: a copy to write f into
        with_face->n = part->n;
        std::copy(part->p, part->p + part->n, with_face->p);
      }
      for (int k = 0; k < with_face->n; ++k) {
        Pt& p = with_face->p[k];
        p.f = z0 + gx * (p.x - q[0][0]) + gy * (p.y - q[0][1]);
      }
      // min(z_f, z_facet): z_f where z_f <= z_facet, else z_facet (the rest, strictly, so that a
      // face on the facet's plane counts once).
      Poly below, above;
      double term = 0;
      if (with_face->clip([](const Pt& p) { return p.z - p.f; }, &below))
        term += below.integral([](const Pt& p) { return p.f; });
      else
        term += with_face->integral([](const Pt& p) { return p.f; });
      if (with_face->clip([](const Pt& p) { return p.f - p.z; }, &above, true))
        term += above.integral([](const Pt& p) { return p.z; });
      else
        term += with_face->integral([](const Pt& p) { return p.z; });
      sum += facet.upper ? term : -term;
    }
    return sign * sum;
  }

 private:
  // A facet of a box clipped by a few planes has a few corners; one clipped by three lines and
  // then one more gains at most one corner each.
  static constexpr int kCapacity = 48;
  // A point of the shadow with the facet's height z and the face's f there (above z_ref_).
  struct Pt {
    double x, y, z, f;
  };
  // A convex polygon of the shadow, counter-clockwise.
  struct Poly {
    Pt p[kCapacity];
    int n = 0;
    // The part where f >= 0 (f > 0 if strict; f linear, given per corner), in the same cyclic
    // order, into *out; false, and *out untouched, where that is all of it. Throws
    // InconsistentSides where the rounded values change sign more often than a convex
    // polygon's can.
    template <class F>
    bool clip(const F& fn, Poly* out, bool strict = false) const {
      double val[kCapacity];
      bool in[kCapacity];
      bool all = true;
      for (int i = 0; i < n; ++i) {
        val[i] = fn(p[i]);
        all &= in[i] = strict ? val[i] > 0 : val[i] >= 0;
      }
      if (all) return false;
      out->n = 0;
      for (int i = 0; i < n; ++i) {
        if (out->n + 2 > kCapacity) throw InconsistentSides();
        const int j = (i + 1) % n;
        const Pt& a = p[i];
        const Pt& b = p[j];
        if (in[i]) out->p[out->n++] = a;
        if (in[i] != in[j]) {
          const double s = val[i] / (val[i] - val[j]);
          out->p[out->n++] = {a.x + s * (b.x - a.x), a.y + s * (b.y - a.y), a.z + s * (b.z - a.z),
                              a.f + s * (b.f - a.f)};
        }
      }
      if (out->n < 3) out->n = 0;
      return true;
    }
    // The integral of v (linear, given per corner) over the polygon: per fan triangle, its
    // signed area times the mean of v at its corners.
    template <class V>
    double integral(const V& v) const {
      double sum = 0;
      for (int k = 1; k + 1 < n; ++k) {
        const Pt &a = p[0], &b = p[k], &c = p[k + 1];
        const double twice = (b.x - a.x) * (c.y - a.y) - (b.y - a.y) * (c.x - a.x);
        sum += twice * (v(a) + v(b) + v(c));
      }
      return sum / 6;
    }
  };
  struct Facet {
    bool upper = false;
    Poly shadow;
    std::array<double, 2> lo, hi;  // the shadow's bounds
  };
  double z_ref_ = 0;  // the cell's lowest z: heights are taken above it
  std::vector<Facet> facets_;
};

// The interval and rational paths' term of one face (corners q, the column along +z, `sign`
// the sign of its normal's z): the signed vol(cell ∩ prism(face)), the cell clipped in space
// by the prism's four half-spaces. A prism that holds the whole cell adds its sign to *whole
// instead (the cell's volume, once, at the end). side and value are scratch.
template <class NT>
NT prism_volume_in_space(const Cell<NT>& cell, const Vec3 (&q)[3], int sign, long* whole,
                         std::vector<int>* side, std::vector<NT>* value) {
  // The prism's 4 half-spaces: the 3 vertical sides through its edges, then below its plane.
  Plane<NT> h[4];
  for (int k = 0; k < 3; ++k) {
    const Vec3& a = q[k];
    const Vec3& b = q[(k + 1) % 3];
    h[k].n[0] = NT(b[1]) - NT(a[1]);
    h[k].n[1] = NT(a[0]) - NT(b[0]);
    h[k].n[2] = NT(0);
    if (sign < 0) h[k].n[0] = -h[k].n[0], h[k].n[1] = -h[k].n[1];
    h[k].d = h[k].n[0] * NT(a[0]) + h[k].n[1] * NT(a[1]);
  }
  {
    NT e1[3], e2[3];
    for (int i = 0; i < 3; ++i)
      e1[i] = NT(q[1][i]) - NT(q[0][i]), e2[i] = NT(q[2][i]) - NT(q[0][i]);
    const NT nrm[3] = {e1[1] * e2[2] - e1[2] * e2[1], e1[2] * e2[0] - e1[0] * e2[2],
                       e1[0] * e2[1] - e1[1] * e2[0]};
    for (int i = 0; i < 3; ++i) h[3].n[i] = sign > 0 ? nrm[i] : NT(-nrm[i]);
    h[3].d = h[3].n[0] * NT(q[0][0]) + h[3].n[1] * NT(q[0][1]) + h[3].n[2] * NT(q[0][2]);
  }
  const Plane<NT>* cutting[4];
  int n_cutting = 0;
  for (int k = 0; k < 4; ++k) {
    bool any_pos, any_neg;
    cell.sides(h[k], side, value, &any_pos, &any_neg);
    if (!any_neg) return NT(0);  // beyond or on the plane: the prism adds no volume
    if (any_pos) cutting[n_cutting++] = &h[k];
  }
  if (n_cutting == 0) {  // the whole cell, added once at the end
    *whole += sign;
    return NT(0);
  }
  Cell<NT> piece = cell.clipped(*cutting[0]);
  for (int k = 1; k < n_cutting && !piece.empty(); ++k) piece = piece.clipped(*cutting[k]);
  if (piece.empty()) return NT(0);
  return sign > 0 ? piece.volume() : NT(-piece.volume());
}

// vol(cell \ X): the cell's volume less the signed prism decomposition of X within it, over
// the faces of `faces` (AabbTree::over_faces(mesh)) that meet the column above `reach`, a
// double box that holds the exact cell. The direction and the faces are chosen from `reach`
// alone, so every number type takes the same ones.
template <class NT>
NT outside_volume(const Mesh& mesh, const AabbTree& faces, const Cell<NT>& cell_xyz,
                  const Aabb& reach) {
  if (cell_xyz.empty()) return NT(0);
  const NT vol = cell_xyz.volume();
  const Aabb& bounds = reach;
  int dir = 0;
  size_t fewest = SIZE_MAX;
  for (int d = 0; d < 6; ++d) {
    size_t n = 0;
    const Aabb column = column_of(bounds, d);
    // Counted only until it reaches the fewest so far, which it then cannot beat.
    faces.visit_accepted([&](const Aabb& b) { return n < fewest && column.overlaps(b); },
                         [&](int32_t) { ++n; });
    if (n < fewest) fewest = n, dir = d;
  }
  const Cell<NT> cell = cell_xyz.mapped(dir);
  std::optional<ChordMap> chords;
  if constexpr (std::is_same_v<NT, double>) chords.emplace(cell);
  NT inside(0);
  long whole = 0;
  std::vector<int> side;
  std::vector<NT> value;
  const Aabb column = column_of(bounds, dir);
  faces.visit_accepted([&](const Aabb& b) { return column.overlaps(b); },
                       [&](int32_t f) {
                         Vec3 q[3];
                         for (int k = 0; k < 3; ++k) {
                           const Vec3& p = mesh.corner(f, k);
                           const std::array<double, 3> m = to_direction(dir, p[0], p[1], p[2]);
                           q[k] = Vec3(m[0], m[1], m[2]);
                         }
                         // The sign of the face normal's z, exactly; a vertical face bounds no
                         // column.
                         const int sign = orient2d(q[0], q[1], q[2], 0, 1);
                         if (sign == 0) return;
                         if constexpr (std::is_same_v<NT, double>)
                           inside += chords->prism_volume(q, sign);
                         else
                           inside += prism_volume_in_space(cell, q, sign, &whole, &side, &value);
                       });
  if (whole != 0) inside += NT(static_cast<double>(whole)) * vol;
  return vol - inside;
}

// The cells that make up S = B ∩ (E_0 ∪ ... ∪ E_{k-1}): B split against each E_i in turn, the
// part of what no earlier E covers that lies in E_i being a cell of S (the clipping path's
// split, exact/clip_solver.cpp). Disjoint; empty where B is flat or meets none of them.
template <class NT>
std::vector<Cell<NT>> shared_cells(const Obb& box, const std::vector<Obb>& earlier,
                                   double snap = 0) {
  const box_clip::Frame<NT> fb = box_clip::make_frame<NT>(box);
  const int orientation = box_clip::ClipTraits<NT>::sign(fb.det);
  std::vector<Cell<NT>> shared;
  if (orientation == 0) return shared;
  std::vector<Cell<NT>> pieces{Cell<NT>::from_box(fb, orientation)};
  pieces[0].snap = snap;
  std::vector<int> side;
  std::vector<NT> value;
  for (const Obb& e : earlier) {
    const box_clip::Frame<NT> fe = box_clip::make_frame<NT>(e);
    const int sigma = box_clip::ClipTraits<NT>::sign(fe.det);
    if (sigma == 0) continue;
    const std::array<Plane<NT>, 6> hs = box_planes(fe, sigma);
    std::vector<Cell<NT>> next;
    for (Cell<NT>& p : pieces) {
      Cell<NT> rest = std::move(p);
      for (const Plane<NT>& h : hs) {
        bool any_pos, any_neg;
        rest.sides(h, &side, &value, &any_pos, &any_neg);
        if (!any_pos) continue;  // nothing of `rest` beyond this face
        if (!any_neg) {          // all of it beyond or on the plane: it stays whole
          next.push_back(std::move(rest));
          rest = Cell<NT>();
          break;
        }
        Cell<NT> beyond = rest.clipped(h.complement());
        if (!beyond.empty()) next.push_back(std::move(beyond));
        rest = rest.clipped_with(side, value, any_pos, any_neg);
        if (rest.empty()) break;
      }
      if (!rest.empty()) shared.push_back(std::move(rest));
    }
    pieces = std::move(next);
    if (pieces.empty()) break;
  }
  return shared;
}

// A double box around the cell whose vertices these are: NumberBounds' bounds, which hold the
// exact cell for exact and interval vertices, grown by 1e-9 of their magnitude. For double
// vertices, which are rounded, that margin is far beyond their usual rounding but no proof
// where a cut meets a face at a grazing angle: the double path is an estimate.
template <class NT>
Aabb reach_of(const Cell<NT>& cell) {
  Aabb b = cell.bounds();
  for (int i = 0; i < 3; ++i) {
    const double pad = 1e-9 * (std::abs(b.lo[i]) + std::abs(b.hi[i])) + 1e-300;
    b.lo[i] -= pad;
    b.hi[i] += pad;
  }
  return b;
}

// vol(S \ X) for S = B ∩ (E_0 ∪ ... ∪ E_{k-1}): what B shares with the earlier boxes, outside
// the solid. With one earlier box, vol((B ∩ E_0) \ X).
template <class NT>
NT shared_outside_volume(const Mesh& mesh, const AabbTree& faces, const Obb& box,
                         const std::vector<Obb>& earlier, double snap = 0) {
  NT total(0);
  for (const Cell<NT>& cell : shared_cells<NT>(box, earlier, snap))
    total += outside_volume(mesh, faces, cell, reach_of(cell));
  return total;
}

}  // namespace vobb::cell_clip
