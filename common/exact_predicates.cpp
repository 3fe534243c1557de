#include "common/exact_predicates.h"

#include <mpfr.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <limits>
#include <vector>

#include "common/status.h"

namespace vobb {
namespace {

// Static error bounds for the filtered determinants, in units of eta = 2^-52, which bounds one
// operation's relative error in every rounding mode (the callers include the polyhedral
// solver, which runs under upward rounding): the floating result's sign is decided where it
// exceeds bound * permanent (docs/derivations.md, "Orientation filters in any rounding mode").
constexpr double kEta = std::numeric_limits<double>::epsilon();  // 2^-52
constexpr double kOrient2dBound = 4 * kEta;
constexpr double kOrient3dBound = 8 * kEta;
// The relative bounds assume no underflow. A product that underflows is off by at most 2^-1074
// in absolute terms in any rounding mode (subtractions of subnormals are exact); in orient3d
// such an error in a minor is then multiplied by |u|. Adding 2^-1020 (|u|_1 + 1), itself never
// subnormal, covers that with a factor of 2^50 to spare; it only sends determinants near
// 1e-307 to GMP.
const double kUnderflowSlack = std::ldexp(1.0, -1020);

// x = odd 2^exp exactly, for finite x != 0 (odd below 2^53 in magnitude).
static_assert(sizeof(long) >= 8, "odd mantissas of 53 bits go through mpz_set_si's long");
void split_double(double x, long* odd, long* exp) {
  int e = 0;
  const auto m = static_cast<int64_t>(std::ldexp(std::frexp(x, &e), 53));  // x = m 2^(e-53)
  const int tz = __builtin_ctzll(static_cast<uint64_t>(std::abs(m)));
  *odd = static_cast<long>(m / (int64_t{1} << tz));
  *exp = e - 53 + tz;
}

// The N finite doubles x[i] as integers z[i] in one unit 2^e0, the least of their lowest set
// bits: x[i] = odd 2^exp with exp >= e0, so z[i] = odd 2^(exp - e0) and z[i] 2^e0 = x[i]
// exactly. A determinant is a homogeneous polynomial in the coordinates, so its sign is the same
// in any positive unit, and integers have no fractions to reduce. False when every x[i] is 0.
template <int N>
bool to_common_units(const double (&x)[N], mpz_class (&z)[N]) {
  long odd[N], exp[N];
  long e0 = std::numeric_limits<long>::max();
  for (int i = 0; i < N; ++i) {
    if (x[i] == 0) continue;
    split_double(x[i], &odd[i], &exp[i]);
    e0 = std::min(e0, exp[i]);
  }
  if (e0 == std::numeric_limits<long>::max()) return false;
  for (int i = 0; i < N; ++i) {
    if (x[i] == 0) {
      z[i] = 0;
      continue;
    }
    mpz_set_si(z[i].get_mpz_t(), odd[i]);
    mpz_mul_2exp(z[i].get_mpz_t(), z[i].get_mpz_t(), static_cast<mp_bitcnt_t>(exp[i] - e0));
  }
  return true;
}

int orient3d_exact(const Vec3& a, const Vec3& b, const Vec3& c, const Vec3& d) {
  const double x[12] = {a[0], a[1], a[2], b[0], b[1], b[2], c[0], c[1], c[2], d[0], d[1], d[2]};
  // Kept per thread: the limbs are reused, not allocated per call.
  thread_local mpz_class z[12], m, det;
  if (!to_common_units(x, z)) return 0;  // four copies of the origin
  mpz_class* u = z + 3;                  // b - a, c - a, d - a, in place
  for (int r = 1; r < 4; ++r)
    for (int i = 0; i < 3; ++i)
      mpz_sub(z[3 * r + i].get_mpz_t(), z[3 * r + i].get_mpz_t(), z[i].get_mpz_t());
  mpz_class* v = z + 6;
  mpz_class* w = z + 9;
  det = 0;
  for (int i = 0; i < 3; ++i) {  // u_i (v_j w_k - v_k w_j), (i, j, k) cyclic
    const int j = (i + 1) % 3, k = (i + 2) % 3;
    mpz_mul(m.get_mpz_t(), v[j].get_mpz_t(), w[k].get_mpz_t());
    mpz_submul(m.get_mpz_t(), v[k].get_mpz_t(), w[j].get_mpz_t());
    mpz_addmul(det.get_mpz_t(), u[i].get_mpz_t(), m.get_mpz_t());
  }
  return mpz_sgn(det.get_mpz_t());
}

int orient2d_exact(const Vec3& a, const Vec3& b, const Vec3& c, int i, int j) {
  const double x[6] = {a[i], a[j], b[i], b[j], c[i], c[j]};
  thread_local mpz_class z[6], det;
  if (!to_common_units(x, z)) return 0;
  for (int r = 2; r < 6; ++r) mpz_sub(z[r].get_mpz_t(), z[r].get_mpz_t(), z[r % 2].get_mpz_t());
  mpz_mul(det.get_mpz_t(), z[2].get_mpz_t(), z[5].get_mpz_t());     // (b - a)_i (c - a)_j
  mpz_submul(det.get_mpz_t(), z[3].get_mpz_t(), z[4].get_mpz_t());  // - (b - a)_j (c - a)_i
  return mpz_sgn(det.get_mpz_t());
}

}  // namespace

int orient3d(const Vec3& a, const Vec3& b, const Vec3& c, const Vec3& d) {
  const double ux = b[0] - a[0], uy = b[1] - a[1], uz = b[2] - a[2];
  const double vx = c[0] - a[0], vy = c[1] - a[1], vz = c[2] - a[2];
  const double wx = d[0] - a[0], wy = d[1] - a[1], wz = d[2] - a[2];
  // Differences of 2^340 or more (or one that overflowed: to infinity, or to the largest
  // double under directed rounding) go to GMP: below it no product of three overflows,
  // which the filter's bound assumes.
  constexpr double kFar = 0x1p340;
  if (!(std::max({std::abs(ux), std::abs(uy), std::abs(uz), std::abs(vx), std::abs(vy),
                  std::abs(vz), std::abs(wx), std::abs(wy), std::abs(wz)}) < kFar))
    return orient3d_exact(a, b, c, d);
  const double m0 = vy * wz - vz * wy, m1 = vz * wx - vx * wz, m2 = vx * wy - vy * wx;
  const double det = ux * m0 + uy * m1 + uz * m2;
  const double perm = std::abs(ux) * (std::abs(vy * wz) + std::abs(vz * wy)) +
                      std::abs(uy) * (std::abs(vz * wx) + std::abs(vx * wz)) +
                      std::abs(uz) * (std::abs(vx * wy) + std::abs(vy * wx));
  const double bound =
      kOrient3dBound * perm + kUnderflowSlack * (std::abs(ux) + std::abs(uy) + std::abs(uz) + 1.0);
  if (det > bound) return 1;
  if (-det > bound) return -1;
  return orient3d_exact(a, b, c, d);
}

int orient2d(const Vec3& a, const Vec3& b, const Vec3& c, int i, int j) {
  // As orient3d: differences of 2^510 or more (a product of two may overflow) go to GMP.
  constexpr double kFar = 0x1p510;
  const double bi = b[i] - a[i], cj = c[j] - a[j], bj = b[j] - a[j], ci = c[i] - a[i];
  if (!(std::max({std::abs(bi), std::abs(cj), std::abs(bj), std::abs(ci)}) < kFar))
    return orient2d_exact(a, b, c, i, j);
  const double l = bi * cj;
  const double r = bj * ci;
  const double det = l - r;
  const double bound = kOrient2dBound * (std::abs(l) + std::abs(r)) + kUnderflowSlack;
  if (det > bound) return 1;
  if (-det > bound) return -1;
  return orient2d_exact(a, b, c, i, j);
}

bool collinear(const Vec3& a, const Vec3& b, const Vec3& c) {
  // Collinear in 3D exactly when every coordinate-plane projection is collinear.
  return orient2d(a, b, c, 0, 1) == 0 && orient2d(a, b, c, 1, 2) == 0 &&
         orient2d(a, b, c, 2, 0) == 0;
}

Rational sum_pairwise(std::vector<Rational>& terms) {
  if (terms.empty()) return Rational(0);
  size_t n = terms.size();
  while (n > 1) {
    size_t half = (n + 1) / 2;
    for (size_t i = 0; i + half < n; ++i) terms[i] += terms[i + half];
    n = half;
  }
  return terms[0];
}

Rational exact_signed_volume(const Mesh& mesh, const std::vector<int32_t>& faces) {
  // Every coordinate is an integer multiple of 2^e0, the least unit among the faces' coordinates'
  // lowest set bits; in that unit each triple product, and so the sum of them, is an integer:
  // integer arithmetic with no fractions to reduce, and one division at the end. Each corner is
  // converted where it is used, so a call costs time in its faces alone (a mesh's shells are
  // summed one call each).
  long e0 = std::numeric_limits<long>::max();
  for (int32_t f : faces)
    for (int c = 0; c < 3; ++c)
      for (int k = 0; k < 3; ++k) {
        const double x = mesh.corner(f, c)[k];
        VOBB_ASSERT(std::isfinite(x), "exact_signed_volume needs finite coordinates");
        if (x == 0) continue;
        long odd = 0, exp = 0;
        split_double(x, &odd, &exp);
        e0 = std::min(e0, exp);
      }
  if (e0 == std::numeric_limits<long>::max()) return Rational(0);  // every coordinate is 0
  mpz_class p[3][3], sum, t;  // p[c][k]: corner c's coordinate k in units of 2^e0
  for (int32_t f : faces) {
    for (int c = 0; c < 3; ++c)
      for (int k = 0; k < 3; ++k) {
        const double x = mesh.corner(f, c)[k];
        if (x == 0) {
          p[c][k] = 0;
          continue;
        }
        long odd = 0, exp = 0;
        split_double(x, &odd, &exp);
        mpz_set_si(p[c][k].get_mpz_t(), odd);
        mpz_mul_2exp(p[c][k].get_mpz_t(), p[c][k].get_mpz_t(), static_cast<mp_bitcnt_t>(exp - e0));
      }
    for (int i = 0; i < 3; ++i) {  // a_i (b_j c_k - b_k c_j), (i, j, k) cyclic
      const int j = (i + 1) % 3, k = (i + 2) % 3;
      mpz_mul(t.get_mpz_t(), p[1][j].get_mpz_t(), p[2][k].get_mpz_t());
      mpz_submul(t.get_mpz_t(), p[1][k].get_mpz_t(), p[2][j].get_mpz_t());
      mpz_addmul(sum.get_mpz_t(), p[0][i].get_mpz_t(), t.get_mpz_t());
    }
  }
  Rational six_v(sum);  // in units of 2^(3 e0)
  if (e0 < 0)
    mpq_div_2exp(six_v.get_mpq_t(), six_v.get_mpq_t(), static_cast<mp_bitcnt_t>(-3 * e0));
  else
    mpq_mul_2exp(six_v.get_mpq_t(), six_v.get_mpq_t(), static_cast<mp_bitcnt_t>(3 * e0));
  return six_v / 6;
}

Rational exact_signed_volume(const Mesh& mesh) {
  std::vector<int32_t> all(mesh.faces.size());
  for (size_t i = 0; i < all.size(); ++i) all[i] = static_cast<int32_t>(i);
  return exact_signed_volume(mesh, all);
}

double to_double_nearest(const Rational& q) {
  // Below 2^-1022 doubles are the multiples of 2^-1074 (subnormals): MPFR has no subnormals,
  // so rounding to 53 bits there and then to the double would round twice. Instead q 2^1074 is
  // rounded once to the nearest integer (ties to even), which a double holds exactly (< 2^53).
  const Rational least_normal = Rational(1) / Rational(mpz_class(1) << 1022);
  if (abs(q) < least_normal) {
    const Rational scaled = q * Rational(mpz_class(1) << 1074);
    mpz_class lo, rem;
    mpz_fdiv_qr(lo.get_mpz_t(), rem.get_mpz_t(), scaled.get_num_mpz_t(), scaled.get_den_mpz_t());
    const int half = cmp(mpz_class(2 * rem), scaled.get_den());  // 2 rem against the denominator
    if (half > 0 || (half == 0 && mpz_odd_p(lo.get_mpz_t()))) ++lo;
    return std::ldexp(lo.get_d(), -1074);  // |lo| <= 2^52: exact, and so is the scaling
  }
  mpfr_t x;
  mpfr_init2(x, 53);
  mpfr_set_q(x, q.get_mpq_t(), MPFR_RNDN);
  double d = mpfr_get_d(x, MPFR_RNDN);  // exact: x has 53 bits and a normal exponent (or overflows)
  mpfr_clear(x);
  return d;
}

std::string format_nearest(const Rational& q) {
  char buf[40];
  std::snprintf(buf, sizeof buf, "%.17g", to_double_nearest(q));
  return buf;
}

void enclose(const Rational& q, double* lo, double* hi) {
  const double d = to_double_nearest(q);
  if (std::isinf(d)) {  // beyond the doubles: between the largest finite one and infinity
    const double most = std::numeric_limits<double>::max();
    *lo = d > 0 ? most : -INFINITY;
    *hi = d > 0 ? INFINITY : -most;
    return;
  }
  const int c = cmp(Rational(d), q);
  *lo = c > 0 ? std::nextafter(d, -INFINITY) : d;
  *hi = c < 0 ? std::nextafter(d, INFINITY) : d;
}

}  // namespace vobb
