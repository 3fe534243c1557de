#include "common/self_intersections.h"

#include <Eigen/Eigenvalues>
#include <algorithm>
#include <array>
#include <cmath>
#include <limits>

#include "common/bvh.h"
#include "common/exact_predicates.h"
#include "common/status.h"

namespace vobb {
namespace {

// ---- exact triangle intersection helpers ------------------------------------------------

// A coordinate plane (i, j) onto which triangle abc projects without degenerating.
// Precondition: abc is not collinear, so one of the three exists.
void projection_for(const Vec3& a, const Vec3& b, const Vec3& c, int* i, int* j) {
  static const int kPlanes[3][2] = {{0, 1}, {1, 2}, {2, 0}};
  for (const auto& p : kPlanes) {
    if (orient2d(a, b, c, p[0], p[1]) != 0) {
      *i = p[0];
      *j = p[1];
      return;
    }
  }
  VOBB_ASSERT(false, "projection_for on a collinear triangle");
}

bool on_segment_2d(const Vec3& p, const Vec3& q, const Vec3& r, int i, int j) {
  // r is known collinear with pq; test that it lies within pq's extent.
  return std::min(p[i], q[i]) <= r[i] && r[i] <= std::max(p[i], q[i]) &&
         std::min(p[j], q[j]) <= r[j] && r[j] <= std::max(p[j], q[j]);
}

bool segments_intersect_2d(const Vec3& p, const Vec3& q, const Vec3& r, const Vec3& s, int i,
                           int j) {
  const int d1 = orient2d(p, q, r, i, j), d2 = orient2d(p, q, s, i, j);
  const int d3 = orient2d(r, s, p, i, j), d4 = orient2d(r, s, q, i, j);
  if (d1 * d2 < 0 && d3 * d4 < 0) return true;
  if (d1 == 0 && on_segment_2d(p, q, r, i, j)) return true;
  if (d2 == 0 && on_segment_2d(p, q, s, i, j)) return true;
  if (d3 == 0 && on_segment_2d(r, s, p, i, j)) return true;
  if (d4 == 0 && on_segment_2d(r, s, q, i, j)) return true;
  return false;
}

bool point_in_triangle_2d(const Vec3& p, const Vec3& a, const Vec3& b, const Vec3& c, int i,
                          int j) {
  const int s = orient2d(a, b, c, i, j);
  return orient2d(a, b, p, i, j) * s >= 0 && orient2d(b, c, p, i, j) * s >= 0 &&
         orient2d(c, a, p, i, j) * s >= 0;
}

bool segment_triangle_coplanar(const Vec3& p, const Vec3& q, const Vec3& a, const Vec3& b,
                               const Vec3& c) {
  int i, j;
  projection_for(a, b, c, &i, &j);
  if (point_in_triangle_2d(p, a, b, c, i, j) || point_in_triangle_2d(q, a, b, c, i, j)) return true;
  return segments_intersect_2d(p, q, a, b, i, j) || segments_intersect_2d(p, q, b, c, i, j) ||
         segments_intersect_2d(p, q, c, a, i, j);
}

// Closed segment pq against closed non-degenerate triangle abc.
bool segment_hits_triangle(const Vec3& p, const Vec3& q, const Vec3& a, const Vec3& b,
                           const Vec3& c) {
  const int op = orient3d(a, b, c, p), oq = orient3d(a, b, c, q);
  if (op * oq > 0) return false;
  if (op == 0 && oq == 0) return segment_triangle_coplanar(p, q, a, b, c);
  // The segment meets the plane in one point; it lies in the triangle iff the line pq passes
  // on no strictly opposite sides of the triangle's edges.
  const int s1 = orient3d(p, q, a, b), s2 = orient3d(p, q, b, c), s3 = orient3d(p, q, c, a);
  const bool pos = s1 > 0 || s2 > 0 || s3 > 0;
  const bool neg = s1 < 0 || s2 < 0 || s3 < 0;
  return !(pos && neg);
}

bool triangles_intersect_coplanar(const Vec3* t, const Vec3* s) {
  int i, j;
  projection_for(t[0], t[1], t[2], &i, &j);
  for (int k = 0; k < 3; ++k) {
    if (point_in_triangle_2d(s[k], t[0], t[1], t[2], i, j)) return true;
    if (point_in_triangle_2d(t[k], s[0], s[1], s[2], i, j)) return true;
  }
  for (int k = 0; k < 3; ++k)
    for (int l = 0; l < 3; ++l)
      if (segments_intersect_2d(t[k], t[(k + 1) % 3], s[l], s[(l + 1) % 3], i, j)) return true;
  return false;
}

// Two triangles with no shared vertex.
bool triangles_intersect(const Vec3* t, const Vec3* s) {
  int ds[3], dt[3];
  for (int k = 0; k < 3; ++k) ds[k] = orient3d(t[0], t[1], t[2], s[k]);
  if ((ds[0] > 0 && ds[1] > 0 && ds[2] > 0) || (ds[0] < 0 && ds[1] < 0 && ds[2] < 0)) return false;
  if (ds[0] == 0 && ds[1] == 0 && ds[2] == 0) return triangles_intersect_coplanar(t, s);
  for (int k = 0; k < 3; ++k) dt[k] = orient3d(s[0], s[1], s[2], t[k]);
  if ((dt[0] > 0 && dt[1] > 0 && dt[2] > 0) || (dt[0] < 0 && dt[1] < 0 && dt[2] < 0)) return false;
  // Not coplanar: the intersection, if any, is a segment or point whose ends lie on an edge
  // of one triangle inside the other.
  for (int k = 0; k < 3; ++k) {
    if (segment_hits_triangle(t[k], t[(k + 1) % 3], s[0], s[1], s[2])) return true;
    if (segment_hits_triangle(s[k], s[(k + 1) % 3], t[0], t[1], t[2])) return true;
  }
  return false;
}

// Is direction d - u inside the closed wedge at u spanned by p - u and q - u (angle < 180)?
bool in_wedge_2d(const Vec3& u, const Vec3& p, const Vec3& q, const Vec3& d, int i, int j) {
  const int s = orient2d(u, p, q, i, j);
  return orient2d(u, p, d, i, j) * s >= 0 && orient2d(u, d, q, i, j) * s >= 0;
}

// Triangles (u, a1, b1) and (u, a2, b2) sharing exactly vertex u.
bool triangles_meet_beyond_vertex(const Vec3& u, const Vec3& a1, const Vec3& b1, const Vec3& a2,
                                  const Vec3& b2) {
  const bool a2_on = orient3d(u, a1, b1, a2) == 0, b2_on = orient3d(u, a1, b1, b2) == 0;
  int i, j;
  if (a2_on && b2_on) {  // coplanar: the wedges at u overlap beyond u
    projection_for(u, a1, b1, &i, &j);
    return in_wedge_2d(u, a1, b1, a2, i, j) || in_wedge_2d(u, a1, b1, b2, i, j) ||
           in_wedge_2d(u, a2, b2, a1, i, j) || in_wedge_2d(u, a2, b2, b1, i, j);
  }
  if (segment_hits_triangle(a1, b1, u, a2, b2) || segment_hits_triangle(a2, b2, u, a1, b1))
    return true;
  // An edge from u that runs inside the other triangle's plane and wedge.
  if (a2_on || b2_on) {
    projection_for(u, a1, b1, &i, &j);
    if (a2_on && in_wedge_2d(u, a1, b1, a2, i, j)) return true;
    if (b2_on && in_wedge_2d(u, a1, b1, b2, i, j)) return true;
  }
  const bool a1_on = orient3d(u, a2, b2, a1) == 0, b1_on = orient3d(u, a2, b2, b1) == 0;
  if (a1_on || b1_on) {
    projection_for(u, a2, b2, &i, &j);
    if (a1_on && in_wedge_2d(u, a2, b2, a1, i, j)) return true;
    if (b1_on && in_wedge_2d(u, a2, b2, b1, i, j)) return true;
  }
  return false;
}

// ---- conservative filters ---------------------------------------------------------------
//
// Rounding. With u = 2^-53, a difference of two doubles is within u of its value (relative),
// a dot product of three terms within 3u |a|_1 |v|_inf plus the error of its inputs. The
// filters below compare floating-point gaps against a tolerance of kFilterSlack times the
// size of the quantities involved, 1e-12 = 4,500 u, which exceeds the few tens of u that
// every computation here can lose; kFilterFloor = 1e-300 covers the absolute error of
// results that underflow (at most a few times 2^-1074). A filter that is too loose only costs
// exact tests; one that is too tight would drop an intersection, so the slack errs wide.
constexpr double kFilterSlack = 1e-12;
constexpr double kFilterFloor = 1e-300;
// Fans of at most this many faces, and edges of at most this many, are searched pair by pair.
constexpr int32_t kSmallFan = 24;
constexpr size_t kSmallEdge = 8;
// Nodes get a slab volume where their box is this many times wider (see add_slab_boxes).
constexpr double kLooseBox = 4.0;
// ... or this many times wider than their spread along their least axis.
constexpr double kThinSlice = 64.0;
// triangles_may_meet is used where no coordinate exceeds kPairFilterLimit (its projections
// are cubic in the coordinates), slab volumes where the largest coordinate S lies in
// [1 / kSlabLimit, kSlabLimit] (their projections are linear in S, and their covariances are
// taken in units of S).
constexpr double kPairFilterLimit = 0x1p300;
constexpr double kSlabLimit = 0x1p500;

int shared_vertices(const Face& F, const Face& G) {
  int n = 0;
  for (int a = 0; a < 3; ++a)
    for (int b = 0; b < 3; ++b) n += F[a] == G[b];
  return n;
}

double max_abs(const Vec3& v) { return v.cwiseAbs().maxCoeff(); }

// x / |x|, scaled by its largest component first so that nothing overflows or underflows;
// 0 for x = 0.
Vec3 unit(const Vec3& x) {
  const Vec3 s = x / max_abs(x);
  const double n = s.norm();
  return n > 0 ? Vec3(s / n) : Vec3::Zero();
}

// Rejects boxes that a triangle certainly misses. Boxes whose intervals do not overlap the
// triangle's bounding box are rejected first, exactly (bounds are minima and maxima of
// coordinates, so no rounding is involved). The remaining separating axes of a triangle and a
// box are the triangle's normal and the box axes crossed with its edges; the triangle's
// projections onto them are computed once per triangle. Any vector is a valid separating
// axis, so the rounding of the axes themselves does not matter, only that of the projections:
// with every coordinate within S in magnitude (the mesh's largest), the triangle's projections,
// the box's centre projection a.c and its radius |a|.h together lose at most about 12 u |a|_1 S,
// so a gap over kFilterSlack |a|_1 S (plus the floor) is a true gap.
class TriangleSeparator {
 public:
  TriangleSeparator(const Vec3* t, const Aabb& bounds, double S) : bounds_(bounds) {
    const Vec3 e[3] = {t[1] - t[0], t[2] - t[1], t[0] - t[2]};
    axis_[0] = e[0].cross(e[1]);
    for (int k = 0; k < 3; ++k)
      for (int j = 0; j < 3; ++j) axis_[1 + 3 * k + j] = Vec3::Unit(k).cross(e[j]);
    for (int i = 0; i < kAxes; ++i) {
      abs_[i] = axis_[i].cwiseAbs();
      const double p0 = axis_[i].dot(t[0]), p1 = axis_[i].dot(t[1]), p2 = axis_[i].dot(t[2]);
      const double tol = kFilterSlack * abs_[i].sum() * S + kFilterFloor;
      lo_[i] = std::min({p0, p1, p2}) - tol;
      hi_[i] = std::max({p0, p1, p2}) + tol;
    }
  }
  bool may_meet(const Aabb& b) const {
    if (!b.overlaps(bounds_)) return false;
    const Vec3 c = 0.5 * (b.lo + b.hi), h = 0.5 * (b.hi - b.lo);
    for (int i = 0; i < kAxes; ++i) {
      const double pc = axis_[i].dot(c), r = abs_[i].dot(h);
      if (pc - r > hi_[i] || pc + r < lo_[i]) return false;
    }
    return true;
  }

 private:
  static constexpr int kAxes = 10;
  Aabb bounds_;
  Vec3 axis_[kAxes], abs_[kAxes];
  double lo_[kAxes], hi_[kAxes];
};

// Rejects pairs of triangles that certainly do not meet, before the exact test: the
// separating axes of two triangles are their normals and the nine cross products of their
// edges. As in TriangleSeparator, any vector is a valid axis, so only the projections'
// rounding matters: each projection of a point with coordinates within S onto a computed axis
// a is within gamma_3 |a|_1 S (gamma_3 = 3u / (1 - 3u)) of its exact value, plus a few times
// 2^-1074 where products underflow, and adding the tolerance loses another u |a|_1 S or so;
// a gap over kFilterSlack |a|_1 S plus the floor (against about 8u |a|_1 S) is a true gap.
// The axes are quadratic in the coordinates and the projections cubic, so S must be at most
// kPairFilterLimit = 2^300 for nothing to overflow (above it the caller skips this filter).
// Where both of t's vertices on an edge lie in s's plane (the rim of a cap and a face of that
// cap), s's normal cannot separate them, but an edge of t across that plane crossed with s's
// edges can; such pairs, decided exactly, cost GMP arithmetic (the orientations are 0).
bool triangles_may_meet(const Vec3* t, const Vec3* s, double S) {
  const Vec3 et[3] = {t[1] - t[0], t[2] - t[1], t[0] - t[2]};
  const Vec3 es[3] = {s[1] - s[0], s[2] - s[1], s[0] - s[2]};
  auto separates = [&](const Vec3& a) {
    const double t0 = a.dot(t[0]), t1 = a.dot(t[1]), t2 = a.dot(t[2]);
    const double s0 = a.dot(s[0]), s1 = a.dot(s[1]), s2 = a.dot(s[2]);
    const double tol = kFilterSlack * a.cwiseAbs().sum() * S + kFilterFloor;
    return std::max({t0, t1, t2}) + tol < std::min({s0, s1, s2}) ||
           std::max({s0, s1, s2}) + tol < std::min({t0, t1, t2});
  };
  if (separates(et[0].cross(et[1])) || separates(es[0].cross(es[1]))) return false;
  for (const Vec3& e : et)
    for (const Vec3& f : es)
      if (separates(e.cross(f))) return false;
  return true;
}

// A volume holding the faces below a tree node that follows their shape where a box cannot:
// the points x with lo_k <= a_k . x <= hi_k for three axes a_k (the covariance axes of those
// faces' vertices), a box [lo, hi] in slab coordinates y = A x (A has rows a_k). The faces of a fan
// around a vertex on a rim (a CAD cylinder's cap) are long and thin, and each box of a few of them
// holds the rim faces of a whole arc; their slab volumes are as thin as the faces.
//
// Why a triangle T whose slab coordinates miss [lo, hi] misses the faces. Every point x of a
// face below the node is a convex combination of their vertices v, so A x is the same
// combination of the A v, all in [lo, hi]; if x lay in T, A x would lie in [lo, hi] and in
// the triangle A T, whose bounds would then overlap [lo, hi]. This needs no property of A:
// the axes need not be orthonormal, nor even independent, so their rounding is harmless. Only
// the rounding of slab coordinates matters:
// - Each coordinate a_k . v is a sum of three products. Computed in doubles (in any order,
//   with or without fused multiply-adds) it is within gamma_3 |a_k|_1 S of its exact value,
//   gamma_3 = 3u / (1 - 3u), for any point v with coordinates within S, plus at most 3 * 2^-1074
//   where products underflow. With |A|_1 the largest |a_k|_1, e = 3.01 u |A|_1 S + 1e-300
//   bounds that error, for the vertices below the node and for T's corners alike.
// - So the exact A v lie in the computed [lo, hi] widened by e, and the exact corners of A T
//   within e of the computed ones (every coordinate): if the exact bounds overlap, the
//   computed bounds overlap [lo, hi] widened by 2e.
// [lo, hi] is widened by kFilterSlack |A|_1 S + kFilterFloor, over 700 times 2e (the axes are
// unit vectors up to rounding, so |A|_1 is about sqrt(3); the widening uses the computed
// |A|_1, not that).
// The volume's three face normals are tried first as separating axes, then, where they do not
// separate, the cross products of A T's edges with them, in slab coordinates (any axis there is
// a valid one: if the images A T and A x miss each other, so do T and x). Their projections
// are linear in the slab coordinates, whose magnitudes are within |A|_1 S (`scale`, plus the
// widening): the computed corners of A T are within e of the exact ones, the projection of a
// corner and the box's centre and radius each lose about 3 u |b|_1 scale more, so a gap over
// kFilterSlack |b|_1 scale plus the floor is a true gap. These axes separate a fan's face from
// nodes of side faces at other angles, which the face's centre, on every such node's slab
// through the axis, keeps the normals from doing (a cap fanned from its centre). On a rim-fan
// cylinder the edge axes had pruned about 1% more nodes and cost more per node than that
// saved, so they are tried only on slices (nodes loose along their least axis), and there only
// where the normals fail.
struct SlabBox {
  Vec3 axis[3];         // a_k
  double lo[3], hi[3];  // widened as above
  double scale;         // |A|_1 S
  bool edges;           // a slice (loose along its least axis): the edge axes are tried too
};

// Conservative: false only where triangle t misses every face below the box's node.
bool may_meet_slabs(const Vec3* t, const SlabBox& box) {
  Vec3 y[3];  // t's corners in slab coordinates
  for (int k = 0; k < 3; ++k) {
    const double p0 = box.axis[k].dot(t[0]), p1 = box.axis[k].dot(t[1]), p2 = box.axis[k].dot(t[2]);
    if (std::max({p0, p1, p2}) < box.lo[k] || std::min({p0, p1, p2}) > box.hi[k]) return false;
    y[0][k] = p0, y[1][k] = p1, y[2][k] = p2;
  }
  if (!box.edges) return true;
  const Vec3 lo(box.lo[0], box.lo[1], box.lo[2]), hi(box.hi[0], box.hi[1], box.hi[2]);
  const Vec3 c = 0.5 * (lo + hi), h = 0.5 * (hi - lo);
  for (int j = 0; j < 3; ++j) {
    // The axes E x u_k for edge E = y[j+1] - y[j] and each unit vector u_k: a point p projects
    // to (E x u_k) . p = (p x E)_k, and y[j], y[j+1] project alike.
    const Vec3 E = y[(j + 1) % 3] - y[j];
    const Vec3 q0 = y[j].cross(E), q2 = y[(j + 2) % 3].cross(E), pc = c.cross(E);
    const Vec3 a = E.cwiseAbs();
    for (int k = 0; k < 3; ++k) {
      const int k1 = (k + 1) % 3, k2 = (k + 2) % 3;  // E x u_k has |E_k2|, |E_k1| there
      const double r = a[k2] * h[k1] + a[k1] * h[k2];
      const double tol = kFilterSlack * (a[k1] + a[k2]) * box.scale + kFilterFloor;
      if (std::min(q0[k], q2[k]) > pc[k] + r + tol || std::max(q0[k], q2[k]) < pc[k] - r - tol)
        return false;
    }
  }
  return true;
}

// A box holding the directions from u into triangle (u, a, b): the great-circle arc from
// the unit vector p towards a to q towards b. An arc of less than 120 degrees (1 + p.q >= 1/2)
// lies in the triangle p, q, w, where w = (p + q) / (1 + p.q) is where its tangents at p and q
// meet; a wider one is split at its midpoint m = (p + q) / |p + q| into two such arcs. Two
// faces around u can meet beyond u only along a direction in both cones, so only if their
// boxes overlap.
// Rounding: p and q are within about 4u of the true unit vectors (the difference a - u is
// correctly rounded; scaling by the largest component first keeps the norm from underflow or
// overflow), w within about 60u, and m, for |p + q| >= 1/8, within about 100u; the box is
// padded by the slack, 1e-12. An arc so close to 180 degrees that |p + q| < 1/8 (wider than
// about 173 degrees) gets the whole cube.
Aabb cone_box(const Vec3& u, const Vec3& a, const Vec3& b) {
  auto direction = [&](const Vec3& x) { return unit(x - u); };
  Aabb box;
  auto add_arc = [&](const Vec3& p, const Vec3& q) {  // precondition: 1 + p.q >= 1/2
    box.extend(p);
    box.extend(q);
    box.extend(Vec3((p + q) / (1.0 + p.dot(q))));
  };
  const Vec3 p = direction(a), q = direction(b);
  if (1.0 + p.dot(q) >= 0.5) {
    add_arc(p, q);
  } else if ((p + q).norm() >= 0.125) {
    const Vec3 m = (p + q).normalized();
    add_arc(p, m);
    add_arc(m, q);
  } else {
    box.extend(Vec3::Constant(-1.0));
    box.extend(Vec3::Constant(1.0));
  }
  box.lo.array() -= kFilterSlack;
  box.hi.array() += kFilterSlack;
  return box;
}

// ---- fans ordered by azimuth ------------------------------------------------------------
//
// The faces around a vertex v, each with its arc of directions from v (cone_box), ordered by
// the angle at which a linear map L : R^3 -> R^2 (the projection across the fan's axis) sends
// those directions: faces whose angle intervals are disjoint do not meet beyond v, for any L,
// and the overlapping intervals of k faces are listed in k log k plus their number. Angles
// are pseudo-angles in [0, 4) (a quarter turn is 1), each padded for its rounding by
// kFilterSlack (|d|_inf E + kFilterFloor) / m + kFilterSlack, for d = x - v, m = |L d|_1 as
// computed, E the larger 1-norm of L's rows; a face whose pad exceeds kWideArc, or whose
// interval may reach half the circle, is "wide". Derivation: docs/derivations.md, "Fans
// ordered by angle".
constexpr double kWideArc = 0.25;  // in pseudo-angle units (a quarter turn is 1)
constexpr double kInfinity = std::numeric_limits<double>::infinity();

double pseudo_angle(double a, double b) {
  if (a > 0 && b >= 0) return b / (a + b);
  if (a <= 0 && b > 0) return 1.0 + (-a) / (b - a);
  if (a < 0 && b <= 0) return 2.0 + (-b) / (-a - b);
  return 3.0 + a / (a - b);  // a >= 0 > b (a = b = 0 is excluded by the caller)
}

// The pseudo-angle of L (x - v) and its pad; false where the face must count as wide.
bool azimuth(const Vec3& d, const Vec3& e1, const Vec3& e2, double E, double* angle, double* pad) {
  const double a = d.dot(e1), b = d.dot(e2);
  const double m = std::abs(a) + std::abs(b);
  *pad = kFilterSlack * (max_abs(d) * E + kFilterFloor) / m + kFilterSlack;
  if (!(m > 0) || !(m < kInfinity) || !(*pad <= kWideArc)) return false;  // also NaN
  *angle = pseudo_angle(a, b);
  return true;
}

// The pairs i < j of a fan's faces (indices into `fan`) whose cones may share a direction
// (conservative: every pair that meets beyond v is listed), each once, in batches (a caller
// that stops early has not paid for the rest). `fan` lists the faces around v (none skipped,
// none degenerate). start() returns false, listing nothing, where the fan suits this search
// badly: an edge at v on more than two of its faces (a non-manifold edge of c faces makes
// c^2 / 2 candidates that the tree search skips by subtree), no usable axis, or more than
// kMaxWide wide faces (each is listed against every other). Its functions stay out of line:
// inlined into find_self_intersections, they cost the search on an ordinary mesh (bunny00)
// 2 % more instructions, from inlining that the compiler then gives up elsewhere.
constexpr int32_t kMaxWide = 16;

class FanSweep {
 public:
  bool start(const Mesh& mesh, int32_t v, const int32_t* fan, int32_t k);
  // Replaces *pairs by up to `most` more pairs; false once none are left.
  bool next(std::vector<std::pair<int32_t, int32_t>>* pairs, size_t most);

 private:
  struct Interval {
    double start, width;  // start in [0, 4), width < 2
    int32_t face;
  };
  int32_t k_ = 0;
  std::vector<Interval> narrow_;
  std::vector<int32_t> wide_;
  std::vector<char> is_wide_;
  size_t wide_at_ = 0;  // wide faces: wide_[wide_at_] against face other_
  int32_t other_ = 0;
  size_t at_ = 0, step_ = 1;  // narrow faces: narrow_[at_] against the one step_ further on
};

[[gnu::noinline]] bool FanSweep::start(const Mesh& mesh, int32_t v, const int32_t* fan, int32_t k) {
  std::vector<int32_t> others;  // the fan's other vertices, each on two faces at most
  others.reserve(2 * k);
  // The axis: the faces' summed unit normals (oriented as listed) across a flat or shallow
  // fan, the edges' summed unit directions along a sharp cone, whichever is longer per term.
  Vec3 normals = Vec3::Zero(), directions = Vec3::Zero();
  std::vector<std::array<Vec3, 2>> dirs(k);
  for (int32_t i = 0; i < k; ++i) {
    const Face& F = mesh.faces[fan[i]];
    const int c = F[0] == v ? 0 : F[1] == v ? 1 : 2;
    const int32_t a = F[(c + 1) % 3], b = F[(c + 2) % 3];
    others.push_back(a);
    others.push_back(b);
    dirs[i] = {mesh.vertices[a] - mesh.vertices[v], mesh.vertices[b] - mesh.vertices[v]};
    const Vec3 p = unit(dirs[i][0]), q = unit(dirs[i][1]);
    normals += unit(p.cross(q));
    directions += p + q;
  }
  std::sort(others.begin(), others.end());
  for (size_t i = 2; i < others.size(); ++i)
    if (others[i] == others[i - 2]) return false;
  const double by_normals = max_abs(normals) / k, by_directions = max_abs(directions) / (2 * k);
  const Vec3 axis = by_normals >= by_directions ? normals : directions;
  if (!(std::max(by_normals, by_directions) > 1e-3)) return false;  // both nearly cancel (or NaN)
  // L's rows: two vectors across the axis (any rows are valid, so their rounding is harmless).
  int least = 0;
  for (int i = 1; i < 3; ++i)
    if (std::abs(axis[i]) < std::abs(axis[least])) least = i;
  const Vec3 e1 = unit(axis.cross(Vec3::Unit(least)));
  const Vec3 e2 = unit(axis.cross(e1));
  const double E = std::max(e1.cwiseAbs().sum(), e2.cwiseAbs().sum());

  k_ = k;
  narrow_.clear();
  wide_.clear();
  is_wide_.assign(k, 0);
  wide_at_ = 0;
  other_ = 0;
  at_ = 0;
  step_ = 1;
  narrow_.reserve(k);
  for (int32_t i = 0; i < k; ++i) {
    double ap, pp, aq, pq;
    bool ok = azimuth(dirs[i][0], e1, e2, E, &ap, &pp) && azimuth(dirs[i][1], e1, e2, E, &aq, &pq);
    if (ok) {
      // The exact pseudo-angles lie within pp of ap and pq of aq, so both lie in the range
      // from the nearer way round's first end less pad to its other end plus pad (pad also
      // covers the rounding of diff and of the sums below); where that range is under half the
      // circle, the exact arc between them, the shorter way round, lies in it. Otherwise the
      // segment may pass through 0, and the face is wide. The margin below 2 keeps two widths'
      // rounded sums from both reaching the other's start (each pair is listed once).
      const double pad = pp + pq + kFilterSlack;
      double diff = aq - ap;
      if (diff < 0) diff += 4.0;
      const double width = std::min(diff, 4.0 - diff) + 2 * pad;
      ok = width < 2.0 - kFilterSlack;
      if (ok) {
        double start = (diff < 2.0 ? ap : aq) - pad;
        if (start < 0) start += 4.0;
        if (start >= 4.0) start = 0.0;  // a tiny negative start rounds up to 4, the same point
        narrow_.push_back({start, width, i});
      }
    }
    if (!ok) {
      if (static_cast<int32_t>(wide_.size()) == kMaxWide) return false;
      wide_.push_back(i);
      is_wide_[i] = 1;
    }
  }
  // Two circular intervals each narrower than half the circle overlap exactly when one's
  // start lies in the other, and not both ways round (that would take widths summing to 4);
  // with equal starts, the pair is met from whichever comes first in the sorted order. So
  // scanning forward from each start, round the circle, lists each overlapping pair once.
  std::sort(narrow_.begin(), narrow_.end(), [](const Interval& x, const Interval& y) {
    return x.start != y.start ? x.start < y.start : x.face < y.face;
  });
  return true;
}

[[gnu::noinline]] bool FanSweep::next(std::vector<std::pair<int32_t, int32_t>>* pairs,
                                      size_t most) {
  pairs->clear();
  auto add = [&](int32_t i, int32_t j) { pairs->push_back({std::min(i, j), std::max(i, j)}); };
  // Wide faces against every other face (pairs of wide faces once).
  while (wide_at_ < wide_.size() && pairs->size() < most) {
    const int32_t i = wide_[wide_at_];
    if (other_ != i && (!is_wide_[other_] || other_ > i)) add(i, other_);
    if (++other_ == k_) {
      other_ = 0;
      ++wide_at_;
    }
  }
  const size_t count = narrow_.size();
  while (at_ < count && pairs->size() < most) {
    if (step_ < count) {
      const Interval& x = narrow_[at_];
      const Interval& y = narrow_[(at_ + step_) % count];
      if (y.start + (at_ + step_ >= count ? 4.0 : 0.0) <= x.start + x.width) {
        add(x.face, y.face);
        ++step_;
        continue;
      }
    }
    ++at_;
    step_ = 1;
  }
  return !pairs->empty();
}

// Faces (u, v, w) on edge uv meet beyond it exactly when their third vertices lie in the
// same half-plane bounded by the line uv (faces_intersect: coplanar, same side). Sorting the
// third vertices by their half-plane's angle around uv, exactly, puts each class of equal
// half-planes in one run, and a run of r faces holds r (r - 1) / 2 meeting pairs, less the
// pairs of faces with the same third vertex where uv is not their least edge (those pairs are
// counted on that edge). The order: against the half-plane of a reference vertex r, a vertex
// is in r's half-plane (key 0), strictly on one side of r's plane (1), in the opposite
// half-plane (2) or strictly on the other side (3); within sides 1 and 3 all half-planes lie
// within an open half-turn, where the sign of orient3d(u, v, a, b) orders them. Costs c log c
// for c faces where deciding every pair costs c^2 / 2 (only a non-manifold edge has c > 2).
size_t pairs_in_same_half_plane(const Mesh& mesh, int32_t lo, int32_t hi,
                                const std::vector<int32_t>& third, size_t* steps) {
  const Vec3& u = mesh.vertices[lo];
  const Vec3& v = mesh.vertices[hi];
  const Vec3& r = mesh.vertices[third[0]];
  int i, j;
  projection_for(u, v, r, &i, &j);
  const int r_side = orient2d(u, v, r, i, j);
  auto key = [&](int32_t x) {
    const Vec3& p = mesh.vertices[x];
    const int s = orient3d(u, v, r, p);
    if (s > 0) return 1;
    if (s < 0) return 3;
    return orient2d(u, v, p, i, j) == r_side ? 0 : 2;
  };
  std::vector<std::pair<int, int32_t>> keyed;  // (key, third vertex)
  keyed.reserve(third.size());
  for (int32_t x : third) keyed.push_back({key(x), x});
  auto before = [&](const std::pair<int, int32_t>& a, const std::pair<int, int32_t>& b) {
    ++*steps;
    if (a.first != b.first) return a.first < b.first;
    if (a.first == 0 || a.first == 2) return false;
    return orient3d(u, v, mesh.vertices[a.second], mesh.vertices[b.second]) > 0;
  };
  std::sort(keyed.begin(), keyed.end(), before);
  size_t pairs = 0;
  std::vector<int32_t> same;
  for (size_t a = 0; a < keyed.size();) {
    size_t b = a + 1;
    while (b < keyed.size() && !before(keyed[a], keyed[b])) ++b;
    pairs += (b - a) * (b - a - 1) / 2;
    same.clear();
    for (size_t x = a; x < b; ++x) same.push_back(keyed[x].second);
    std::sort(same.begin(), same.end());
    for (size_t x = 0; x < same.size();) {
      size_t y = x + 1;
      while (y < same.size() && same[y] == same[x]) ++y;
      if (same[x] < hi) pairs -= (y - x) * (y - x - 1) / 2;  // uv is not their least edge
      x = y;
    }
    a = b;
  }
  return pairs;
}

// A box tree (an AabbTree) over some faces, one box each, whose nodes also know the vertices
// that every face below them lists, so that a query can skip subtrees of faces that all list
// one of the vertices it names, and the largest face index below them, so that a query for
// the pairs (f, g > f) can skip subtrees of smaller faces. Nodes whose box is loose can also
// get a slab volume (add_slab_boxes).
class FaceTree {
 public:
  // boxes[i] is the box of face faces[i]; `faces` must outlive the tree.
  FaceTree(const Mesh& mesh, const std::vector<int32_t>& faces, std::vector<Aabb> boxes)
      : faces_(faces), tree_(std::move(boxes)) {
    const std::vector<AabbTree::Node>& nodes = tree_.nodes();
    extra_.resize(nodes.size());
    for (size_t k = nodes.size(); k-- > 0;) {  // children before parents
      const AabbTree::Node& n = nodes[k];
      Extra& e = extra_[k];
      if (n.count > 0) {
        e.common = mesh.faces[face_at(n.first)];
        for (int32_t i = n.first; i < n.first + n.count; ++i) {
          e.common = intersect(e.common, mesh.faces[face_at(i)]);
          e.last_face = std::max(e.last_face, face_at(i));
        }
      } else {
        const Extra &l = extra_[n.first], &r = extra_[n.first + 1];
        e.common = intersect(l.common, r.common);
        e.last_face = std::max(l.last_face, r.last_face);
      }
    }
  }

  // Gives the nodes whose box is loose a slab volume (SlabBox) holding their faces' vertices,
  // for coordinates within S in magnitude. Costs O(n log n): each face's vertices are
  // projected once for every such node above it. Meshes whose S lies outside
  // [1 / kSlabLimit, kSlabLimit] get none.
  void add_slab_boxes(const Mesh& mesh, double S) {
    if (!(S >= 1.0 / kSlabLimit && S <= kSlabLimit)) return;
    const std::vector<AabbTree::Node>& nodes = tree_.nodes();
    // Covariances of the vertices, in units of S (so that squares neither overflow nor
    // underflow), merged from the children: count, mean and scatter matrix.
    struct Moments {
      double n = 0;
      Vec3 mean = Vec3::Zero();
      Eigen::Matrix3d scatter = Eigen::Matrix3d::Zero();
    };
    const double inv = 1.0 / S;
    std::vector<Moments> moments(nodes.size());
    std::vector<int32_t> begin(nodes.size()), end(nodes.size());  // node's range of order()
    for (size_t k = nodes.size(); k-- > 0;) {                     // children before parents
      const AabbTree::Node& n = nodes[k];
      Moments& m = moments[k];
      if (n.count > 0) {
        begin[k] = n.first;
        end[k] = n.first + n.count;
        for (int32_t i = begin[k]; i < end[k]; ++i)
          for (int32_t v : mesh.faces[face_at(i)]) m.mean += inv * mesh.vertices[v];
        m.n = 3.0 * n.count;
        m.mean /= m.n;
        for (int32_t i = begin[k]; i < end[k]; ++i)
          for (int32_t v : mesh.faces[face_at(i)]) {
            const Vec3 d = inv * mesh.vertices[v] - m.mean;
            m.scatter += d * d.transpose();
          }
      } else {
        const Moments &l = moments[n.first], &r = moments[n.first + 1];
        begin[k] = begin[n.first];
        end[k] = end[n.first + 1];
        const Vec3 d = r.mean - l.mean;
        m.n = l.n + r.n;
        m.mean = l.mean + d * (r.n / m.n);
        m.scatter = l.scatter + r.scatter + (l.n * r.n / m.n) * d * d.transpose();
      }
    }
    Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> eigen;
    for (size_t k = 0; k < nodes.size(); ++k) {
      // Only where the box is far looser than the slab volume can be, along the middle axis or
      // the least one: its middle extent over kLooseBox times the spread of the vertices along
      // the middle axis (a uniform spread of length l has variance l^2 / 12), as a fan's faces
      // from a rim vertex are; or its least extent over kThinSlice times their spread along the
      // least axis, as a slice along a diagonal is (the faces of a fan from a centre and the
      // side faces beside them, in a box from the centre to the rim). Elsewhere (most nodes of
      // most meshes) the test would cost more than it saves. The middle eigenvalue is at least
      // the smaller one of each 2 x 2 block on the diagonal (Courant-Fischer), and the least at
      // least 4 det / trace^2 (the other two multiply to at most (trace / 2)^2): cheaper to
      // find, they rule out most nodes first.
      const Eigen::Matrix3d& C = moments[k].scatter;
      Vec3 extent = inv * (nodes[k].bounds.hi - nodes[k].bounds.lo);
      std::sort(extent.data(), extent.data() + 3);
      // Loose: the middle eigenvalue of the scatter matrix (variance times count) less than
      // `bound`, or the least less than `bound_least`.
      const double spread = extent[1] / kLooseBox, spread_least = extent[0] / kThinSlice;
      const double bound = spread * spread * moments[k].n / 12.0;
      const double bound_least = spread_least * spread_least * moments[k].n / 12.0;
      bool loose = true;
      for (int i = 0; i < 3 && loose; ++i) {
        const int j = (i + 1) % 3;
        const double mean = 0.5 * (C(i, i) + C(j, j)), half = 0.5 * (C(i, i) - C(j, j));
        loose = mean - std::sqrt(half * half + C(i, j) * C(i, j)) < bound;
      }
      const double trace = C.trace();
      const bool thin = bound_least > 0 && !(4 * C.determinant() >= bound_least * trace * trace);
      if (!loose && !thin) continue;
      eigen.computeDirect(C, Eigen::EigenvaluesOnly);  // ascending
      const bool slice = thin && eigen.eigenvalues()[0] < bound_least;
      if (!(slice || (loose && eigen.eigenvalues()[1] < bound))) continue;
      eigen.computeDirect(C);
      // Any axes are valid (see SlabBox); a failed or non-finite solve gets no slab volume.
      if (eigen.info() != Eigen::Success || !eigen.eigenvectors().allFinite()) continue;
      const Eigen::Matrix3d A = eigen.eigenvectors().transpose();  // rows a_k
      Aabb slabs;                                                  // [lo, hi]
      for (int32_t i = begin[k]; i < end[k]; ++i)
        for (int32_t v : mesh.faces[face_at(i)]) slabs.extend(Vec3(A * mesh.vertices[v]));
      const double norm1 = A.cwiseAbs().rowwise().sum().maxCoeff();  // |A|_1
      const double widen = kFilterSlack * norm1 * S + kFilterFloor;
      SlabBox b;
      b.scale = norm1 * S;
      b.edges = slice;
      for (int a = 0; a < 3; ++a) {
        b.axis[a] = A.row(a).transpose();
        b.lo[a] = slabs.lo[a] - widen;
        b.hi[a] = slabs.hi[a] + widen;
      }
      extra_[k].slab = static_cast<int32_t>(slabs_.size());
      slabs_.push_back(b);
    }
  }

  // Calls visit(g, box of g) for every face g > f below nodes that `accept` passes (called on
  // node boxes; the caller tests the faces' own boxes in visit) and, where a node has a slab
  // volume, `accept_slab` passes too, skipping every subtree whose faces all list one of
  // `skip` (entries < 0 are unused); counts in *steps the nodes it looks at and the slab
  // volumes it tests.
  template <typename Accept, typename AcceptSlab, typename Visit>
  void query(int32_t f, const std::array<int32_t, 3>& skip, size_t* steps, Accept accept,
             AcceptSlab accept_slab, Visit visit) const {
    const std::vector<AabbTree::Node>& nodes = tree_.nodes();
    if (nodes.empty()) return;
    int32_t stack[64];  // median splits: depth <= 31, and one waiting sibling per level
    int top = 0;
    stack[top++] = 0;
    while (top > 0) {
      const int32_t k = stack[--top];
      const AabbTree::Node& n = nodes[k];
      const Extra& e = extra_[k];
      ++*steps;
      bool shares = false;
      for (int32_t v : e.common) shares |= v >= 0 && (v == skip[0] || v == skip[1] || v == skip[2]);
      if (shares || e.last_face <= f || !accept(n.bounds)) continue;
      if (e.slab >= 0) {
        ++*steps;
        if (!accept_slab(slabs_[e.slab])) continue;
      }
      if (n.count > 0) {
        for (int32_t i = n.first; i < n.first + n.count; ++i) {
          ++*steps;
          if (face_at(i) > f) visit(face_at(i), tree_.primitive_bounds(tree_.order()[i]));
        }
      } else {
        stack[top++] = n.first + 1;
        stack[top++] = n.first;
      }
    }
  }

 private:
  struct Extra {
    std::array<int32_t, 3> common = {-1, -1, -1};  // vertices every face below lists; -1 unused
    int32_t last_face = -1;                        // the largest face index below
    int32_t slab = -1;                             // index into slabs_, or -1 for none
  };

  static std::array<int32_t, 3> intersect(const std::array<int32_t, 3>& x,
                                          const std::array<int32_t, 3>& y) {
    std::array<int32_t, 3> out = {-1, -1, -1};
    int n = 0;
    for (int32_t v : x)
      if (v >= 0 && std::find(y.begin(), y.end(), v) != y.end()) out[n++] = v;
    return out;
  }
  int32_t face_at(int32_t i) const { return faces_[tree_.order()[i]]; }

  const std::vector<int32_t>& faces_;  // tree primitive i is faces_[i]
  AabbTree tree_;
  std::vector<Extra> extra_;    // per node of tree_
  std::vector<SlabBox> slabs_;  // the slab volumes of some nodes (Extra::slab)
};

}  // namespace

bool faces_intersect(const Mesh& mesh, size_t f, size_t g) {
  const Face& F = mesh.faces[f];
  const Face& G = mesh.faces[g];
  int shared = 0, fi[3], gi[3];
  for (int a = 0; a < 3; ++a)
    for (int b = 0; b < 3; ++b)
      if (F[a] == G[b]) {
        fi[shared] = a;
        gi[shared] = b;
        ++shared;
      }
  const Vec3 t[3] = {mesh.vertices[F[0]], mesh.vertices[F[1]], mesh.vertices[F[2]]};
  const Vec3 s[3] = {mesh.vertices[G[0]], mesh.vertices[G[1]], mesh.vertices[G[2]]};
  if (shared == 0) return triangles_intersect(t, s);
  if (shared == 3) return true;  // the same triangle twice
  if (shared == 2) {
    // Sharing edge uv: they overlap only if coplanar with the third vertices on one side.
    const Vec3& u = t[fi[0]];
    const Vec3& v = t[fi[1]];
    const Vec3& a = t[3 - fi[0] - fi[1]];
    const Vec3& b = s[3 - gi[0] - gi[1]];
    if (orient3d(u, v, a, b) != 0) return false;
    int i, j;
    projection_for(u, v, a, &i, &j);
    return orient2d(u, v, a, i, j) * orient2d(u, v, b, i, j) > 0;
  }
  const Vec3& u = t[fi[0]];
  return triangles_meet_beyond_vertex(u, t[(fi[0] + 1) % 3], t[(fi[0] + 2) % 3], s[(gi[0] + 1) % 3],
                                      s[(gi[0] + 2) % 3]);
}

SelfIntersectionSearch find_self_intersections(const Mesh& mesh, const std::vector<char>& skip,
                                               size_t stop_at) {
  VOBB_ASSERT(skip.size() == mesh.faces.size(), "find_self_intersections: one skip flag per face");
  SelfIntersectionSearch out;
  // Once stopped, every loop below ends at its next check and no tree descends further.
  auto done = [&] { return out.stopped; };
  auto found = [&](size_t n) {
    out.pairs += n;
    if (stop_at > 0 && out.pairs >= stop_at) out.stopped = true;
  };
  auto decide = [&](int32_t f, int32_t g) {
    if (out.stopped) return;
    ++out.exact_tests;
    if (faces_intersect(mesh, f, g)) found(1);
  };
  std::vector<int32_t> faces;
  for (size_t f = 0; f < mesh.faces.size(); ++f)
    if (!skip[f]) faces.push_back(static_cast<int32_t>(f));

  // Sharing two vertices: the faces on each edge. A pair listing the same three vertices
  // shares three edges and is counted on the least of them only.
  {
    std::vector<std::array<int32_t, 3>> recs;  // (lo, hi, face)
    recs.reserve(3 * faces.size());
    for (int32_t f : faces)
      for (int k = 0; k < 3; ++k) {
        const int32_t a = mesh.faces[f][k], b = mesh.faces[f][(k + 1) % 3];
        recs.push_back({std::min(a, b), std::max(a, b), f});
      }
    std::sort(recs.begin(), recs.end());
    std::vector<int32_t> third;
    for (size_t i = 0; i < recs.size() && !done();) {
      size_t j = i + 1;
      while (j < recs.size() && recs[j][0] == recs[i][0] && recs[j][1] == recs[i][1]) ++j;
      const int32_t lo = recs[i][0], hi = recs[i][1];
      if (j - i <= kSmallEdge) {
        for (size_t x = i; x < j && !done(); ++x)
          for (size_t y = x + 1; y < j; ++y) {
            const Face& F = mesh.faces[recs[x][2]];
            ++out.filter_steps;
            if (shared_vertices(F, mesh.faces[recs[y][2]]) == 3 &&
                F[0] + F[1] + F[2] - lo - hi < hi)
              continue;  // the same face twice, and (lo, hi) is not its least edge
            decide(recs[x][2], recs[y][2]);
          }
      } else {
        third.clear();
        for (size_t x = i; x < j; ++x) {
          const Face& F = mesh.faces[recs[x][2]];
          third.push_back(F[0] + F[1] + F[2] - lo - hi);
        }
        found(pairs_in_same_half_plane(mesh, lo, hi, third, &out.filter_steps));
      }
      i = j;
    }
  }

  // Sharing one vertex v: faces around v whose cones from v may share a direction.
  {
    std::vector<int32_t> start(mesh.vertices.size() + 1, 0);
    for (int32_t f : faces)
      for (int32_t v : mesh.faces[f]) ++start[v + 1];
    for (size_t v = 0; v < mesh.vertices.size(); ++v) start[v + 1] += start[v];
    std::vector<int32_t> around(start.back()), fill(start.begin(), start.end() - 1);
    for (int32_t f : faces)
      for (int32_t v : mesh.faces[f]) around[fill[v]++] = f;
    std::vector<Aabb> cones;
    FanSweep sweep;
    std::vector<std::pair<int32_t, int32_t>> pairs;
    for (size_t v = 0; v < mesh.vertices.size() && !done(); ++v) {
      const int32_t* fan = around.data() + start[v];
      const int32_t k = start[v + 1] - start[v];
      if (k < 2) continue;
      cones.resize(k);
      for (int32_t i = 0; i < k; ++i) {
        const Face& F = mesh.faces[fan[i]];
        const int c = F[0] == static_cast<int32_t>(v) ? 0 : F[1] == static_cast<int32_t>(v) ? 1 : 2;
        cones[i] = cone_box(mesh.vertices[v], mesh.vertices[F[(c + 1) % 3]],
                            mesh.vertices[F[(c + 2) % 3]]);
      }
      // A pair of faces around v whose cones' boxes overlap, unless they share an edge too.
      auto candidate = [&](int32_t i, int32_t j) {
        ++out.filter_steps;
        if (cones[i].overlaps(cones[j]) &&
            shared_vertices(mesh.faces[fan[i]], mesh.faces[fan[j]]) == 1)
          decide(fan[i], fan[j]);
      };
      if (k <= kSmallFan) {  // the usual vertex: a tree would cost more than it saves
        for (int32_t i = 0; i < k && !done(); ++i)
          for (int32_t j = i + 1; j < k; ++j) candidate(i, j);
        continue;
      }
      if (sweep.start(mesh, static_cast<int32_t>(v), fan, k)) {
        while (!done() && sweep.next(&pairs, 4096))
          for (size_t p = 0; p < pairs.size() && !done(); ++p)
            candidate(pairs[p].first, pairs[p].second);
        continue;
      }
      // Faces that share an edge with fan[i] as well are left to the edge lists: subtrees
      // whose faces all list another vertex of fan[i] are skipped (on a non-manifold edge of c
      // faces, the c^2 / 2 such pairs would otherwise all pass the cone filter).
      const std::vector<int32_t> fan_faces(fan, fan + k);
      const FaceTree tree(mesh, fan_faces, cones);
      for (int32_t i = 0; i < k && !done(); ++i) {
        const Face& F = mesh.faces[fan[i]];
        std::array<int32_t, 3> skip = F;
        for (int32_t& x : skip)
          if (x == static_cast<int32_t>(v)) x = -1;
        const Aabb& cone = cones[i];
        tree.query(
            fan[i], skip, &out.filter_steps,
            [&](const Aabb& b) { return !done() && b.overlaps(cone); },
            [](const SlabBox&) { return true; },
            [&](int32_t g, const Aabb& box) {
              if (box.overlaps(cone) && shared_vertices(F, mesh.faces[g]) == 1) decide(fan[i], g);
            });
      }
    }
  }

  // Sharing no vertex: the face tree, descended only into nodes whose box and slab volume
  // f's triangle may both meet, and pruned at subtrees whose faces all list a vertex of f.
  {
    std::vector<Aabb> boxes(faces.size());
    for (size_t i = 0; i < faces.size(); ++i) boxes[i] = mesh.face_bounds(faces[i]);
    FaceTree tree(mesh, faces, std::move(boxes));
    const Aabb all = mesh.bounds();  // S for the separator: no coordinate exceeds it
    const double largest = std::max(max_abs(all.lo), max_abs(all.hi));
    tree.add_slab_boxes(mesh, largest);
    const bool test_pairs = largest <= kPairFilterLimit;
    for (int32_t f : faces) {
      if (done()) break;
      const Face& F = mesh.faces[f];
      const Vec3 t[3] = {mesh.vertices[F[0]], mesh.vertices[F[1]], mesh.vertices[F[2]]};
      const TriangleSeparator sep(t, mesh.face_bounds(f), largest);
      tree.query(
          f, F, &out.filter_steps, [&](const Aabb& b) { return !done() && sep.may_meet(b); },
          [&](const SlabBox& slab) { return may_meet_slabs(t, slab); },
          [&](int32_t g, const Aabb& box) {
            if (shared_vertices(F, mesh.faces[g]) != 0 || !sep.may_meet(box)) return;
            const Face& G = mesh.faces[g];
            const Vec3 s[3] = {mesh.vertices[G[0]], mesh.vertices[G[1]], mesh.vertices[G[2]]};
            if (test_pairs) {
              ++out.filter_steps;  // the triangle pair's test is a step of its own
              if (!triangles_may_meet(t, s, largest)) return;
            }
            decide(f, g);
          });
    }
  }
  return out;
}

}  // namespace vobb
