// The box-frame clip formula (common/box_frame_clip.h) on its own: a face's term in closed form,
// the same decisions in rationals and in double, and the polygon bound under rounded signs.
#include "common/box_frame_clip.h"

#include <gtest/gtest.h>

namespace vobb {
namespace {

using box_clip::Point;
using box_clip::Polygon;

template <class NT>
Point<NT> pt(double x, double y, double z) {
  Point<NT> p;
  p.x[0] = NT(x);
  p.x[1] = NT(y);
  p.x[2] = NT(z);
  return p;
}

// A counter-clockwise triangle inside the column at height z = 0.5 with R = 1: its shadow has
// area 1/2, so the term is 6 * (1/2) * (z + R) = 4.5; the same above the slab (z = 3) counts
// 2R per unit area: 6 * (1/2) * 2 = 6; below (z = -3) nothing; and a triangle reaching past
// x = 1 is clipped to its part in the column: (0,0)-(2,0)-(0,1) clipped at x <= 1 leaves the
// quadrilateral (0,0),(1,0),(1,1/2),(0,1) of area 3/4, at z = 0.5 giving 6 * 3/4 * 3/2 = 27/4.
TEST(BoxFrameClip, FaceTermsInClosedForm) {
  const Rational R(1);
  Rational t;
  const Point<Rational> mid[3] = {pt<Rational>(0, 0, 0.5), pt<Rational>(1, 0, 0.5),
                                  pt<Rational>(0, 1, 0.5)};
  ASSERT_TRUE(box_clip::face_term6(mid, R, &t));
  EXPECT_EQ(t, Rational(9, 2));
  const Point<Rational> top[3] = {pt<Rational>(0, 0, 3), pt<Rational>(1, 0, 3),
                                  pt<Rational>(0, 1, 3)};
  ASSERT_TRUE(box_clip::face_term6(top, R, &t));
  EXPECT_EQ(t, Rational(6));
  const Point<Rational> below[3] = {pt<Rational>(0, 0, -3), pt<Rational>(1, 0, -3),
                                    pt<Rational>(0, 1, -3)};
  EXPECT_FALSE(box_clip::face_term6(below, R, &t));
  const Point<Rational> wide[3] = {pt<Rational>(0, 0, 0.5), pt<Rational>(2, 0, 0.5),
                                   pt<Rational>(0, 1, 0.5)};
  ASSERT_TRUE(box_clip::face_term6(wide, R, &t));
  EXPECT_EQ(t, Rational(27, 4));
  // The same in double: every value here is a small dyadic, so double is exact too.
  const Point<double> wide_d[3] = {pt<double>(0, 0, 0.5), pt<double>(2, 0, 0.5),
                                   pt<double>(0, 1, 0.5)};
  double td = 0;
  ASSERT_TRUE(box_clip::face_term6(wide_d, 1.0, &td));
  EXPECT_EQ(td, 6.75);
}

// Signs that contradict each other (as rounded ones may) can grow a clipped polygon beyond the
// kMaxPolygon vertices that exact signs allow: clip() refuses with PolygonOverflow instead of
// writing past its buffer.
TEST(BoxFrameClip, InconsistentSignsCannotOverflowThePolygon) {
  Polygon<double> in, out;
  in.n = box_clip::kMaxPolygon;
  for (int i = 0; i < in.n; ++i) in.v[i] = pt<double>(i, 0, 0);
  int call = 0;
  auto alternating = [&](const Point<double>&, int, int, int, const double&) {
    return call++ % 2 ? 1 : -1;
  };
  EXPECT_THROW(box_clip::detail::clip(alternating, &in, 0, 1, 1, 1.0, &out),
               box_clip::PolygonOverflow);
  // Consistent signs on the same polygon: at most one vertex more, no throw.
  auto exact = [](const Point<double>& p, int, int, int, const double&) {
    return p.x[0] > 4 ? 1 : -1;
  };
  const Polygon<double>* r = box_clip::detail::clip(exact, &in, 0, 1, 1, 1.0, &out);
  EXPECT_LE(r->n, box_clip::kMaxPolygon);
}

}  // namespace
}  // namespace vobb
