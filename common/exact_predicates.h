// Exact geometric predicates on double inputs, and exact rational helpers.
//
// Every input double is an exact rational; these functions decide signs of polynomials in
// those rationals without error, in any floating-point rounding mode. A floating-point filter
// with a static error bound answers the easy cases; the rest are decided in GMP integers (the
// inputs in units of their least set bit).
// Preconditions: all inputs finite.
// This is the only exactness `common/` needs (solidity, volume, containment); the CGAL-based
// solver lives in `exact/`.
#pragma once

#include <gmpxx.h>

#include <string>
#include <vector>

#include "common/mesh.h"

namespace vobb {

using Rational = mpq_class;

// Sign of det[b-a, c-a, d-a]: +1 when d lies on the side that the normal of the
// counter-clockwise triangle (a, b, c) points to, -1 on the other side, 0 when coplanar.
int orient3d(const Vec3& a, const Vec3& b, const Vec3& c, const Vec3& d);

// Sign of the 2D cross product (b-a) x (c-a), on coordinates (i, j) of the inputs:
// +1 counter-clockwise, -1 clockwise, 0 collinear.
int orient2d(const Vec3& a, const Vec3& b, const Vec3& c, int i, int j);

// True when a, b, c are collinear (or coincide), exactly.
bool collinear(const Vec3& a, const Vec3& b, const Vec3& c);

// Exact signed volume enclosed by the faces (divergence theorem), positive for an outward
// oriented closed mesh: the sum of the faces' triple products over 6, in integer units of the
// coordinates' least set bit. Precondition: the faces' coordinates are finite.
Rational exact_signed_volume(const Mesh& mesh);
Rational exact_signed_volume(const Mesh& mesh, const std::vector<int32_t>& faces);

// Sum of the terms, added pairwise so that operands stay balanced (long exact sums of
// rationals with different denominators grow slowly this way). Consumes the vector.
Rational sum_pairwise(std::vector<Rational>& terms);

// The double nearest to q (ties to even), as MPFR rounds it (infinity beyond the doubles;
// +0 for a q that rounds to zero, of either sign). mpq_get_d truncates instead.
double to_double_nearest(const Rational& q);

// [lo, hi]: the largest double <= q and the smallest double >= q (equal when q is a double;
// the largest finite double and infinity beyond the doubles).
void enclose(const Rational& q, double* lo, double* hi);

// "%.17g" of the correctly rounded double: the way every exact value is printed.
std::string format_nearest(const Rational& q);

}  // namespace vobb
