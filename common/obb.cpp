#include "common/obb.h"

#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>
#include <limits>

#include "common/box_frame_clip.h"
#include "common/solidity.h"
#include "common/status.h"
#include "common/text_util.h"

namespace vobb {
namespace {
constexpr double kEps = std::numeric_limits<double>::epsilon();
// Below this, products in the containment filter may underflow (2^-1022 is the least normal;
// the filter multiplies three such factors at most): such cases take the exact path.
const double kFilterFloor = std::ldexp(1.0, -600);
}  // namespace

double volume(const Obb& box) {
  const double det = box.axes[0].dot(box.axes[1].cross(box.axes[2]));
  // Multiplied as mantissas in [0.5, 1) with the exponents summed apart and applied once, so
  // that no partial product underflows or overflows: left to right, h0 h1 of a needle box
  // (h = 2^-600, 2^-500, 2^200) underflowed to 0 and the box counted as flat. The relative
  // error is that of 5 products (the estimators' round-off term, fast/cubemap_bound.h),
  // plus the one final rounding where the volume itself is subnormal.
  double mantissa = 1;
  long exponent = 0;
  for (const double x : {8.0, box.half[0], box.half[1], box.half[2], std::abs(det)}) {
    int e;
    mantissa *= std::frexp(x, &e);
    exponent += e;
    mantissa = std::frexp(mantissa, &e);
    exponent += e;
  }
  if (mantissa == 0 || !std::isfinite(mantissa)) return mantissa;
  return std::ldexp(mantissa, static_cast<int>(std::clamp(exponent, -2000L, 2000L)));
}

std::string box_defect(const Obb& b) {
  if (!b.center.allFinite() || !b.half.allFinite()) return "non-finite box values";
  for (const Vec3& a : b.axes)
    if (!a.allFinite()) return "non-finite box axes";
  if ((b.half.array() < 0).any()) return "negative half extent";
  // 1 / h may overflow in the box's frame (fast/cubemap.h).
  if ((b.half.array() > 0 && b.half.array() < 0x1p-1022).any())
    return "subnormal half extent (below 2^-1022)";
  for (int i = 0; i < 3; ++i)
    for (int k = i; k < 3; ++k) {
      const double dev = std::abs(b.axes[i].dot(b.axes[k]) - (i == k ? 1.0 : 0.0));
      if (!(dev <= 1e-5))
        return "axes are not orthonormal (a" + std::to_string(i) + " . a" + std::to_string(k) +
               " is off by " + format_double(dev) + ")";
    }
  static_assert(kMaxBoxReach == 4 * kMaxCoordinate);
  for (int j = 0; j < 3; ++j) {
    const double reach = std::abs(b.center[j]) + b.half[0] * std::abs(b.axes[0][j]) +
                         b.half[1] * std::abs(b.axes[1][j]) + b.half[2] * std::abs(b.axes[2][j]);
    if (!(reach <= kMaxBoxReach)) return "extends beyond +-2^242 (about 7.1e72)";
  }
  return "";
}

std::array<Vec3, 8> corners(const Obb& box) {
  std::array<Vec3, 8> out;
  for (int i = 0; i < 8; ++i) {
    Vec3 p = box.center;
    for (int k = 0; k < 3; ++k) p += ((i >> k) & 1 ? 1.0 : -1.0) * box.half[k] * box.axes[k];
    out[i] = p;
  }
  return out;
}

std::array<Vec3, 3> orthonormalize(const std::array<Vec3, 3>& axes) {
  Vec3 a0 = axes[0].normalized();
  Vec3 a1 = (axes[1] - axes[1].dot(a0) * a0).normalized();
  Vec3 a2 = a0.cross(a1).normalized();
  // One more pass removes the residual of the first projection.
  a1 = (a1 - a1.dot(a0) * a0).normalized();
  return {a0, a1, a2};
}

double fit_slack(const Obb& box, double mesh_scale) {
  // Rounding in one projection p.a (3 products, 2 sums) is below 3 eps |p|; rebuilding the
  // centre from the projected mid-points adds 3 eps |c|; the stored axes are orthonormal to
  // about 2 eps, which moves a parallelepiped coordinate by 2 eps |p - c|. 16 eps times the
  // largest of those lengths covers their sum with room to spare. Where that is below the
  // least normal double (tiny coordinates, whose products round by up to 2^-1074 absolute), it
  // is raised to it: no half extent fit_obb pads is then subnormal (obb.h, box_defect).
  const double scale = std::max(mesh_scale, box.center.cwiseAbs().maxCoeff());
  return std::max(16.0 * kEps * scale, std::numeric_limits<double>::min());
}

Obb fit_obb(const Mesh& mesh, const std::vector<int32_t>& faces,
            const std::array<Vec3, 3>& in_axes) {
  VOBB_ASSERT(!faces.empty(), "fit_obb needs at least one face");
  Obb box;
  box.axes = orthonormalize(in_axes);
  Vec3 lo = Vec3::Constant(std::numeric_limits<double>::infinity());
  Vec3 hi = -lo;
  double scale = 0.0;
  for (int32_t f : faces) {
    for (int j = 0; j < 3; ++j) {
      const Vec3& p = mesh.corner(f, j);
      scale = std::max(scale, p.cwiseAbs().maxCoeff());
      for (int k = 0; k < 3; ++k) {
        const double s = p.dot(box.axes[k]);
        lo[k] = std::min(lo[k], s);
        hi[k] = std::max(hi[k], s);
      }
    }
  }
  box.center = Vec3::Zero();
  for (int k = 0; k < 3; ++k) {
    box.center += (0.5 * (lo[k] + hi[k])) * box.axes[k];
    box.half[k] = 0.5 * (hi[k] - lo[k]);
  }
  double pad = fit_slack(box, scale);
  const Vec3 tight = box.half;
  // The padding is derived to suffice; the exact check makes sure of it. Should a vertex still
  // fall outside (it never has), the padding doubles until the check passes.
  for (int attempt = 0; attempt < 64; ++attempt, pad *= 2) {
    box.half = tight + Vec3::Constant(pad);
    ExactBoxContainment inside(box);
    bool all_in = true;
    for (int32_t f : faces) {
      for (int j = 0; j < 3 && all_in; ++j) all_in = inside.contains(mesh.corner(f, j));
      if (!all_in) break;
    }
    if (all_in) return box;
  }
  VOBB_ASSERT(false, "fit_obb could not make a conservative box");
  return box;
}

bool boxes_apart(const Obb& a, const Obb& b) {
  const Vec3 d = b.center - a.center;
  // Every projection below is a few products and sums of numbers no larger than `scale`: their
  // rounding is far below 1e-12 of it, so a gap wider than that is a true gap. Any direction
  // separates convex sets, so the axes need not be exactly unit or orthogonal.
  const double scale = d.cwiseAbs().sum() + a.half.sum() + b.half.sum();
  const double slack = 1e-12 * scale + 1e-300;
  auto split_by = [&](const Vec3& axis) {
    const double n = axis.norm();
    if (!(n > 1e-6)) return false;  // parallel edges: a degenerate axis decides nothing
    const Vec3 u = axis / n;
    double ra = 0, rb = 0;
    for (int k = 0; k < 3; ++k) {
      ra += a.half[k] * std::abs(u.dot(a.axes[k]));
      rb += b.half[k] * std::abs(u.dot(b.axes[k]));
    }
    return std::abs(u.dot(d)) > ra + rb + slack;
  };
  return any_separating_axis(a, b, split_by);
}

std::vector<Obb> boxes_meeting(const Obb& b, const std::vector<Obb>& pool) {
  std::vector<Obb> out;
  for (const Obb& o : pool)
    if (!boxes_apart(b, o)) out.push_back(o);
  return out;
}

Obb rotated_box(const Vec3& c, const Vec3& half, double angle, const Vec3& axis) {
  Obb b;
  b.center = c;
  b.half = half;
  const Eigen::Matrix3d r = Eigen::AngleAxisd(angle, axis.normalized()).toRotationMatrix();
  b.axes = {r.col(0), r.col(1), r.col(2)};
  return b;
}

ExactBoxFrame::ExactBoxFrame(const Obb& box) {
  box_clip::Frame<Rational> f = box_clip::make_frame<Rational>(box);
  for (int k = 0; k < 3; ++k) {
    c[k] = std::move(f.c[k]);
    for (int i = 0; i < 3; ++i) {
      u[k][i] = std::move(f.u[k][i]);
      w[k][i] = std::move(f.w[k][i]);
    }
  }
  det = std::move(f.det);
}

Rational exact_volume(const Obb& box) { return 8 * abs(ExactBoxFrame(box).det); }

void ExactBoxFrame::corner(int index, Rational out[3]) const {
  for (int i = 0; i < 3; ++i) {
    out[i] = c[i];
    for (int k = 0; k < 3; ++k) {
      if ((index >> k) & 1)
        out[i] += u[k][i];
      else
        out[i] -= u[k][i];
    }
  }
}

namespace {
// x * 2^s, rounded toward zero to a double (off by under 2 eps of it where it is normal).
double scaled_shadow(const Rational& x, long s) {
  Rational y;
  if (s >= 0)
    mpq_mul_2exp(y.get_mpq_t(), x.get_mpq_t(), static_cast<mp_bitcnt_t>(s));
  else
    mpq_div_2exp(y.get_mpq_t(), x.get_mpq_t(), static_cast<mp_bitcnt_t>(-s));
  return y.get_d();
}
}  // namespace

ExactBoxContainment::ExactBoxContainment(const Obb& box) : frame_(box) {
  const long e = box_clip::frame_exponent(box);
  scale_ = std::ldexp(1.0, static_cast<int>(-e));
  for (int k = 0; k < 3; ++k) {
    cd_[k] = box.center[k];
    wd_abs_sum_[k] = 0;
    for (int i = 0; i < 3; ++i) {
      wd_[k][i] = scaled_shadow(frame_.w[k][i], -2 * e);
      wd_abs_sum_[k] += std::abs(wd_[k][i]);
    }
  }
  det_sign_ = sgn(frame_.det);
  abs_det_ = abs(frame_.det);
  abs_det_d_ = scaled_shadow(abs_det_, -3 * e);
  if (det_sign_ == 0)
    for (int k = 0; k < 3; ++k)
      if (box.half[k] != 0 && !box.axes[k].isZero()) spans_[span_count_++] = k;
}

// A flat box is {c + sum over spanning axes k of t_k u_k : |t_k| <= 1}. With d = p - c:
//  - no spanning axis: p == c;
//  - one, u: d parallel to u (d x u = 0) and |d . u| <= u . u;
//  - two, u and v, n = u x v: d in their plane (d . n = 0), and d = t_u u + t_v v with
//    t_u (n . n) = (d x v) . n and t_v (n . n) = (u x d) . n, each at most n . n in magnitude;
//  - three with det 0: linearly dependent axes, outside the precondition: nothing.
bool ExactBoxContainment::contains_flat(const Vec3& p) const {
  Rational d[3];
  for (int i = 0; i < 3; ++i) d[i] = Rational(p[i]) - frame_.c[i];
  // Explicit result type: Rational arithmetic builds expression templates that must not outlive
  // their operands.
  auto dot = [](const Rational* a, const Rational* b) -> Rational {
    return a[0] * b[0] + a[1] * b[1] + a[2] * b[2];
  };
  auto cross = [](const Rational* a, const Rational* b, Rational* out) {
    out[0] = a[1] * b[2] - a[2] * b[1];
    out[1] = a[2] * b[0] - a[0] * b[2];
    out[2] = a[0] * b[1] - a[1] * b[0];
  };
  if (span_count_ == 0) return d[0] == 0 && d[1] == 0 && d[2] == 0;
  if (span_count_ == 1) {
    const Rational* u = frame_.u[spans_[0]];
    Rational x[3];
    cross(d, u, x);
    return x[0] == 0 && x[1] == 0 && x[2] == 0 && abs(dot(d, u)) <= dot(u, u);
  }
  if (span_count_ == 2) {
    const Rational* u = frame_.u[spans_[0]];
    const Rational* v = frame_.u[spans_[1]];
    Rational n[3], x[3];
    cross(u, v, n);
    const Rational nn = dot(n, n);
    if (nn == 0 || dot(d, n) != 0) return false;
    cross(d, v, x);
    if (abs(dot(x, n)) > nn) return false;
    cross(u, d, x);
    return abs(dot(x, n)) <= nn;
  }
  return false;
}

bool ExactBoxContainment::contains(const Vec3& p) const {
  if (det_sign_ == 0) return contains_flat(p);
  // Filter, in the shadows' units: t_k det = (p - c) . w_k. In double, the difference p - c
  // is off by eps|p - c| (its scaling by a power of two is exact where it stays normal), the
  // stored w is off by 2 eps |w| (rounded from exact), the dot product adds 3 eps: the result
  // is off by at most 8 eps sum_i |p_i - c_i| |w_i|; the determinant shadow by 2 eps. Where a
  // scaled difference or a product is subnormal it is off by at most 2^-1075 more, times |w_i|
  // for the difference: the last term. Non-finite shadows (a needle box's) fail every test.
  // Relative bounds fail where values underflow further; such cases go exact.
  bool certain = abs_det_d_ > kFilterFloor;
  for (int k = 0; k < 3 && certain; ++k) {
    double dot = 0.0, mag = 0.0;
    for (int i = 0; i < 3; ++i) {
      const double d = (p[i] - cd_[i]) * scale_;
      dot += d * wd_[k][i];
      mag += std::abs(d * wd_[k][i]);
    }
    if (mag < kFilterFloor) {
      certain = false;
      break;
    }
    const double err =
        8.0 * kEps * mag + 2.0 * kEps * abs_det_d_ + 0x1p-1072 * (wd_abs_sum_[k] + 1.0);
    if (std::abs(dot) + err < abs_det_d_) continue;      // surely inside slab k
    if (std::abs(dot) - err > abs_det_d_) return false;  // surely outside
    certain = false;
  }
  if (certain) return true;
  for (int k = 0; k < 3; ++k) {
    Rational dot = 0;
    for (int i = 0; i < 3; ++i) dot += (Rational(p[i]) - frame_.c[i]) * frame_.w[k][i];
    if (abs(dot) > abs_det_) return false;
  }
  return true;
}

}  // namespace vobb
