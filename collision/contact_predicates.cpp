// Collider tests (see contact_predicates.h). Compiled with -ffp-contract=off: the interval
// arithmetic below assumes each + - * is rounded to nearest on its own (no fused multiply-add).
#include "collision/contact_predicates.h"

#include <algorithm>
#include <atomic>
#include <cmath>
#include <limits>

#include "common/exact_predicates.h"

namespace vobb::collision {
namespace {

constexpr double kU = std::numeric_limits<double>::epsilon() / 2;  // unit round-off, 2^-53
constexpr double kInf = std::numeric_limits<double>::infinity();

std::atomic<uint64_t> g_exact_fallbacks{0};

// ---- outward-rounded interval arithmetic --------------------------------------------------
// A result rounded to nearest is within half an ulp of the true value; one nextafter step
// outwards therefore encloses it (at a binade boundary the step is the smaller ulp, which is
// still at least half of the true value's ulp; underflow is covered by the step to the
// smallest subnormal). So every Interval holds the exact value of what it stands for.
struct Interval {
  double lo, hi;
};
double down(double x) { return std::nextafter(x, -kInf); }
double up(double x) { return std::nextafter(x, kInf); }
Interval point(double x) { return {x, x}; }
Interval operator+(Interval a, Interval b) { return {down(a.lo + b.lo), up(a.hi + b.hi)}; }
Interval operator-(Interval a, Interval b) { return {down(a.lo - b.hi), up(a.hi - b.lo)}; }
Interval operator-(Interval a) { return {-a.hi, -a.lo}; }
Interval operator*(Interval a, Interval b) {
  const double p[4] = {a.lo * b.lo, a.lo * b.hi, a.hi * b.lo, a.hi * b.hi};
  return {down(std::min(std::min(p[0], p[1]), std::min(p[2], p[3]))),
          up(std::max(std::max(p[0], p[1]), std::max(p[2], p[3])))};
}
Interval iabs(Interval a) {
  if (a.lo >= 0) return a;
  if (a.hi <= 0) return {-a.hi, -a.lo};
  return {0.0, std::max(-a.lo, a.hi)};
}
Interval imin(Interval a, Interval b) { return {std::min(a.lo, b.lo), std::min(a.hi, b.hi)}; }
Interval imax(Interval a, Interval b) { return {std::max(a.lo, b.lo), std::max(a.hi, b.hi)}; }
// Sign of a separation value: +1 surely > 0 (separated), -1 surely <= 0, 0 undecided.
int sep_sign(Interval s) { return s.lo > 0 ? 1 : (s.hi <= 0 ? -1 : 0); }

Rational iabs(const Rational& a) { return a < 0 ? Rational(-a) : a; }
Rational imin(const Rational& a, const Rational& b) { return a < b ? a : b; }
Rational imax(const Rational& a, const Rational& b) { return a < b ? b : a; }
int sep_sign(const Rational& s) { return s > 0 ? 1 : -1; }

// ---- separating-axis test, box (parallelepiped) against triangle -------------------------
// T is Interval (filter) or Rational (exact). Inputs: the box centre c, its half-edge vectors
// u_k = half_k axes_k, and the triangle p0 p1 p2. The candidate axes are complete for two
// convex polytopes: the parallelepiped's face normals u_{k+1} x u_{k+2}, the triangle's normal,
// and the 9 cross products of a box edge with a triangle edge (a zero axis separates nothing,
// so degenerate crosses are harmless). Along an axis L the box projects onto c.L +- sum_k |u_k.L|
// (its support function, exact for any parallelepiped), the triangle onto [min p_i.L,
// max p_i.L]. Closed sets: touching counts as touching. Returns +1 separated, -1 touching,
// 0 undecided (Interval only).
template <class T>
void sub3(const T a[3], const T b[3], T out[3]) {
  for (int i = 0; i < 3; ++i) out[i] = a[i] - b[i];
}
template <class T>
void cross3(const T a[3], const T b[3], T out[3]) {
  out[0] = a[1] * b[2] - a[2] * b[1];
  out[1] = a[2] * b[0] - a[0] * b[2];
  out[2] = a[0] * b[1] - a[1] * b[0];
}
template <class T>
T dot3(const T a[3], const T b[3]) {
  return a[0] * b[0] + a[1] * b[1] + a[2] * b[2];
}

template <class T>
int sat_box_triangle(const T c[3], const T u[3][3], const T p[3][3]) {
  T d[3][3], e[3][3];
  for (int i = 0; i < 3; ++i) sub3(p[i], c, d[i]);
  for (int j = 0; j < 3; ++j) sub3(p[(j + 1) % 3], p[j], e[j]);
  bool undecided = false;
  auto axis = [&](const T L[3]) {
    const T r = iabs(dot3(u[0], L)) + iabs(dot3(u[1], L)) + iabs(dot3(u[2], L));
    const T d0 = dot3(d[0], L), d1 = dot3(d[1], L), d2 = dot3(d[2], L);
    const T lo = imin(imin(d0, d1), d2), hi = imax(imax(d0, d1), d2);
    const T sep = imax(lo - r, -hi - r);
    const int s = sep_sign(sep);
    if (s == 0) undecided = true;
    return s == 1;
  };
  T L[3];
  for (int k = 0; k < 3; ++k) {
    cross3(u[(k + 1) % 3], u[(k + 2) % 3], L);
    if (axis(L)) return 1;
  }
  cross3(e[0], e[1], L);
  if (axis(L)) return 1;
  for (int k = 0; k < 3; ++k)
    for (int j = 0; j < 3; ++j) {
      cross3(u[k], e[j], L);
      if (axis(L)) return 1;
    }
  return undecided ? 0 : -1;
}

// Double filter of sat_box_triangle with a semi-static error bound. For an axis L = x × y the
// separation min_i(D_i.L) - sum_k |u_k.L| (and its mirror) is a polynomial of degree 3 in the
// inputs; its computed value differs from the exact one (with the exact u_k = half_k axes_k,
// the exact L) by at most gamma_m times the same polynomial in absolute values, where m = 11
// roundings lie on its longest path (u_k or D_i or e_j: 1, the cross: 2, the dot: 3, the
// absolute sum: 2, the subtraction: 1, plus 2 for the inputs of the cross). That absolute
// polynomial is at most |L|abs . (max_i |D_i| + sum_k |u_k|) with |L|abs = |x| × |y| taken
// on absolute values (all componentwise). 16u times the computed bound covers gamma_11 and the
// bound's own round-off (relative 10u). Returns +1 separated, -1 touching, 0 undecided.
int sat_box_triangle_filter(const Collider& b, const Vec3* const p[3]) {
  Vec3 u[3], ua[3], d[3], e[3], da[3], ea[3];
  for (int k = 0; k < 3; ++k) {
    u[k] = b.half[k] * b.axes[k];
    ua[k] = u[k].cwiseAbs();
    d[k] = *p[k] - b.center;
    da[k] = d[k].cwiseAbs();
  }
  for (int j = 0; j < 3; ++j) {
    e[j] = *p[(j + 1) % 3] - *p[j];
    ea[j] = e[j].cwiseAbs();
  }
  const Vec3 dmax = da[0].cwiseMax(da[1]).cwiseMax(da[2]);
  const Vec3 mag = dmax + ua[0] + ua[1] + ua[2];
  auto abs_cross = [](const Vec3& x, const Vec3& y) {
    return Vec3(x[1] * y[2] + x[2] * y[1], x[2] * y[0] + x[0] * y[2], x[0] * y[1] + x[1] * y[0]);
  };
  bool undecided = false;
  auto axis = [&](const Vec3& L, const Vec3& La) {
    const double r = std::abs(u[0].dot(L)) + std::abs(u[1].dot(L)) + std::abs(u[2].dot(L));
    const double d0 = d[0].dot(L), d1 = d[1].dot(L), d2 = d[2].dot(L);
    const double sep =
        std::max(std::min(std::min(d0, d1), d2) - r, -std::max(std::max(d0, d1), d2) - r);
    const double bound = 16 * kU * La.dot(mag);
    if (sep > bound) return true;
    if (!(sep <= -bound)) undecided = true;
    return false;
  };
  for (int k = 0; k < 3; ++k) {
    const int a = (k + 1) % 3, c = (k + 2) % 3;
    if (axis(u[a].cross(u[c]), abs_cross(ua[a], ua[c]))) return 1;
  }
  if (axis(e[0].cross(e[1]), abs_cross(ea[0], ea[1]))) return 1;
  for (int k = 0; k < 3; ++k)
    for (int j = 0; j < 3; ++j)
      if (axis(u[k].cross(e[j]), abs_cross(ua[k], ea[j]))) return 1;
  return undecided ? 0 : -1;
}

bool box_touches_triangle(const Collider& b, const Vec3& p0, const Vec3& p1, const Vec3& p2) {
  const Vec3* ps[3] = {&p0, &p1, &p2};
  const int s = sat_box_triangle_filter(b, ps);
  if (s != 0) return s < 0;
  {
    Interval c[3], u[3][3], p[3][3];
    for (int i = 0; i < 3; ++i) {
      c[i] = point(b.center[i]);
      for (int k = 0; k < 3; ++k) u[k][i] = point(b.half[k]) * point(b.axes[k][i]);
      for (int k = 0; k < 3; ++k) p[k][i] = point((*ps[k])[i]);
    }
    const int si = sat_box_triangle(c, u, p);
    if (si != 0) return si < 0;
  }
  g_exact_fallbacks.fetch_add(1, std::memory_order_relaxed);
  Rational c[3], u[3][3], p[3][3];
  for (int i = 0; i < 3; ++i) {
    c[i] = b.center[i];
    for (int k = 0; k < 3; ++k) u[k][i] = Rational(b.half[k]) * Rational(b.axes[k][i]);
    for (int k = 0; k < 3; ++k) p[k][i] = (*ps[k])[i];
  }
  return sat_box_triangle(c, u, p) < 0;
}

}  // namespace

Vec3 closest_point_on_triangle(const Vec3& p, const Vec3& a, const Vec3& b, const Vec3& c) {
  // Voronoi regions of the triangle (Ericson, Real-Time Collision Detection, §5.1.5), in
  // double. Every branch returns a + v (b - a) + w (c - a) with v, w >= 0 and v + w <= 1 up to
  // a few ulps: the edge parameters are d/(d - d') with d >= 0 >= d', which rounds into [0, 1].
  const Vec3 ab = b - a, ac = c - a, ap = p - a;
  const double d1 = ab.dot(ap), d2 = ac.dot(ap);
  if (d1 <= 0 && d2 <= 0) return a;
  const Vec3 bp = p - b;
  const double d3 = ab.dot(bp), d4 = ac.dot(bp);
  if (d3 >= 0 && d4 <= d3) return b;
  const double vc = d1 * d4 - d3 * d2;
  if (vc <= 0 && d1 >= 0 && d3 <= 0) return a + (d1 / (d1 - d3)) * ab;
  const Vec3 cp = p - c;
  const double d5 = ab.dot(cp), d6 = ac.dot(cp);
  if (d6 >= 0 && d5 <= d6) return c;
  const double vb = d5 * d2 - d1 * d6;
  if (vb <= 0 && d2 >= 0 && d6 <= 0) return a + (d2 / (d2 - d6)) * ac;
  const double va = d3 * d6 - d5 * d4;
  if (va <= 0 && (d4 - d3) >= 0 && (d5 - d6) >= 0)
    return b + ((d4 - d3) / ((d4 - d3) + (d5 - d6))) * (c - b);
  const double denom = 1.0 / (va + vb + vc);
  return a + ab * (vb * denom) + ac * (vc * denom);
}

double mesh_scale(const Mesh& mesh) {
  double s = 0;
  for (const Vec3& v : mesh.vertices) s = std::max(s, v.norm());
  return s;
}

PreparedCollider prepare_collider(const Collider& c, double mesh_scale) {
  PreparedCollider p;
  p.c = c;
  Vec3 reach;
  if (c.shape == ColliderShape::kSphere) {
    reach = Vec3::Constant(c.radius);
    p.extent = c.radius;
    // One-sided bound of the sphere test. When closest_point_on_triangle returns q~ and
    // |s - q~|^2 <= r^2 in double: q~ is the rounded a + v ab + w ac with v, w >= 0 and
    // v + w <= 1 + 3u, so it lies within 3u(|ab| + |ac|) + 3u(|a| + |ab| + |ac|) <= 15u S of
    // the triangle (S = mesh_scale bounds every vertex norm, |ab|, |ac| <= 2S); the norm of
    // s - q~ is computed with relative error <= 5u and s - q~ itself carries 2u(|s| + S).
    // Together dist(s, T) <= r + 8u r + 20u (|s| + S); 32u (|s| + S + r) is a margin above it.
    p.sphere_slack = 32 * kU * (c.center.norm() + mesh_scale + c.radius);
  } else {
    for (int i = 0; i < 3; ++i)
      reach[i] = c.half[0] * std::abs(c.axes[0][i]) + c.half[1] * std::abs(c.axes[1][i]) +
                 c.half[2] * std::abs(c.axes[2][i]);
    // Each coordinate reach is a sum of three rounded products: relative error <= 5u; the
    // bound below adds 8u of it and the outward steps.
    reach *= 1 + 8 * kU;
    for (int k = 0; k < 3; ++k) p.extent += c.half[k] * c.axes[k].norm();
  }
  for (int i = 0; i < 3; ++i) {
    p.bounds.lo[i] = down(down(c.center[i] - reach[i]) - 2 * kU * std::abs(c.center[i]));
    p.bounds.hi[i] = up(up(c.center[i] + reach[i]) + 2 * kU * std::abs(c.center[i]));
  }
  return p;
}

bool touches_triangle(const PreparedCollider& pc, const Vec3& p0, const Vec3& p1, const Vec3& p2) {
  // Exact prefilter: the triangle's bounding box (min/max of exact coordinates) against the
  // collider's outward-rounded one. Disjoint boxes mean disjoint solids.
  for (int i = 0; i < 3; ++i) {
    const double lo = std::min(std::min(p0[i], p1[i]), p2[i]);
    const double hi = std::max(std::max(p0[i], p1[i]), p2[i]);
    if (hi < pc.bounds.lo[i] || lo > pc.bounds.hi[i]) return false;
  }
  const Collider& c = pc.c;
  if (c.shape == ColliderShape::kSphere)
    return (c.center - closest_point_on_triangle(c.center, p0, p1, p2)).squaredNorm() <=
           c.radius * c.radius;
  return box_touches_triangle(c, p0, p1, p2);
}

PreparedBox prepare_box(const Obb& box) {
  PreparedBox p;
  p.box = box;
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < 3; ++j)
      p.orth_error =
          std::max(p.orth_error, std::abs(box.axes[i].dot(box.axes[j]) - (i == j ? 1.0 : 0.0)));
  p.extent = box.center.norm();
  for (int k = 0; k < 3; ++k) p.extent += box.half[k] * box.axes[k].norm();
  p.half_norm = box.half.norm();
  return p;
}

bool may_touch_box(const PreparedCollider& pc, const PreparedBox& pb) {
  // The box B is the parallelepiped c_B + A [-h, h] (A = [a0 a1 a2], nearly orthonormal).
  // Reject only when the collider's solid is provably farther from B than the collider's
  // own slack (0 for boxes: touches_triangle is exact there). Faces lie in B exactly, so a
  // face that touches_triangle accepts is never pruned.
  const Collider& c = pc.c;
  const Obb& b = pb.box;
  const Vec3 d = c.center - b.center;
  if (c.shape == ColliderShape::kSphere) {
    // Distance from the centre s to B. Write A = Q (I + F) with Q orthonormal (polar
    // factor); A^T A = I + E with |E_ij| <= orth_error + 4u (the computed error plus its own
    // round-off), so ||F||_2 <= ||E||_2 <= 3 (orth_error + 4u). B lies within ||F|| |h| of
    // the box B_Q = c_B + Q [-h, h], and the computed coordinates d_k = (s - c_B) . a_k differ
    // from Q^T (s - c_B) by ||F|| |s - c_B| plus round-off. The distance to B_Q is 1-Lipschitz
    // in those coordinates, so dist(s, B) >= computed - 3 (orth_error + 4u)(|d| + |h|) - rnd,
    // where rnd, the round-off of d, the three dot products, the excesses, their squares, sum
    // and root, is <= 10u (|s| + |c_B| + sum h_k |a_k| + r); 32u is used.
    double e2 = 0;
    for (int k = 0; k < 3; ++k) {
      const double excess = std::abs(d.dot(b.axes[k])) - b.half[k];
      if (excess > 0) e2 += excess * excess;
    }
    const double margin = 3 * (pb.orth_error + 4 * kU) * (d.norm() + pb.half_norm) +
                          32 * kU * (c.center.norm() + pb.extent + c.radius);
    return std::sqrt(e2) <= c.radius + pc.sphere_slack + margin;
  }
  // Box against box: separating axes a_i, b_j and a_i x b_j (15). Any vector L is a valid
  // axis for a parallelepiped (its support function sum_k h_k |a_k . L| is exact), so the
  // rounding of L itself does no harm; only the projections' round-off matters. Each term of
  // |d.L| - sum h_k |a_k.L| - sum g_k |b_k.L| is a dot product of 3 rounded products
  // (relative 3u on |x||L|), scaled and summed in 8 more steps, all bounded by
  // |L| (|c| + |c_B| + sum h_k |a_k| + sum g_k |b_k|): round-off <= 12u times that; 32u used.
  const double scale = c.center.norm() + pb.extent + pc.extent;
  auto separated = [&](const Vec3& L) {
    double r = 0;
    for (int k = 0; k < 3; ++k)
      r += b.half[k] * std::abs(b.axes[k].dot(L)) + c.half[k] * std::abs(c.axes[k].dot(L));
    return std::abs(d.dot(L)) - r > 32 * kU * L.norm() * scale;
  };
  return !any_separating_axis(b, c, separated);
}

uint64_t exact_fallbacks() { return g_exact_fallbacks.load(std::memory_order_relaxed); }

}  // namespace vobb::collision
