// The box-frame clip formula (common/box_frame_clip.h) on its own: a face's term in closed form,
// the same decisions in rationals and in double, and the polygon bound under rounded signs.
#include "common/box_frame_clip.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <random>

#include "common/bvh.h"

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

// A closed rod of `sides`-gon section (radius r) and `rings` rings along the unit direction a,
// length L, with fan caps; faces outward.
Mesh rod(const Vec3& a, int rings, int sides, double r, double L) {
  const Vec3 u = a.unitOrthogonal(), w = a.cross(u);
  Mesh m;
  for (int i = 0; i < rings; ++i)
    for (int j = 0; j < sides; ++j) {
      const double t = 2 * M_PI * j / sides;
      m.vertices.push_back(L * i / (rings - 1) * a + r * (std::cos(t) * u + std::sin(t) * w));
    }
  const int c0 = static_cast<int>(m.vertices.size());
  m.vertices.push_back(Vec3::Zero());
  m.vertices.push_back(L * a);
  auto v = [&](int i, int j) { return i * sides + (j % sides); };
  for (int i = 0; i + 1 < rings; ++i)
    for (int j = 0; j < sides; ++j) {
      m.faces.push_back({v(i, j), v(i, j + 1), v(i + 1, j + 1)});
      m.faces.push_back({v(i, j), v(i + 1, j + 1), v(i + 1, j)});
    }
  for (int j = 0; j < sides; ++j) {
    m.faces.push_back({c0, v(0, j + 1), v(0, j)});
    m.faces.push_back({c0 + 1, v(rings - 1, j), v(rings - 1, j + 1)});
  }
  return m;
}

// The faces a labelling's column visits: those ColumnFilter::place puts in it, counted through
// visit_accepted, apart from column_of's own walk.
size_t visited(const Mesh& mesh, const AabbTree& faces, const Obb& box) {
  const box_clip::ColumnFilter f(box);
  size_t n = 0;
  faces.visit_accepted(f, [&](int32_t i) {
    n += f.place(faces.primitive_bounds(i), mesh.corner(i, 0), mesh.corner(i, 1),
                 mesh.corner(i, 2)) > 0;
  });
  return n;
}

// A triangle that ColumnFilter::place puts outside the column adds nothing to the formula, decided
// in rationals: random boxes and triangles around them, from slivers to triangles larger than the
// box. The test refuses many triangles whose boxes the first test keeps (the slivers it is for).
TEST(ColumnFilter, ATriangleItRefusesAddsNothing) {
  std::mt19937_64 rng(23);
  std::uniform_real_distribution<double> u(-1, 1), half(0.05, 1), size(-3, 0.5);
  int refused = 0, refused_past_box = 0;
  for (int trial = 0; trial < 3000; ++trial) {
    Obb box;
    box.center = Vec3(u(rng), u(rng), u(rng));
    const Eigen::Matrix3d q =
        Eigen::Quaterniond(Eigen::Vector4d(u(rng), u(rng), u(rng), u(rng)).normalized())
            .toRotationMatrix();
    for (int k = 0; k < 3; ++k) box.axes[k] = q.col(k), box.half[k] = half(rng);
    const box_clip::ColumnFilter filter(box);
    const box_clip::Frame<Rational> frame = box_clip::make_frame<Rational>(box);
    const Rational R = abs(frame.det);
    for (int t = 0; t < 20; ++t) {
      // A long edge from p along d and a short one: slivers at every angle.
      const Vec3 p = 2.5 * Vec3(u(rng), u(rng), u(rng));
      const Vec3 d = std::pow(10.0, size(rng)) * Vec3(u(rng), u(rng), u(rng)) * 3;
      const Vec3 e = std::pow(10.0, size(rng) - 1) * Vec3(u(rng), u(rng), u(rng));
      const Vec3 tri[3] = {p, p + d, p + e};
      Aabb b;
      for (const Vec3& c : tri) b.extend(c);
      if (filter.place(b, tri[0], tri[1], tri[2]) > 0) continue;
      ++refused;
      if (filter(b)) ++refused_past_box;
      const Point<Rational> in_frame[3] = {box_clip::to_frame(frame, tri[0]),
                                           box_clip::to_frame(frame, tri[1]),
                                           box_clip::to_frame(frame, tri[2])};
      Rational term;
      if (box_clip::face_term6(in_frame, R, &term)) {
        ASSERT_EQ(term, 0) << trial << " " << t;
      }
    }
  }
  EXPECT_GT(refused, 10000);
  EXPECT_GT(refused_past_box, 1000);
}

// A rod along a diagonal of its bounds: for a box a quarter of the way along it, the column
// that leaves the bounds soonest runs along the rod to its near end (a quarter of its faces);
// fewest_faces_column takes the fewest of the six, a column across the rod, and the exact OBV
// is the same in every labelling.
TEST(FewestFacesColumn, ADiagonalRodIsCutAcrossNotAlong) {
  const Vec3 a = Vec3(1, 1, 1).normalized();
  const double L = 1.7, r = 0.02;
  const int rings = 257, sides = 8;
  const Mesh mesh = rod(a, rings, sides, r, L);
  const AabbTree faces = AabbTree::over_faces(mesh);
  Obb box;
  const double step = L / (rings - 1);
  box.center = (64 + 2) * step * a;  // rings 64 to 68
  box.axes = {a, a.unitOrthogonal(), a.cross(a.unitOrthogonal())};
  box.half = Vec3(2 * step, r, r) * 1.001;
  const box_clip::Column column = box_clip::fewest_faces_column(box, mesh, faces);
  const Obb& chosen = column.box;
  // Its faces are the column's, in visit order.
  EXPECT_EQ(column.faces, box_clip::column_of(chosen, mesh, faces).faces);
  const Obb first = box_clip::shortest_column(box, faces.bounds());
  const size_t n_chosen = visited(mesh, faces, chosen), n_first = visited(mesh, faces, first);
  EXPECT_GE(n_first, 64u * 2 * sides);  // the 64 rings before the box, at least
  EXPECT_LT(8 * n_chosen, n_first);
  // The fewest of the six labellings (the ones shortest_column chooses among).
  size_t fewest = SIZE_MAX;
  const int orders[6][3] = {{0, 1, 2}, {1, 0, 2}, {1, 2, 0}, {2, 1, 0}, {2, 0, 1}, {0, 2, 1}};
  for (const auto& o : orders) {
    Obb b = box;
    for (int n = 0; n < 3; ++n) b.axes[n] = box.axes[o[n]], b.half[n] = box.half[o[n]];
    fewest = std::min(fewest, visited(mesh, faces, b));
  }
  EXPECT_EQ(n_chosen, fewest);
  const Rational obv = box_clip::box_obv_rational(mesh, faces, chosen);
  EXPECT_GT(obv, 0);
  EXPECT_EQ(obv, box_clip::box_obv_rational(mesh, faces, first));
  EXPECT_EQ(obv, box_clip::box_obv_rational(mesh, faces, box));
  // A box at the rod's end keeps the first labelling, whose column leaves the rod at once, and
  // the faces it gathered nearest first come in visit order too.
  Obb end = box;
  end.center = 2 * step * a;
  const box_clip::Column at_end = box_clip::fewest_faces_column(end, mesh, faces);
  const Obb first_at_end = box_clip::shortest_column(end, faces.bounds());
  EXPECT_EQ(at_end.box.axes, first_at_end.axes);
  EXPECT_EQ(at_end.faces, box_clip::column_of(first_at_end, mesh, faces).faces);
  EXPECT_FALSE(at_end.faces.empty());
}

}  // namespace
}  // namespace vobb
