#include "fast/texel_plan.h"

#include <Eigen/LU>
#include <algorithm>
#include <cfenv>
#include <cmath>
#include <cstdint>
#include <limits>
#if defined(__SSE2__)
#include <xmmintrin.h>
#endif

#include "common/status.h"

namespace vobb {

// The box's frame, with inverse_error bounding the rounding of to_local (BoxFrame). Axes that
// double cannot invert and subnormal half extents (whose inverse may overflow) give an invalid
// frame.
// Derivation: docs/derivations.md, "The box frame's rounding".
BoxFrame box_frame(const Obb& box) {
  Eigen::Matrix3d axes, m;
  for (int k = 0; k < 3; ++k) {
    axes.col(k) = box.axes[k];
    m.col(k) = box.half[k] * box.axes[k];
  }
  const double det_axes = axes.determinant();
  BoxFrame f;
  if (!(det_axes != 0 && std::isfinite(det_axes) && (box.half.array() >= 0x1p-1022).all())) {
    f.valid = false;  // axes that double cannot invert (box_defect refuses such boxes)
    return f;
  }
  f.to_local = axes.inverse();
  for (int k = 0; k < 3; ++k) f.to_local.row(k) /= box.half[k];
  if (!f.to_local.allFinite()) {
    f.valid = false;
    return f;
  }
  f.center = box.center;
  // |det M| = h0 h1 h2 |det A|, without partial products that underflow (volume(), obb.h); it
  // may still underflow to 0 as a whole (the caller treats that box as flat).
  f.volume_scale = volume(box) / 8;
  f.mirrored = det_axes < 0;
  f.half = box.half;
  constexpr double u = 0x1p-53, gamma4 = 4 * u / (1 - 4 * u);
  const Eigen::Matrix3d e = Eigen::Matrix3d::Identity() - m * f.to_local;
  const Eigen::Matrix3d size = Eigen::Matrix3d::Identity() + m.cwiseAbs() * f.to_local.cwiseAbs();
  double eps = 0, p_norm = 0;
  for (int i = 0; i < 3; ++i) {
    double row = 0, p_row = 0;
    for (int j = 0; j < 3; ++j) {
      row += std::abs(e(i, j)) + 2 * (gamma4 + 2 * u) * size(i, j);
      p_row += std::abs(box.half[i] * f.to_local(i, j));
    }
    for (int j = 0; j < 3; ++j)
      row += 0x1p-1074 * std::abs(f.to_local(i, j)) * 3;  // underflow of M~
    eps = std::max(eps, row);
    p_norm = std::max(p_norm, p_row);
  }
  eps *= 2;
  p_norm *= 1 + 8 * u;
  f.inverse_error = eps < 0.5 && std::isfinite(p_norm) ? p_norm * eps / (1 - eps)
                                                       : std::numeric_limits<double>::infinity();
  return f;
}

Vec3 BoxFrame::local_error(const Vec3& p) const {
  constexpr double u = 0x1p-53, gamma4 = 4 * u / (1 - 4 * u);
  const Vec3 w = (p - center).cwiseAbs() * (1 + u);  // |p - c| bounds |fl(p - c)| within u
  const Vec3 rounding = (to_local.cwiseAbs() * w) * (2 * gamma4);
  Vec3 out;
  for (int k = 0; k < 3; ++k)
    out[k] = inverse_error * w.maxCoeff() / std::abs(half[k]) * (1 + 4 * u) + rounding[k];
  return out;
}

namespace {

// |a| x |b| componentwise: (|a_y| |b_z| + |a_z| |b_y|, ...), what bounds the rounding of a x b.
Vec3 abs_cross(const Vec3& a, const Vec3& b) {
  const Vec3 x = a.cwiseAbs(), y = b.cwiseAbs();
  return Vec3(x[1] * y[2] + x[2] * y[1], x[2] * y[0] + x[0] * y[2], x[0] * y[1] + x[1] * y[0]);
}

// LocalTriangle::edge_tie for E = fl(+-(p x q)): a bound on |fl(d . E) - d* . E*| over the
// texel directions d (double) and d* (exact).
// Derivation: docs/derivations.md, "Edge ties".
double edge_tie(const Vec3& E, const Vec3& p, const Vec3& q) {
  constexpr double u = 0x1p-53;
  return 8 * u * (E.cwiseAbs().sum() + abs_cross(p, q).sum()) + 0x1p-1070;
}

// p x q in rationals, exactly.
void exact_cross(const Vec3& p, const Vec3& q, Rational E[3]) {
  for (int c = 0; c < 3; ++c) {
    const int c1 = (c + 1) % 3, c2 = (c + 2) % 3;
    E[c] = Rational(p[c1]) * Rational(q[c2]) - Rational(p[c2]) * Rational(q[c1]);
  }
}

// Whether E* = +-(p x q) is exactly the zero vector (LocalTriangle::edge_zero). Each component
// of E = fl(E*) is within gamma_2 of |p| x |q| of E*'s (fused or not; edge_tie), plus
// underflow, so only an E within that of 0 on every component can come from E* = 0: only such
// an edge is tested in rationals, once.
bool cross_is_exactly_zero(const Vec3& E, const Vec3& p, const Vec3& q) {
  constexpr double u = 0x1p-53;
  const Vec3 bound = abs_cross(p, q);
  for (int c = 0; c < 3; ++c)
    if (std::abs(E[c]) > 8 * u * bound[c] + 0x1p-1070) return false;
  Rational exact[3];
  exact_cross(p, q, exact);
  return sgn(exact[0]) == 0 && sgn(exact[1]) == 0 && sgn(exact[2]) == 0;
}

// Sutherland-Hodgman: keep the part of a convex polygon where plane(p) >= 0.
template <class Plane>
int clip(const Vec3* in, int n, Vec3* out, const Plane& plane) {
  int k = 0;
  for (int a = 0; a < n; ++a) {
    const Vec3& p = in[a];
    const Vec3& q = in[(a + 1) % n];
    const double fp = plane(p), fq = plane(q);
    if (fp >= 0) out[k++] = p;
    if ((fp >= 0) != (fq >= 0)) out[k++] = p + (fp / (fp - fq)) * (q - p);
    VOBB_ASSERT(k <= 16, "clipped polygon fits its buffer");
  }
  return k;
}

// The texels of cubemap face `face` whose rays may meet triangle t (within the cube unless
// no_far_clip): t is clipped to the face's cone {zeta >= |u|, zeta >= |v|} (and zeta <= 1), and
// the texels whose centres lie in the projected clipped polygon's bounds form the span.
// A clipped vertex too close to the centre to project reliably gives the whole face.
// `slack` bounds how far (Euclidean, local units) the plan's vertices may lie from the exact
// ones (BoxFrame::local_error); the clipping planes and the projected bounds are widened for
// it, so that the spans cover the exact face too.
// Derivation: docs/derivations.md, "Texel spans".
bool texel_span(const LocalTriangle& t, int face, int m, bool no_far_clip, double slack,
                TexelSpan* span) {
  const int k = face / 2, a = (k + 1) % 3, b = (k + 2) % 3;
  const double s = face % 2 == 0 ? 1.0 : -1.0;
  const double g = 2 * slack;
  Vec3 buf0[16], buf1[16];  // a convex polygon gains at most one vertex per plane: 3 + 5 <= 16
  for (int c = 0; c < 3; ++c) buf0[c] = Vec3(s * t.p[c][k], t.p[c][a], t.p[c][b]);  // (zeta, u, v)
  int n = 3;
  n = clip(buf0, n, buf1, [g](const Vec3& p) { return p[0] - p[1] + g; });
  n = clip(buf1, n, buf0, [g](const Vec3& p) { return p[0] + p[1] + g; });
  n = clip(buf0, n, buf1, [g](const Vec3& p) { return p[0] - p[2] + g; });
  n = clip(buf1, n, buf0, [g](const Vec3& p) { return p[0] + p[2] + g; });
  if (!no_far_clip) n = clip(buf0, n, buf1, [slack](const Vec3& p) { return 1 + slack - p[0]; });
  const Vec3* poly = no_far_clip ? buf0 : buf1;
  if (n == 0) return false;
  double scale = 1;
  for (int c = 0; c < 3; ++c) scale = std::max(scale, t.p[c].cwiseAbs().maxCoeff());
  // Interpolated coordinates carry absolute errors of a few eps * scale; a vertex with
  // zeta > 1e-6 scale projects with relative error < 1e-9, far inside the one-texel margin.
  // Below 4 slack the exact face may reach the centre: the whole face.
  double ulo = 1, uhi = -1, vlo = 1, vhi = -1, zeta_min = HUGE_VAL;
  bool whole = false;
  for (int c = 0; c < n; ++c) {
    const double zeta = poly[c][0];
    if (!(zeta > 1e-6 * scale) || !(zeta > 4 * slack)) {
      whole = true;
      break;
    }
    zeta_min = std::min(zeta_min, zeta);
    const double u = std::clamp(poly[c][1] / zeta, -1.0, 1.0),
                 v = std::clamp(poly[c][2] / zeta, -1.0, 1.0);
    ulo = std::min(ulo, u);
    uhi = std::max(uhi, u);
    vlo = std::min(vlo, v);
    vhi = std::max(vhi, v);
  }
  if (!whole && slack > 0) {
    const double widen = 2 * slack / zeta_min * (1 + 1e-9);
    ulo = std::max(-2.0, ulo - widen);  // the clamps keep the casts to int below defined
    vlo = std::max(-2.0, vlo - widen);
    uhi = std::min(2.0, uhi + widen);
    vhi = std::min(2.0, vhi + widen);
  }
  span->face = face;
  if (whole) {
    span->i0 = span->j0 = span->ci0 = span->cj0 = 0;
    span->i1 = span->j1 = span->ci1 = span->cj1 = m - 1;
    return true;
  }
  constexpr double kDelta = 1e-8;  // see below
  // Cells: texel i covers u in [-1 + 2i/m, -1 + 2(i+1)/m]; widened by delta like the centres.
  auto cell = [&](double x) {
    return std::clamp(static_cast<int>(std::floor((x + 1) * m / 2)), 0, m - 1);
  };
  span->ci0 = cell(ulo - kDelta);
  span->ci1 = cell(uhi + kDelta);
  span->cj0 = cell(vlo - kDelta);
  span->cj1 = cell(vhi + kDelta);
  // Texel i's centre is -1 + (2i + 1) / m; keep the centres within [lo - delta, hi + delta].
  // A texel ray that hits the face inside the cone passes through the clipped polygon, so its
  // (u, v) lies in the projected bounds up to the projection's relative error, below 1e-9
  // (above): delta = 1e-8 keeps every such texel. A face that covers no texel centre gets none.
  auto lo = [&](double x) {
    return std::max(0, static_cast<int>(std::ceil(((x - kDelta + 1) * m - 1) / 2)));
  };
  auto hi = [&](double x) {
    return std::min(m - 1, static_cast<int>(std::floor(((x + kDelta + 1) * m - 1) / 2)));
  };
  span->i0 = lo(ulo);
  span->i1 = hi(uhi);
  span->j0 = lo(vlo);
  span->j1 = hi(vhi);
  if (span->i0 > span->i1 || span->j0 > span->j1)
    span->i0 = 1, span->i1 = 0;  // no centre: draw nothing
  return true;
}

}  // namespace

double resolution_bound(const BoxPlan& plan, int m) {
  if (plan.unresolved)
    return plan.frame.volume_scale * 4.0;  // half the box: the OBV is in [0, vol]
  if (plan.flat || plan.spans.empty()) return 0.0;
  std::vector<char> touched(6 * static_cast<size_t>(m) * m, 0);
  size_t count = 0, pairs = 0, near_pairs = 0;
  for (const TexelSpan& s : plan.spans) {
    const bool near = plan.tris[s.tri].near_centre;
    for (int i = s.ci0; i <= s.ci1; ++i)
      for (int j = s.cj0; j <= s.cj1; ++j) {
        char& t = touched[(static_cast<size_t>(s.face) * m + i) * m + j];
        count += t == 0;
        t = 1;
        ++pairs;
        near_pairs += near;
      }
  }
  // Pyramids per covered texel (header): one, or two where the centre's class may disagree
  // with the plan's faces; plus 2 per (texel, face) pair of a face near the centre, whose
  // hits the plan may get wrong, and 3e-6 per other pair for the depths of the plan's planes
  // (face_near_centre).
  const double off_by = plan.centre_near_surface ? 2.0 : 1.0;
  const double pyramids = static_cast<double>(count) * off_by +
                          2.0 * static_cast<double>(near_pairs) + 3e-6 * static_cast<double>(pairs);
  return plan.frame.volume_scale * 4.0 / (3.0 * m * m) * pyramids;
}

// ---- round-off of evaluating a plan -------------------------------------------------------
//
// Derivation of the per-pair terms: docs/derivations.md, "Round-off of evaluating a plan".

namespace {

// Exact signs from floating-point expansions (docs/derivations.md, "Exact edge sides without
// rationals"): a sum of doubles is kept as a nonoverlapping expansion (two_sum), products as
// hi + lo (two_product, by fma). Exact in round-to-nearest while no product underflows or
// overflows; the callers check both and otherwise use rationals.
inline void two_sum(double a, double b, double* s, double* e) {
  *s = a + b;
  const double bv = *s - a;
  *e = (a - (*s - bv)) + (b - bv);
}

// The sign of the exact sum of x[0..n), n <= 32: the terms grown into a nonoverlapping
// expansion (Shewchuk's Grow-Expansion, zeros dropped), whose sign is its largest component's.
int sign_of_exact_sum(const double* x, int n) {
  double e[32];
  int len = 0;
  for (int i = 0; i < n; ++i) {
    double q = x[i];
    int out = 0;
    for (int j = 0; j < len; ++j) {
      double h;
      two_sum(q, e[j], &q, &h);
      if (h != 0) e[out++] = h;
    }
    if (q != 0) e[out++] = q;
    len = out;
  }
  return len == 0 ? 0 : (e[len - 1] > 0 ? 1 : -1);
}

// Whether double arithmetic rounds to nearest. fegetround reads the x87 control word, but
// double arithmetic on x86-64 runs in SSE, whose mode a library may set alone (CGAL's
// Protect_FPU_rounding does): both are read.
bool rounding_to_nearest() {
#if defined(__SSE2__)
  if ((_mm_getcsr() & _MM_ROUND_MASK) != _MM_ROUND_NEAREST) return false;
#endif
  return std::fegetround() == FE_TONEAREST;
}

// Products in [2^-800, 2^1000] (or exactly 0), times integers of at most 2^12: their
// two_product parts and the integer multiples of those neither underflow nor overflow
// (docs/derivations.md, "Exact edge sides without rationals").
inline bool product_in_range(double hi) {
  const double a = std::abs(hi);
  return a == 0 || (a >= 0x1p-800 && a <= 0x1p1000);
}

// The sign of sum_c w[c] E*[c], E* = p x q, for integers |w[c]| <= 2^12; false where a product
// leaves product_in_range (or the rounding mode is not to nearest): the caller uses rationals.
bool edge_dot_sign(const Vec3& p, const Vec3& q, const double w[3], int* sign) {
  double hi[3][2], lo[3][2];  // E*[c] = hi[c][0] + lo[c][0] + hi[c][1] + lo[c][1], exactly
  for (int c = 0; c < 3; ++c) {
    const int c1 = (c + 1) % 3, c2 = (c + 2) % 3;
    for (int half = 0; half < 2; ++half) {
      // E*[c] = p[c1] q[c2] - p[c2] q[c1]
      const double x = half == 0 ? p[c1] : -p[c2];
      const double y = half == 0 ? q[c2] : q[c1];
      hi[c][half] = x * y;
      if (!product_in_range(hi[c][half]) || (hi[c][half] == 0 && x != 0 && y != 0)) return false;
      lo[c][half] = std::fma(x, y, -hi[c][half]);
    }
  }
  // A filter first: each E*[c] to within a few ulps of itself (where its two products cancel,
  // their difference is exact), then the dot with a bound on its error; a sign the bound cannot
  // cross is the exact one (docs/derivations.md, "Exact edge sides without rationals").
  constexpr double u = 0x1p-53;
  double dot = 0, bound = 0;
  for (int c = 0; c < 3; ++c) {
    const double s1 = hi[c][0] + hi[c][1], s2 = lo[c][0] + lo[c][1], e = s1 + s2;
    const double we = w[c] * e;
    dot += we;
    bound +=
        std::abs(w[c]) * u * (std::abs(s1) + std::abs(s2) + std::abs(e)) + 4 * u * std::abs(we);
  }
  bound *= 1 + 16 * u;  // the bound's own arithmetic: at most 7 roundings
  if (std::abs(dot) > bound) {
    *sign = dot > 0 ? 1 : -1;
    return true;
  }
  double terms[24];
  int n = 0;
  for (int c = 0; c < 3; ++c)
    for (int half = 0; half < 2; ++half)
      for (const double part : {hi[c][half], lo[c][half]}) {
        const double wpart = w[c] * part;
        terms[n++] = wpart;
        terms[n++] = std::fma(w[c], part, -wpart);
      }
  *sign = sign_of_exact_sum(terms, n);
  return true;
}

}  // namespace

bool exact_edge_side_by_expansion(const LocalTriangle& t, int k, const Texel& x, int* side) {
  if (t.edge_zero[k]) {
    *side = 0;  // E* = 0, decided by plan(): the end of this function's search
    return true;
  }
  if (x.m > 4096 || !rounding_to_nearest()) return false;
  const int a = k, b = (k + 1) % 3;
  VOBB_ASSERT(t.p[a].allFinite() && t.p[b].allFinite(), "plan() keeps only finite faces");
  const bool canonical = t.id[a] < t.id[b];
  const Vec3& p = canonical ? t.p[a] : t.p[b];
  const Vec3& q = canonical ? t.p[b] : t.p[a];
  // m d* = (+-m, 2i + 1 - m, 2j + 1 - m) on the axes (k, a, b) of the cubemap face; the dot
  // first, then the components of E* in the order of the perturbation (see LocalTriangle).
  const int fk = x.face / 2, fa = (fk + 1) % 3, fb = (fk + 2) % 3;
  double w[3];
  w[fk] = x.face % 2 == 0 ? x.m : -x.m;
  w[fa] = 2 * x.i + 1 - x.m;
  w[fb] = 2 * x.j + 1 - x.m;
  int s = 0;
  if (!edge_dot_sign(p, q, w, &s)) return false;
  for (int c : {fa, fb, fk}) {
    if (s != 0) break;
    double unit[3] = {0, 0, 0};
    unit[c] = 1;
    if (!edge_dot_sign(p, q, unit, &s)) return false;
  }
  *side = canonical ? s : -s;  // E* = +-(p x q): the same for the two faces of an edge, negated
  return true;
}

int exact_edge_side(const LocalTriangle& t, int k, const Texel& x) {
  int side = 0;
  if (exact_edge_side_by_expansion(t, k, x, &side)) return side;
  return exact_edge_side_rational(t, k, x);
}

int exact_edge_side_rational(const LocalTriangle& t, int k, const Texel& x) {
  if (t.edge_zero[k]) return 0;
  const int a = k, b = (k + 1) % 3;
  VOBB_ASSERT(t.p[a].allFinite() && t.p[b].allFinite(), "plan() keeps only finite faces");
  const bool canonical = t.id[a] < t.id[b];
  const Vec3& p = canonical ? t.p[a] : t.p[b];
  const Vec3& q = canonical ? t.p[b] : t.p[a];
  // E* = +-(p x q), exactly: the same rationals for the two faces of an edge, negated.
  Rational E[3];
  exact_cross(p, q, E);
  if (!canonical)
    for (Rational& e : E) e = -e;
  // m d* = (+-m, 2i + 1 - m, 2j + 1 - m) on the axes (k, a, b) of the cubemap face.
  const int fk = x.face / 2, fa = (fk + 1) % 3, fb = (fk + 2) % 3;
  const Rational dot = (x.face % 2 == 0 ? x.m : -x.m) * E[fk] + (2 * x.i + 1 - x.m) * E[fa] +
                       (2 * x.j + 1 - x.m) * E[fb];
  if (sgn(dot) != 0) return sgn(dot);
  for (int c : {fa, fb, fk})
    if (sgn(E[c]) != 0) return sgn(E[c]);
  return 0;
}

PlanRounding analyse_plan_rounding(const BoxPlan& plan, int m, const RoundingModel& model) {
  PlanRounding out;
  if (plan.flat || plan.spans.empty()) return out;
  const double u = model.u;
  std::vector<uint16_t> terms(6 * static_cast<size_t>(m) * m, 0);
  auto add_term = [&](size_t texel) {
    out.pairs += 1;
    terms[texel] = static_cast<uint16_t>(std::min(65535, terms[texel] + 1));
  };
  for (const TexelSpan& span : plan.spans) {
    const LocalTriangle& t = plan.tris[span.tri];
    if (t.plane == 0) continue;
    const int k = span.face / 2, a = (k + 1) % 3, b = (k + 2) % 3;
    const double fn = pow2_normalizer(t.normal[0], t.normal[1], t.normal[2]);
    // zeta = plane / nd = (plane fn) / (nd fn) with |nd fn| up to 3 (|d_i| <= 1, |n_i fn| < 1):
    // a scaled plane below `tiny` may give a zeta that underflows to 0.
    const bool plane_underflows = std::abs(t.plane * fn) < model.tiny;
    double fe[3];  // the power-of-two scale of each edge cross (the shader's)
    for (int e = 0; e < 3; ++e)
      fe[e] = pow2_normalizer(t.edge_cross[e][0], t.edge_cross[e][1], t.edge_cross[e][2]);
    // The reference's edge tests use E* (exact), the evaluation edge_cross (E* rounded in
    // double): |d* . (E - E*)| <= gamma_2 || |p| x |q| ||_1, plus underflow (see edge_tie), in
    // the scaled units of `dot` below. Negligible against float's own error except at exact
    // ties, which it turns into uncertain pairs.
    double tie_term[3];
    for (int e = 0; e < 3; ++e)
      tie_term[e] = (2.01 * 0x1p-53 * abs_cross(t.p[e], t.p[(e + 1) % 3]).sum() + 0x1p-1070) *
                    fe[e] * (1 + 1e-12);
    for (int i = span.i0; i <= span.i1; ++i) {
      for (int j = span.j0; j <= span.j1; ++j) {
        const Texel x{span.face, i, j, m,
                      cubemap_direction(span.face, texel_center(i, m), texel_center(j, m))};
        const Vec3& d = x.d;
        // Edge tests: definite sides must agree; any uncertain one makes the pair uncertain.
        int definite = 0;
        bool unsure = false, miss = false;
        for (int e = 0; e < 3 && !miss; ++e) {
          int side;
          if (model.exact_edges) {
            side = cpu_edge_side(t, e, x);
            if (side == 0) miss = true;  // E* = 0: texel_hit reports no hit, as exactly
          } else {
            const Vec3& E = t.edge_cross[e];
            const double dot = d.dot(E) * fe[e];
            const double err = 8 * u * (std::abs(E[a]) + std::abs(E[b])) * fe[e] +
                               5 * u * d.cwiseAbs().dot(E.cwiseAbs()) * fe[e] +
                               (model.scaled_inputs ? model.tiny : model.tiny * fe[e]) +
                               tie_term[e];
            if (std::abs(dot) <= err) {
              unsure = true;
              continue;
            }
            side = dot > 0 ? 1 : -1;
          }
          if (miss) break;
          if (definite == 0)
            definite = side;
          else if (side != definite)
            miss = true;
        }
        if (miss) continue;
        const size_t texel = (static_cast<size_t>(span.face) * m + i) * m + j;
        if (unsure || plane_underflows) {
          out.uncertain += 1;
          add_term(texel);
          continue;
        }
        const double nd = t.normal.dot(d);
        const double r = (8 * u * (std::abs(t.normal[a]) + std::abs(t.normal[b])) +
                          5 * u * d.cwiseAbs().dot(t.normal.cwiseAbs())) /
                         std::abs(nd);
        if (!(r < 0.5)) {
          out.uncertain += 1;
          add_term(texel);
          continue;
        }
        const double zeta = t.plane / nd;
        if (zeta <= 0) continue;  // r < 1/2 keeps nd's sign, rounding keeps the plane's: all agree
        const double z = (1 + r) / (1 - r) * (1 + u) * (1 + 3 * u) - 1;
        const bool near_one = std::abs(zeta - 1) <= zeta * z;
        if (zeta >= 1 && !near_one) {  // beyond the box in both: nothing, or exactly -s (far)
          if (plan.far_count) {
            out.sum_abs += 1;
            add_term(texel);
          }
          continue;
        }
        const double z3 = std::pow(1 + z, 3) * (1 + u) * (1 + u) - 1;
        const double c3 = zeta * zeta * zeta;
        const double value_err = c3 * z3 + u * (1 + c3 * (1 + z3));
        add_term(texel);
        out.sum_abs += std::min(1.0, (plan.far_count ? c3 : std::abs(1 - c3)) + value_err);
        out.value_errors += value_err + (near_one ? std::abs(1 - c3) : 0);
      }
    }
  }
  out.most_per_texel = *std::max_element(terms.begin(), terms.end());
  return out;
}

// Derivation: docs/derivations.md, "The CPU twin's sum".
double cpu_rounding_bound(const BoxPlan& plan, int m) {
  if (plan.flat) return 0.0;
  constexpr double u = 0x1p-53;
  const PlanRounding r =
      analyse_plan_rounding(plan, m, RoundingModel{u, 3 * 0x1p-1074, false, true});
  const double n = r.pairs + 6;
  const double gamma = n * u / (1 - n * u);
  const double texel_weight = 4.0 / (3.0 * m * m);
  const double magnitude = std::abs(plan.constant) + texel_weight * (r.sum_abs + 2 * r.uncertain);
  return plan.frame.volume_scale *
         (texel_weight * (r.value_errors + 2 * r.uncertain) + gamma * magnitude);
}

namespace {

// Every field as a new BoxPlan has it, but the vectors' capacity.
void reset_plan(BoxPlan* out) {
  BoxPlan& plan = *out;
  std::vector<LocalTriangle> tris = std::move(plan.tris);
  std::vector<TexelSpan> spans = std::move(plan.spans);
  tris.clear();
  spans.clear();
  plan = BoxPlan{};
  plan.tris = std::move(tris);
  plan.spans = std::move(spans);
}

// Marks a box whose view of the mesh the plan's doubles cannot hold (see BoxPlan::unresolved).
void unresolve(const Obb& box, BoxPlan* out) {
  BoxPlan& plan = *out;
  plan.unresolved = true;
  plan.constant = 4.0;
  plan.tris.clear();
  plan.spans.clear();
  plan.centre_near_surface = false;
  if (!(plan.frame.volume_scale > 0) || !std::isfinite(plan.frame.volume_scale))
    plan.frame.volume_scale = volume(box) / 8;  // invalid frame: volume() is the scale
}

// Whether face t, whose plan holds e1 = p1 - p0 and e2 = p2 - p0 and lies within `slack` of the
// exact face, may pass so near the centre that the plan's hits on it cannot be trusted
// (LocalTriangle::near_centre); where it may not, each hit's depth is within 2^-20 relative.
// Derivation: docs/derivations.md, "Faces near the centre".
bool face_near_centre(const LocalTriangle& t, const Vec3& e1, const Vec3& e2, double slack) {
  constexpr double u = 0x1p-53;
  const Vec3 spread = e1.cwiseAbs().cwiseMax(e2.cwiseAbs());
  const double delta = 8 * u * abs_cross(e1, e2).dot(spread) +
                       4 * u * t.normal.cwiseAbs().dot(t.p[0].cwiseAbs()) +
                       0x1p-1072 * (spread.sum() + t.p[0].cwiseAbs().sum() + 1);
  return !(std::abs(t.plane) > (2 * slack * t.normal.norm() + (0x1p20 + 1) * delta) * (1 + 1e-12));
}

// Local units. Culling only needs to be conservative: a face is dropped only when its
// exact coordinates (within local_error of the plan's) miss the cube on some axis.
constexpr double kCullMargin = 1e-9;

// Adds mesh face f, in the plan's local coordinates, and its texel spans at resolution m to
// the plan, unless culling shows that it misses the cube; a face that the plan's doubles cannot
// hold marks the plan unresolved instead.
void consider_face(const Mesh& mesh, int32_t f, int m, bool no_far_clip, bool culling,
                   BoxPlan* out) {
  BoxPlan& plan = *out;
  if (plan.unresolved) return;  // the plan is dropped anyway (unresolve below)
  LocalTriangle t;
  Vec3 err = Vec3::Zero();  // per axis, the most any of the three vertices may be off
  for (int k = 0; k < 3; ++k) {
    t.id[k] = mesh.faces[f][k];
    const Vec3& v = mesh.vertices[t.id[k]];
    t.p[k] = plan.frame.local(v);
    err = err.cwiseMax(plan.frame.local_error(v));
  }
  if (!plan.far_count && culling) {
    for (int axis = 0; axis < 3; ++axis) {
      const double lo = std::min({t.p[0][axis], t.p[1][axis], t.p[2][axis]});
      const double hi = std::max({t.p[0][axis], t.p[1][axis], t.p[2][axis]});
      const double margin = std::max(kCullMargin, err[axis]);
      if (lo > 1 + margin || hi < -1 - margin) return;  // misses the cube
    }
  }
  // Every point of the exact face lies within `slack` of the plan's (barycentric weights).
  const double slack = err.norm() * (1 + 1e-15);
  // Kept faces must lie within 2^300 box units, so that crosses (2^601), normals (2^603),
  // planes (2^905) and the error terms built from them stay finite, and their error bound
  // must be finite. (Culling is sound with overflowed coordinates: an infinite coordinate
  // stands for one beyond 2^1024 box units, and an infinite error keeps the face.)
  const double far = std::max(
      {t.p[0].cwiseAbs().maxCoeff(), t.p[1].cwiseAbs().maxCoeff(), t.p[2].cwiseAbs().maxCoeff()});
  if (!(far <= 0x1p300) || !(slack < HUGE_VAL)) {
    plan.unresolved = true;
    return;
  }
  for (int k = 0; k < 3; ++k) {
    const int a = k, b = (k + 1) % 3;
    t.edge_cross[k] = t.id[a] < t.id[b] ? Vec3(t.p[a].cross(t.p[b])) : Vec3(-t.p[b].cross(t.p[a]));
    t.edge_tie[k] = edge_tie(t.edge_cross[k], t.p[a], t.p[b]);
    t.edge_zero[k] = cross_is_exactly_zero(t.edge_cross[k], t.p[a], t.p[b]);
  }
  const Vec3 e1 = t.p[1] - t.p[0], e2 = t.p[2] - t.p[0];
  t.normal = e1.cross(e2);
  if (plan.frame.mirrored) t.normal = -t.normal;
  t.plane = t.normal.dot(t.p[0]);
  if (!plan.far_count) t.near_centre = face_near_centre(t, e1, e2, slack);
  const int32_t index = static_cast<int32_t>(plan.tris.size());
  bool used = false;
  for (int face = 0; face < 6; ++face) {
    TexelSpan span;
    if (!texel_span(t, face, m, no_far_clip, slack, &span)) continue;
    span.tri = index;
    plan.spans.push_back(span);
    used = true;
  }
  if (used) plan.tris.push_back(t);
  if (used && t.near_centre) plan.centre_near_surface = true;
}

// Calls visit(f) for every face of the mesh whose bounds (in `faces`) may meet the box, in mesh
// order.
template <class Visit>
void for_each_face_near(const Mesh& mesh, const AabbTree& faces, const Obb& box,
                        const Visit& visit) {
  Aabb world;
  for (const Vec3& c : corners(box)) world.extend(c);
  // The corners are rounded at the scale of the coordinates, not of the box (a box of size
  // 0.01 at 1e6 has corners off by 1e-10): the pad covers both, far above a few roundings.
  const double scale = std::max(world.lo.cwiseAbs().maxCoeff(), world.hi.cwiseAbs().maxCoeff());
  const Vec3 pad = Vec3::Constant(1e-9 * ((world.hi - world.lo).norm() + scale));
  world.lo -= pad;
  world.hi += pad;
  // Faces in mesh order, as without culling: the same plan, the same float blend order.
  thread_local std::vector<int32_t> ids;  // scratch, kept for its capacity
  ids.clear();
  faces.for_each_overlap(world, [&](int32_t f) { ids.push_back(f); });
  const size_t n_faces = mesh.faces.size();
  if (ids.size() * 256 < n_faces) {  // few: sorting costs less than a pass over all faces
    std::sort(ids.begin(), ids.end());
    for (int32_t f : ids) visit(f);
  } else {  // many (a box over much of the mesh): a bit per face, read in order
    thread_local std::vector<uint64_t> bits;
    bits.assign((n_faces + 63) / 64, 0);
    for (int32_t f : ids) bits[static_cast<size_t>(f) >> 6] |= uint64_t{1} << (f & 63);
    for (size_t w = 0; w < bits.size(); ++w)
      for (uint64_t word = bits[w]; word != 0; word &= word - 1)
        visit(static_cast<int32_t>(64 * w + static_cast<size_t>(__builtin_ctzll(word))));
  }
}

}  // namespace

BoxPlanner::BoxPlanner(const Mesh& mesh) : mesh_(mesh), faces_(AabbTree::over_faces(mesh)) {}

BoxPlan BoxPlanner::plan(const Obb& box, int m) const {
  BoxPlan plan;
  this->plan(box, m, &plan);
  return plan;
}

void BoxPlanner::plan(const Obb& box, int m, BoxPlan* out) const {
  VOBB_ASSERT(m >= 1, "cubemap resolution m >= 1");
  BoxPlan& plan = *out;
  reset_plan(&plan);
  if (volume(box) == 0.0) {  // a flat box (or one whose volume underflows): OBV 0
    plan.flat = true;
    return;
  }
  plan.frame = box_frame(box);
  if (plan.frame.valid && !(plan.frame.volume_scale > 0)) {  // underflows: OBV below 2^-1074 or so
    plan.flat = true;
    return;
  }
  if (!plan.frame.valid) {
    unresolve(box, &plan);
    return;
  }
  plan.where = locate_point(mesh_, faces_, box.center);
  plan.far_count = plan.where == Location::kOnSurface;
  plan.constant = plan.far_count || plan.where == Location::kOutside ? 8.0 : 0.0;

  // Without culling, spans also cover the faces' parts beyond the box, as a renderer that
  // draws the whole mesh per cubemap face would.
  const bool no_far_clip = plan.far_count || !culling_;
  auto consider = [&](int32_t f) { consider_face(mesh_, f, m, no_far_clip, culling_, &plan); };
  if (plan.far_count || !culling_) {
    for (size_t f = 0; f < mesh_.faces.size(); ++f) consider(static_cast<int32_t>(f));
  } else {
    for_each_face_near(mesh_, faces_, box, consider);
  }
  if (plan.unresolved) unresolve(box, &plan);
}

}  // namespace vobb
