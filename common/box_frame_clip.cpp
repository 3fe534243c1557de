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

int frame_exponent(const Obb& box) {
  int sum = 0;
  for (int k = 0; k < 3; ++k) {
    if (!(box.half[k] > 0)) return 0;
    sum += std::ilogb(box.half[k]);
  }
  return sum >= 0 ? sum / 3 : -((-sum + 2) / 3);  // floor(sum / 3)
}

Obb shortest_column(const Obb& box, const Aabb& bounds) {
  return relabelled(box, ranked(box, bounds)[0]);
}

namespace {

// Calls visit(i, place) for every position i in faces.order() whose face `f` places in its
// column (ColumnFilter::place > 0), descending only into nodes whose boxes f accepts, while
// more() holds (tested at each node). Left children first, so that positions come in
// increasing order, or with `near` the child whose box's centre is nearer *near first.
template <class More, class Visit>
void walk(const Mesh& mesh, const AabbTree& faces, const ColumnFilter& f, const Vec3* near,
          const More& more, const Visit& visit) {
  const std::vector<AabbTree::Node>& nodes = faces.nodes();
  const std::vector<int32_t>& prim = faces.order();
  if (nodes.empty()) return;
  int32_t stack[128];  // median splits: depth below 64, one waiting sibling per level
  int top = 0;
  stack[top++] = 0;
  while (top > 0 && more()) {
    const AabbTree::Node& n = nodes[stack[--top]];
    if (!f(n.bounds)) continue;
    if (n.count > 0) {
      for (int32_t i = n.first; i < n.first + n.count; ++i) {
        const int32_t g = prim[i];
        const int p = f.place(faces.primitive_bounds(g), mesh.corner(g, 0), mesh.corner(g, 1),
                              mesh.corner(g, 2));
        if (p > 0) visit(i, p);
      }
    } else {
      bool left_first = true;
      if (near != nullptr) {
        const Aabb &l = nodes[n.first].bounds, &r = nodes[n.first + 1].bounds;
        left_first =
            (l.lo + l.hi - 2 * *near).squaredNorm() <= (r.lo + r.hi - 2 * *near).squaredNorm();
      }
      stack[top++] = left_first ? n.first + 1 : n.first;  // popped second
      stack[top++] = left_first ? n.first : n.first + 1;
    }
  }
}

}  // namespace

Column fewest_faces_column(const Obb& box, const Mesh& mesh, const AabbTree& faces) {
  const std::array<int, 6> order = ranked(box, faces.bounds());
  std::array<std::optional<ColumnFilter>, 6> filter;
  for (int o = 0; o < 6; ++o) filter[o].emplace(relabelled(box, order[o]));
  Column out{relabelled(box, order[0]), {}, filter[0]->flat()};
  if (out.flat) return out;  // no volume in any order: no face is visited
  // The first column's faces as positions in faces.order() (sorted, they are visit_accepted's
  // order), gathered nearest the box first, until they outnumber those that may meet the box
  // more than allowed.
  std::vector<int32_t> pos;
  size_t in_box = 0;
  bool kept = true;
  walk(
      mesh, faces, *filter[0], &box.center, [&] { return kept; },
      [&](int32_t i, int p) {
        pos.push_back(i);
        in_box += p == 2;
        kept = pos.size() <= 4 * in_box + 256;
      });
  if (kept) {
    std::sort(pos.begin(), pos.end());
    out.faces.reserve(pos.size());
    for (int32_t i : pos) out.faces.push_back(faces.order()[i]);
    return out;
  }
  // Rounds that count every order's faces up to a cap doubled each round: once an order's
  // count ends below the cap, the fewest is among those that ended (the others reached it),
  // the first in rank among equals. A round costs at most six caps of faces.
  int best = -1;
  for (size_t cap = 256; best < 0; cap *= 2) {
    size_t fewest = cap;
    for (int o = 0; o < 6; ++o) {
      size_t n = 0;
      walk(
          mesh, faces, *filter[o], nullptr, [&] { return n < fewest; }, [&](int32_t, int) { ++n; });
      if (n < fewest) fewest = n, best = o;
    }
  }
  return column_of(relabelled(box, order[best]), mesh, faces);
}

Column column_of(const Obb& box, const Mesh& mesh, const AabbTree& faces) {
  const ColumnFilter f(box);
  Column out{box, {}, f.flat()};
  if (out.flat) return out;
  walk(
      mesh, faces, f, nullptr, [] { return true; },
      [&](int32_t i, int) { out.faces.push_back(faces.order()[i]); });
  return out;
}

Rational box_obv_rational(const Mesh& mesh, const AabbTree& faces, const Obb& box) {
  const Column column = column_of(box, mesh, faces);
  if (column.flat) return Rational(0);  // a flat box has no volume, inside or out
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
  for (const int32_t f : column.faces) {
    const Point<Rational> tri[3] = {to_t(mesh.faces[f][0]), to_t(mesh.faces[f][1]),
                                    to_t(mesh.faces[f][2])};
    Rational t;
    if (face_term6(tri, R, &t) && sgn(t) != 0) terms.push_back(std::move(t));
  }
  return obv_from_sum6(sum_pairwise(terms), R);
}

}  // namespace vobb::box_clip
