#include "common/box_frame_clip.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <optional>
#include <unordered_map>

namespace vobb::box_clip {
namespace {

// Sum of the absolute components: at least the Euclidean norm, and |a_i b_j| + |a_j b_i| <=
// l1(a) l1(b) for every pair of components.
double l1(const double* v) { return std::abs(v[0]) + std::abs(v[1]) + std::abs(v[2]); }

// One unit of rounding in any rounding mode (directed rounding errs by up to 2^-52).
constexpr double kEps = 0x1p-52;

}  // namespace

ColumnFilter::ColumnFilter(const Obb& box) {
  const Frame<double> f = make_frame<double>(box);
  flat_ = box.half[0] == 0 || box.half[1] == 0 || box.half[2] == 0;
  for (int k = 0; k < 3; ++k) {
    c_[k] = box.center[k];
    abs_c_[k] = std::abs(c_[k]);
    for (int i = 0; i < 3; ++i) {
      w_[k][i] = f.w[k][i];
      abs_w_[k][i] = std::abs(w_[k][i]);
    }
  }
  R_ = std::abs(f.det);
  // u carries 1 rounding, each w component 2 more over |a1 b2| + |a2 b1| <= l1(u') l1(u''),
  // det 3 more over l1(u0) (l1(w0) + w_err): 16 eps and 32 eps leave twice that room
  // (docs/derivations.md, "The column filter").
  double nu[3];
  for (int k = 0; k < 3; ++k) nu[k] = l1(f.u[k]);
  for (int k = 0; k < 3; ++k) w_err_[k] = 16 * kEps * nu[(k + 1) % 3] * nu[(k + 2) % 3];
  R_err_ = 32 * kEps * nu[0] * nu[1] * nu[2];
}

namespace {

constexpr int kOrders[6][3] = {{0, 1, 2}, {1, 0, 2}, {1, 2, 0}, {2, 1, 0}, {2, 0, 1}, {0, 2, 1}};

// The box with its edges in order o of kOrders.
Obb relabelled(const Obb& box, int o) {
  Obb out = box;
  for (int n = 0; n < 3; ++n) {
    out.axes[n] = box.axes[kOrders[o][n]];
    out.half[n] = box.half[kOrders[o][n]];
  }
  return out;
}

// How far `bounds` reaches beyond the box along the column of order o.
double bounds_reach(const Obb& box, const Aabb& bounds, int o) {
  const int i = kOrders[o][0], j = kOrders[o][1], k = kOrders[o][2];
  const Vec3 d = box.axes[i].cross(box.axes[j]);
  double reach = -INFINITY;
  for (int corner = 0; corner < 8; ++corner) {
    const Vec3 p((corner & 1) ? bounds.hi[0] : bounds.lo[0],
                 (corner & 2) ? bounds.hi[1] : bounds.lo[1],
                 (corner & 4) ? bounds.hi[2] : bounds.lo[2]);
    reach = std::max(reach, (p - box.center).dot(d));
  }
  return reach - box.half[k] * std::abs(box.axes[k].dot(d));
}

// The orders by the reach of `bounds` along their columns, shortest first (stable).
std::array<int, 6> ranked(const Obb& box, const Aabb& bounds) {
  double reach[6];
  std::array<int, 6> order;
  for (int o = 0; o < 6; ++o) reach[o] = bounds_reach(box, bounds, o), order[o] = o;
  std::stable_sort(order.begin(), order.end(), [&](int a, int b) { return reach[a] < reach[b]; });
  return order;
}

}  // namespace

Obb shortest_column(const Obb& box, const Aabb& bounds) {
  return relabelled(box, ranked(box, bounds)[0]);
}

Obb fewest_faces_column(const Obb& box, const Mesh& mesh, const AabbTree& faces) {
  const std::array<int, 6> order = ranked(box, faces.bounds());
  std::array<std::optional<ColumnFilter>, 6> filter;
  for (int o = 0; o < 6; ++o) filter[o].emplace(relabelled(box, order[o]));
  if (filter[0]->flat()) return box;  // no volume in any order: no face is visited
  // The faces of `faces` in column o, counted until they reach `cap`.
  auto count = [&](int o, size_t cap) {
    const ColumnFilter& f = *filter[o];
    size_t n = 0;
    faces.visit_accepted(
        [&](const Aabb& b) { return n < cap && f(b); },
        [&](int32_t i) {
          if (f.meets_triangle(mesh.corner(i, 0), mesh.corner(i, 1), mesh.corner(i, 2))) ++n;
        });
    return n;
  };
  // The faces that may meet the box itself, which every column holds: the first in rank is
  // taken when its column holds few more.
  Aabb reach;
  for (int i = 0; i < 3; ++i) {
    double e = 0;
    for (int k = 0; k < 3; ++k) e += box.half[k] * std::abs(box.axes[k][i]);
    e += 1e-9 * (e + std::abs(box.center[i]));  // the sums' rounding, with room
    reach.lo[i] = box.center[i] - e;
    reach.hi[i] = box.center[i] + e;
  }
  size_t in_box = 0;
  faces.visit_accepted(
      [&](const Aabb& b) { return reach.overlaps(b); },
      [&](int32_t i) {
        if (filter[0]->may_meet_box(mesh.corner(i, 0), mesh.corner(i, 1), mesh.corner(i, 2)))
          ++in_box;
      });
  const size_t enough = 2 * in_box + 64;
  if (count(0, enough + 1) <= enough) return relabelled(box, order[0]);
  // Otherwise the fewest, in rounds that count every order up to a cap doubled each round: once
  // an order's count ends below the cap, the fewest is among those that ended (the others
  // reached it), the first in rank among equals. A round costs at most six caps of faces, so
  // the search costs O(the fewest), however many faces the other columns hold.
  for (size_t cap = enough;; cap *= 2) {
    int best = -1;
    size_t fewest = cap;
    for (int o = 0; o < 6; ++o) {
      const size_t n = count(o, fewest);
      if (n < fewest) fewest = n, best = o;
    }
    if (best >= 0) return relabelled(box, order[best]);
  }
}

Rational box_obv_rational(const Mesh& mesh, const AabbTree& faces, const Obb& box) {
  const ColumnFilter filter(box);
  if (filter.flat()) return Rational(0);  // a flat box has no volume, inside or out
  const Frame<Rational> frame = make_frame<Rational>(box);
  if (sgn(frame.det) == 0) return Rational(0);
  const Rational R = abs(frame.det);
  std::unordered_map<int32_t, Point<Rational>> tmap;  // faces share vertices
  auto to_t = [&](int32_t v) -> const Point<Rational>& {
    auto it = tmap.find(v);
    if (it != tmap.end()) return it->second;
    return tmap.emplace(v, to_frame(frame, mesh.vertices[v])).first->second;
  };
  std::vector<Rational> terms;
  faces.visit_accepted(filter, [&](int32_t f) {
    if (!filter.meets_triangle(mesh.corner(f, 0), mesh.corner(f, 1), mesh.corner(f, 2))) return;
    const Point<Rational> tri[3] = {to_t(mesh.faces[f][0]), to_t(mesh.faces[f][1]),
                                    to_t(mesh.faces[f][2])};
    Rational t;
    if (face_term6(tri, R, &t) && sgn(t) != 0) terms.push_back(std::move(t));
  });
  return obv_from_sum6(sum_pairwise(terms), R);
}

}  // namespace vobb::box_clip
