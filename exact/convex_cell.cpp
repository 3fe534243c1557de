#include "exact/convex_cell.h"

#include <cmath>
#include <limits>

#include "common/status.h"

namespace vobb::exact {
namespace {

Rational det3(const Rational* a, const Rational* b, const Rational* c) {
  return a[0] * (b[1] * c[2] - b[2] * c[1]) - a[1] * (b[0] * c[2] - b[2] * c[0]) +
         a[2] * (b[0] * c[1] - b[1] * c[0]);
}

// Largest double <= q, and smallest double >= q.
double round_down(const Rational& q) {
  double d = q.get_d();  // truncates toward zero
  if (Rational(d) > q) d = std::nextafter(d, -std::numeric_limits<double>::infinity());
  return d;
}
double round_up(const Rational& q) {
  double d = q.get_d();
  if (Rational(d) < q) d = std::nextafter(d, std::numeric_limits<double>::infinity());
  return d;
}

}  // namespace

void HalfSpace::set_shadow() {
  for (int i = 0; i < 3; ++i) nd[i] = n[i].get_d();
  dd = d.get_d();
}

HalfSpace HalfSpace::complement() const {
  HalfSpace h;
  for (int i = 0; i < 3; ++i) h.n[i] = -n[i];
  h.d = -d;
  h.set_shadow();
  return h;
}

void ConvexCell::refresh_shadow() {
  vd_.resize(v_.size());
  for (size_t i = 0; i < v_.size(); ++i)
    for (int k = 0; k < 3; ++k) vd_[i][k] = v_[i].x[k].get_d();
}

Side ConvexCell::classify(const HalfSpace& h) const {
  // n.v - d in double: each of the 7 inputs is within one ulp of its exact value: 2 eps
  // relative, or, where it is subnormal (or flushed to 0), 2^-1074 absolute. The 3 products
  // and 3 sums add at most 6 roundings of eps/2: the result is within 8 eps (sum |n_i v_i| +
  // |d|) of the exact value (16 eps is used), plus the subnormal inputs' absolute errors times
  // what they multiply: 2^-1074 (sum |n_i| + sum |v_i| + 1), taken as 2^-1072 of it. An absolute
  // 2^-1000 covers underflow in the products and sums.
  constexpr double kEps = std::numeric_limits<double>::epsilon();
  static const double kTiny = std::ldexp(1.0, -1000);
  static const double kSubnormal = std::ldexp(1.0, -1072);
  const double n_sum = std::abs(h.nd[0]) + std::abs(h.nd[1]) + std::abs(h.nd[2]);
  bool all_in = true, all_out = true;
  for (const Vec3& p : vd_) {
    const double a = h.nd[0] * p[0], b = h.nd[1] * p[1], c = h.nd[2] * p[2];
    const double v = a + b + c - h.dd;
    const double err = 16 * kEps * (std::abs(a) + std::abs(b) + std::abs(c) + std::abs(h.dd)) +
                       kTiny +
                       kSubnormal * (n_sum + std::abs(p[0]) + std::abs(p[1]) + std::abs(p[2]) + 1);
    if (!(v < -err)) all_in = false;  // surely inside needs v surely below 0
    if (!(v > err)) all_out = false;
    if (!all_in && !all_out) return Side::kCrossing;
  }
  return all_in ? Side::kInside : Side::kOutside;
}

std::array<HalfSpace, 6> box_half_spaces(const Obb& box) {
  const ExactBoxFrame f(box);
  const Rational& det = f.det;
  const Rational(&w)[3][3] = f.w;
  const Rational(&c)[3] = f.c;
  VOBB_ASSERT(sgn(det) != 0, "box_half_spaces on a box of zero volume");
  const int sigma = sgn(det);
  const Rational abs_det = abs(det);
  // t_k <= 1:  (s w_k) . p <= |D| + s w_k . c;   t_k >= -1:  (-s w_k) . p <= |D| - s w_k . c.
  std::array<HalfSpace, 6> out;
  for (int k = 0; k < 3; ++k) {
    Rational wc = w[k][0] * c[0] + w[k][1] * c[1] + w[k][2] * c[2];
    if (sigma < 0) wc = -wc;
    HalfSpace& plus = out[2 * k];
    HalfSpace& minus = out[2 * k + 1];
    for (int i = 0; i < 3; ++i) {
      plus.n[i] = sigma > 0 ? w[k][i] : Rational(-w[k][i]);
      minus.n[i] = -plus.n[i];
    }
    plus.d = abs_det + wc;
    minus.d = abs_det - wc;
    plus.set_shadow();
    minus.set_shadow();
  }
  return out;
}

ConvexCell ConvexCell::from_box(const Obb& box) {
  ConvexCell cell;
  const ExactBoxFrame f(box);
  const int orientation = sgn(f.det);
  if (orientation == 0) return cell;  // a flat box encloses no volume: the empty cell
  cell.v_.resize(8);
  for (int c = 0; c < 8; ++c) f.corner(c, cell.v_[c].x);
  for (const auto& q : kBoxQuads) {
    if (orientation > 0)
      cell.faces_.push_back({q[0], q[1], q[2], q[3]});
    else
      cell.faces_.push_back({q[3], q[2], q[1], q[0]});  // left-handed axes mirror the box
  }
  cell.refresh_shadow();
  return cell;
}

void ConvexCell::clip(const HalfSpace& h) {
  if (faces_.empty()) return;
  const int n = static_cast<int>(v_.size());
  std::vector<Rational> value(n);
  std::vector<int> side(n);
  bool any_pos = false, any_neg = false;
  for (int i = 0; i < n; ++i) {
    value[i] = h.n[0] * v_[i].x[0] + h.n[1] * v_[i].x[1] + h.n[2] * v_[i].x[2] - h.d;
    side[i] = sgn(value[i]);
    any_pos |= side[i] > 0;
    any_neg |= side[i] < 0;
  }
  if (!any_pos) return;  // entirely kept
  if (!any_neg) {        // nothing strictly inside: empty, or flat on the plane
    v_.clear();
    vd_.clear();
    faces_.clear();
    return;
  }
  std::vector<std::vector<int>> kept = clipped_faces(faces_, side, n, [&](int a, int b) {
    const Rational t = value[a] / (value[a] - value[b]);
    QPoint p;
    for (int i = 0; i < 3; ++i) p.x[i] = v_[a].x[i] + t * (v_[b].x[i] - v_[a].x[i]);
    v_.push_back(std::move(p));
    return static_cast<int>(v_.size()) - 1;
  });
  std::vector<QPoint> nv;
  for (int old : compact_faces(&kept, v_.size())) nv.push_back(std::move(v_[old]));
  v_ = std::move(nv);
  faces_ = std::move(kept);
  if (faces_.size() < 4) {  // cannot enclose volume
    v_.clear();
    faces_.clear();
  }
  refresh_shadow();
}

Rational ConvexCell::volume() const {
  if (faces_.empty()) return Rational(0);
  const QPoint& p = v_[faces_[0][0]];
  std::vector<Rational> terms;
  for (const std::vector<int>& f : faces_) {
    Rational a[3];
    for (int i = 0; i < 3; ++i) a[i] = v_[f[0]].x[i] - p.x[i];
    for (size_t k = 1; k + 1 < f.size(); ++k) {
      Rational b[3], c[3];
      for (int i = 0; i < 3; ++i) {
        b[i] = v_[f[k]].x[i] - p.x[i];
        c[i] = v_[f[k + 1]].x[i] - p.x[i];
      }
      Rational t = det3(a, b, c);
      if (sgn(t) != 0) terms.push_back(std::move(t));
    }
  }
  return sum_pairwise(terms) / 6;
}

Aabb ConvexCell::bounds() const {
  Aabb b;
  for (const QPoint& p : v_)
    for (int i = 0; i < 3; ++i) {
      b.lo[i] = std::min(b.lo[i], round_down(p.x[i]));
      b.hi[i] = std::max(b.hi[i], round_up(p.x[i]));
    }
  return b;
}

}  // namespace vobb::exact
