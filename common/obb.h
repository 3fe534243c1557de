// vobb::Obb — an oriented bounding box: centre, three axes and half extents.
//
// The certified solid of a box is the parallelepiped {c + sum_k t_k h_k a_k : t in [-1,1]^3},
// evaluated exactly from the stored doubles (DESIGN §1). Axes should be unit and
// right-handed; a box read from a file may have axes that are only nearly orthonormal, and
// its solid is still that exact parallelepiped.
#pragma once

#include <array>
#include <string>
#include <vector>

#include "common/exact_predicates.h"
#include "common/mesh.h"

namespace vobb {

struct Obb {
  Vec3 center = Vec3::Zero();
  std::array<Vec3, 3> axes = {Vec3::UnitX(), Vec3::UnitY(), Vec3::UnitZ()};  // world coords
  Vec3 half = Vec3::Zero();                                                  // >= 0
};

// A box with centre c and half extents `half` whose axes are the columns of the rotation by
// `angle` radians about `axis` (nonzero; normalized here).
Obb rotated_box(const Vec3& c, const Vec3& half, double angle = 0,
                const Vec3& axis = Vec3(1, 2, 3));

// Volume of the parallelepiped, 8 h0 h1 h2 |det[a0 a1 a2]|, in double.
double volume(const Obb& box);

// What makes a box unfit for vobb's estimators and files, in words ("" when it is fit):
// non-finite numbers, a negative or subnormal half extent (below 2^-1022; zero is a flat box
// and fine), axes further from orthonormal than 1e-5 in some dot product (DESIGN §7: axes
// written with 6 significant digits are off by 2e-6 at most), or a box reaching beyond
// kMaxBoxReach in some coordinate. Box files and the validation suite refuse such boxes.
std::string box_defect(const Obb& box);

// Largest |coordinate| a box's corners may reach, 2^242 (about 7.1e72): four times the mesh
// range (kMaxCoordinate, common/solidity.h). Every box fit_obb makes around faces within that
// range reaches at most 3 kMaxCoordinate and its round-off padding (docs/derivations.md,
// "The reach of a fitted box"), so no box the builders make is refused.
inline constexpr double kMaxBoxReach = 0x1p242;

// A box and the earlier boxes that what it shares with them is measured against
// (fast/poly_overlap.h).
struct ShareQuery {
  Obb box;
  std::vector<Obb> earlier;
};

// The 8 corners: corner i is c + sum_k s_k h_k a_k with s_k = +1 when bit k of i is set,
// else -1.
std::array<Vec3, 8> corners(const Obb& box);

// The 6 faces of a box as quads of corner indices (numbered as in corners()), counter-
// clockwise seen from outside when the axes are right-handed; reverse them for left-handed.
inline constexpr int kBoxQuads[6][4] = {{0, 4, 6, 2}, {1, 3, 7, 5}, {0, 1, 5, 4},
                                        {2, 6, 7, 3}, {0, 2, 3, 1}, {4, 5, 7, 6}};

// Orthonormal right-handed frame from three approximate axes (Gram-Schmidt on a0, a1;
// a2 = a0 x a1). Precondition: a0 and a1 are finite and not parallel.
std::array<Vec3, 3> orthonormalize(const std::array<Vec3, 3>& axes);

// The tight box of the given faces' vertices along the given axes (orthonormalized first),
// padded by a derived round-off margin and then checked exactly: every vertex lies in the
// returned box's certified solid. Each box face lies within `fit_slack(box)` of some vertex.
// Precondition: `faces` is not empty and its vertices are finite.
Obb fit_obb(const Mesh& mesh, const std::vector<int32_t>& faces, const std::array<Vec3, 3>& axes);

// Upper bound on the distance by which fit_obb's faces may stand off the nearest vertex:
// the padding that makes the box exactly conservative despite double rounding, and at least
// 2^-1022, so that every padded half extent is a normal double.
double fit_slack(const Obb& box, double mesh_scale);

// The certified solid's frame in exact rationals: centre c, edge vectors u_k = h_k a_k, and
// Cramer rows w_k = u_{k+1} x u_{k+2}, so that for any point p, (p - c) . w_k = t_k det
// with det = det[u0 u1 u2] and t the parallelepiped coordinates. The solid is
// {p : |(p - c) . w_k| <= |det| for k = 0, 1, 2}; det == 0 for a flat box.
struct ExactBoxFrame {
  explicit ExactBoxFrame(const Obb& box);
  // Corner i exactly, numbered as in corners().
  void corner(int i, Rational out[3]) const;
  Rational c[3];
  Rational u[3][3];
  Rational w[3][3];
  Rational det;
};

// The certified solid's volume, 8 |det[u0 u1 u2]|, exactly (volume() is its double estimate).
Rational exact_volume(const Obb& box);

// Exact point-in-box test against the certified solid (boundary counts as inside).
// Build once per box, query per point. A box with zero half extents is the closed
// parallelepiped all the same (DESIGN §1): a rectangle, a segment or its centre point.
// Precondition for that case: the axes of its nonzero extents are linearly independent (tree
// files guarantee it: their axes are orthonormal within 1e-5); otherwise it contains nothing.
class ExactBoxContainment {
 public:
  explicit ExactBoxContainment(const Obb& box);
  bool contains(const Vec3& p) const;

 private:
  bool contains_flat(const Vec3& p) const;  // det == 0

  ExactBoxFrame frame_;
  Rational abs_det_;
  int det_sign_ = 0;
  int spans_[3] = {-1, -1, -1};  // flat box: the axes with nonzero extent, in order
  int span_count_ = 0;
  // Double shadows of the above for a filter, in units of 2^e (box_clip::frame_exponent):
  // lengths times scale_ = 2^-e, w times 2^-2e, det times 2^-3e, so that a box's filter does
  // not depend on how far its size lies from 1.
  double wd_[3][3];
  double wd_abs_sum_[3];
  double cd_[3];
  double abs_det_d_;
  double scale_;
};

// The separating-axis test's candidates for two boxes (anything with `axes`, a std::array of
// three Vec3), in a fixed order: a's and b's axes (a_0, b_0, a_1, b_1, a_2, b_2), then the cross
// products a_i x b_j. Calls `separates(L)` on each until one returns true, and returns whether
// one did. The caller's predicate decides what separates, with its own round-off allowance.
template <class BoxA, class BoxB, class Separates>
bool any_separating_axis(const BoxA& a, const BoxB& b, Separates separates) {
  for (int k = 0; k < 3; ++k)
    if (separates(a.axes[k]) || separates(b.axes[k])) return true;
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < 3; ++j)
      if (separates(a.axes[i].cross(b.axes[j]))) return true;
  return false;
}

// Whether two boxes are surely apart: one of the 15 separating axes splits them with a gap
// wider than round-off can close. False where they may meet (touching boxes may).
bool boxes_apart(const Obb& a, const Obb& b);
// The boxes of `pool`, in order, that are not surely apart from b (the others share no volume
// with it).
std::vector<Obb> boxes_meeting(const Obb& b, const std::vector<Obb>& pool);

}  // namespace vobb
