// OBV of one box on the clipping path (b), in the box's own frame.
//
// The linear map T(p) = W (p - c), with rows w_k = u_{k+1} x u_{k+2} (u_k = h_k a_k), sends the
// box's certified solid to the cube |T_k| <= R = |det U| and has det W = det(U)^2 > 0, so it
// keeps orientation and scales volumes by det(U)^2. All of it is exact in rationals.
// In T-space, the signed prism decomposition along -T_2 gives
//   vol(X ∩ cube) = sum_T ∫_{shadow(T) ∩ [-R,R]^2} (clamp(z_T, -R, R) + R) dA,
// with the shadow's orientation giving each face's sign. A face inside the column and the
// slab is a closed form (signed shadow area times mean height); only faces crossing the
// column's sides or the slab's planes are clipped, and those clips are axis-aligned.
#include <cmath>
#include <unordered_map>

#include "exact/outer_volume.h"

namespace vobb::exact {
namespace {

struct Q3 {
  Rational x[3];
};

// Twice the signed area of the shadow (x, y) of triangle abc.
Rational cross2(const Q3& a, const Q3& b, const Q3& c) {
  return (b.x[0] - a.x[0]) * (c.x[1] - a.x[1]) - (b.x[1] - a.x[1]) * (c.x[0] - a.x[0]);
}

// Keeps the part of the polygon where sign * x[axis] <= bound (Sutherland-Hodgman; keeps
// the cycle's orientation).
void clip_axis(std::vector<Q3>* poly, int axis, int sign, const Rational& bound) {
  const std::vector<Q3>& in = *poly;
  const size_t n = in.size();
  if (n == 0) return;
  std::vector<Rational> val(n);
  bool any_out = false, any_in = false;
  for (size_t i = 0; i < n; ++i) {
    val[i] = (sign > 0 ? in[i].x[axis] : Rational(-in[i].x[axis])) - bound;
    any_out |= sgn(val[i]) > 0;
    any_in |= sgn(val[i]) <= 0;
  }
  if (!any_out) return;
  std::vector<Q3> out;
  if (any_in) {
    for (size_t i = 0; i < n; ++i) {
      const size_t j = (i + 1) % n;
      const int si = sgn(val[i]), sj = sgn(val[j]);
      if (si <= 0) out.push_back(in[i]);
      if (si * sj < 0) {
        const Rational t = val[i] / (val[i] - val[j]);
        Q3 p;
        for (int k = 0; k < 3; ++k) p.x[k] = in[i].x[k] + t * (in[j].x[k] - in[i].x[k]);
        out.push_back(std::move(p));
      }
    }
  }
  *poly = out.size() >= 3 ? std::move(out) : std::vector<Q3>();
}

// 6 x the integral over the polygon's shadow of clamp(z, -R, R) + R.
Rational column_integral6(std::vector<Q3> poly, const Rational& R) {
  bool all_mid = true, all_top = true;
  for (const Q3& p : poly) {
    if (p.x[2] > R || p.x[2] < -R) all_mid = false;
    if (p.x[2] < R) all_top = false;
  }
  std::vector<Q3> top, mid;
  if (all_top) {
    top = std::move(poly);
  } else if (all_mid) {
    mid = std::move(poly);
  } else {
    top = poly;
    clip_axis(&top, 2, -1, -R);  // z >= R
    mid = std::move(poly);
    clip_axis(&mid, 2, 1, R);    // z <= R
    clip_axis(&mid, 2, -1, R);   // z >= -R
  }
  Rational sum = 0;
  for (size_t k = 1; k + 1 < top.size(); ++k) sum += 6 * R * cross2(top[0], top[k], top[k + 1]);
  for (size_t k = 1; k + 1 < mid.size(); ++k)
    sum += cross2(mid[0], mid[k], mid[k + 1]) * (mid[0].x[2] + mid[k].x[2] + mid[k + 1].x[2] + 3 * R);
  return sum;
}

}  // namespace

Rational ClipSolver::obv(const Obb& box) const {
  const ExactBoxFrame frame(box);
  const Rational(&c)[3] = frame.c;
  const Rational(&w)[3][3] = frame.w;
  const Rational& det = frame.det;
  double wd[3][3];
  for (int k = 0; k < 3; ++k)
    for (int i = 0; i < 3; ++i) wd[k][i] = w[k][i].get_d();
  if (sgn(det) == 0) return Rational(0);  // a flat box has no volume, inside or out
  const Rational R = abs(det);
  const double Rd = R.get_d();

  // Faces that may reach the column {|T_0|, |T_1| <= R, T_2 >= -R}: a conservative test on
  // boxes in double. Every quantity below is off by a few units of rounding (u = 2^-53) of
  // the magnitudes it is computed from: 0.5 (lo + hi) - c by 2u (|lo| + |hi| + |c|) per axis,
  // which is at the coordinates' scale, not the box's (a box of size 0.01 at 1e6 has its
  // faces' centres rounded by 1e-10, its own size's 1e-8); the products and sums of T by 3u of
  // sum |w| (|lo| + |hi| + |c|); w's and R's conversion to double by u of themselves. The pad,
  // 1e-9 of the sum of those magnitudes, is far above all of it. Where w, R or the products
  // are subnormal those errors are absolute instead: 2^-1074 for each conversion of w (times
  // |lo| + |hi| + |c|) and of R, 2^-1075 for each of the 20-odd operations; the floor
  // 2^-1060 (1 + sum (|lo| + |hi| + |c|)) is above all of that.
  const double cd[3] = {box.center[0], box.center[1], box.center[2]};
  auto accept = [&](const Aabb& b) {
    if (b.empty()) return false;
    for (int k = 0; k < 3; ++k) {
      double mid = 0, rad = 0, scale = 0, coords = 0;
      for (int i = 0; i < 3; ++i) {
        mid += (0.5 * (b.lo[i] + b.hi[i]) - cd[i]) * wd[k][i];
        rad += std::abs(wd[k][i]) * 0.5 * (b.hi[i] - b.lo[i]);
        const double size = std::abs(b.lo[i]) + std::abs(b.hi[i]) + std::abs(cd[i]);
        scale += std::abs(wd[k][i]) * size;
        coords += size;
      }
      const double pad = 1e-9 * (scale + rad + Rd) + 0x1p-1060 * (1 + coords);
      if (mid - rad > Rd + pad && k < 2) return false;  // beyond the +side
      if (mid + rad < -Rd - pad) return false;           // beyond the -side (or below)
    }
    return true;
  };
  std::unordered_map<int32_t, Q3> tmap;
  auto to_t = [&](int32_t v) -> const Q3& {
    auto it = tmap.find(v);
    if (it != tmap.end()) return it->second;
    Q3 q;
    Rational d[3];
    for (int i = 0; i < 3; ++i) d[i] = Rational(mesh_.vertices[v][i]) - c[i];
    for (int k = 0; k < 3; ++k) q.x[k] = d[0] * w[k][0] + d[1] * w[k][1] + d[2] * w[k][2];
    return tmap.emplace(v, std::move(q)).first->second;
  };
  std::vector<Rational> terms;
  faces_.for_each_accepted(accept, [&](int32_t f) {
    std::vector<Q3> poly = {to_t(mesh_.faces[f][0]), to_t(mesh_.faces[f][1]), to_t(mesh_.faces[f][2])};
    // Exact quick rejections: the shadow beyond one side of the square, or the face below.
    for (int k = 0; k < 2; ++k) {
      if (poly[0].x[k] > R && poly[1].x[k] > R && poly[2].x[k] > R) return;
      if (poly[0].x[k] < -R && poly[1].x[k] < -R && poly[2].x[k] < -R) return;
    }
    if (poly[0].x[2] < -R && poly[1].x[2] < -R && poly[2].x[2] < -R) return;
    for (int k = 0; k < 2; ++k) {
      clip_axis(&poly, k, 1, R);
      clip_axis(&poly, k, -1, R);
    }
    if (poly.size() < 3) return;
    Rational t = column_integral6(std::move(poly), R);
    if (sgn(t) != 0) terms.push_back(std::move(t));
  });
  // vol_world(X ∩ box) = vol_T / det(U)^2, and vol(box) = 8 |det U|.
  const Rational inside = sum_pairwise(terms) / (6 * R * R);
  return 8 * R - inside;
}

}  // namespace vobb::exact
