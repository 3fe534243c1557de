// The cubemap of the OBV estimator (DESIGN §4, paper §4.1), in box-normalized space.
//
// A box maps to the cube [-1,1]^3 by t = [h0 a0, h1 a1, h2 a2]^-1 (p - c). Seen from its centre,
// cubemap face f (axis k = f / 2, sign s = +1 for even f) covers the directions
// d = s e_k + u e_{k+1} + v e_{k+2}, (u, v) in [-1,1]^2, each face cut into m x m texels whose
// centres are u = -1 + (2i + 1)/m, v = -1 + (2j + 1)/m. Along d, the depth zeta (the k-th
// coordinate times s) of a point is its ray parameter, and the cube's face is at zeta = 1 for
// every texel: the box term of every texel is the exact pyramid (4/m^2)/3.
// With crossings zeta_i < 1 of signs s_i (+1 leaving the solid), one texel's outer volume is
//   (4 / (3 m^2)) [1 - c - sum_i s_i zeta_i^3],   c = 1_X(centre) - sum_i s_i,
// which integrates planes parallel to a cube face exactly. So
//   OBV = |det| (8 (1 - 1_X(centre)) + (4 / (3 m^2)) sum over crossings s_i (1 - zeta_i^3)),
// with |det| = |det[h0 a0, h1 a1, h2 a2]| / 8 * 8 = h0 h1 h2 |det[a0 a1 a2]|.
#pragma once

#include <Eigen/Core>

#include "common/mesh.h"
#include "common/obb.h"

namespace vobb {

struct BoxFrame {
  Eigen::Matrix3d to_local =
      Eigen::Matrix3d::Zero();  // [h0 a0, h1 a1, h2 a2]^-1, rounded (as diag(1 / h) [a0 a1 a2]^-1)
  Vec3 center = Vec3::Zero();
  double volume_scale = 0;  // |det[h0 a0, h1 a1, h2 a2]|: local volume 1 is this much world volume
  bool mirrored = false;    // det < 0: local orientation flips face signs
  Vec3 local(const Vec3& p) const { return to_local * (p - center); }
  // A bound on |local(p) - t|, axis by axis, where t is p's exact coordinates in the box as
  // stored (the parallelepiped c + sum t_k h_k a_k with the axes' doubles taken exactly): the
  // rounding of the inverse, of p - c and of the product (docs/derivations.md, "The box frame's
  // rounding"). Infinite where the frame is too ill-conditioned to bound.
  Vec3 local_error(const Vec3& p) const;
  double inverse_error =
      0;  // alpha of box_frame: h_k |t_k - (to_local (p - c))_k| <= alpha |p - c|_inf
  Vec3 half = Vec3::Ones();  // the box's half extents
  bool valid = true;         // false: axes double cannot invert, or a subnormal half extent
};

// The frame of a box of nonzero volume. Axes that double cannot invert, or a half extent below
// 2^-1022 (1 / h could overflow), give valid = false (box files refuse such boxes: box_defect).
BoxFrame box_frame(const Obb& box);

// Face f's direction for face coordinates (u, v).
inline Vec3 cubemap_direction(int face, double u, double v) {
  const int k = face / 2;
  const double s = face % 2 == 0 ? 1.0 : -1.0;
  Vec3 d;
  d[k] = s;
  d[(k + 1) % 3] = u;
  d[(k + 2) % 3] = v;
  return d;
}

inline double texel_center(int i, int m) { return -1.0 + (2.0 * i + 1.0) / m; }

}  // namespace vobb
