// The polyhedral OBV solver (fast/poly_solver.h): its interval holds the exact rational, it is
// tight, a broken evaluator is caught, and it stays finite or refuses on every input.
#include "fast/poly_solver.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <random>

#include "common/box_frame_clip.h"
#include "common/io/mesh_report.h"
#include "data/analytic_meshes.h"
#include "exact/outer_volume.h"
#include "test_common.h"
#include "validate/box_corpus.h"

namespace vobb {
namespace {

using analytic::AnalyticMesh;

// The interval's width bound for an ordinary box (not a fallback). Let M be the largest
// T-coordinate of a visited face in units of R (at most the mesh's reach from the centre over
// the least half extent). A vertex's T-coordinates are off by about 5u M R (three products
// and two sums), each of at most 6 clips adds about 10u M R, so a clipped coordinate is off by
// at most 60u M R; a doubled fan area (differences of those, products with lengths up to 2R)
// by 2 (120u M R)(2R) 2 < 2^10 u M R^2; at most 7 fan triangles, each times a height factor of
// at most 6R, then divided by 6 R^2: about 2^13 u M R in volume, or 2^10 u M of vol(B) = 8R.
// So width <= faces 2^10 2^-52 max(1, M) vol(B), summed over the faces.
double width_bound(const PolyObv& r, const Obb& b, const Mesh& mesh) {
  double reach = 0;
  for (const Vec3& v : mesh.vertices) reach = std::max(reach, (v - b.center).norm());
  const double m = std::max(1.0, reach / b.half.minCoeff());
  return std::max(1, r.faces) * 0x1p-42 * m * volume(b);
}

// Exact OBV inside [lo, hi], compared as rationals.
::testing::AssertionResult encloses(const PolyObv& r, const Rational& exact) {
  if (Rational(r.lo) <= exact && exact <= Rational(r.hi)) return ::testing::AssertionSuccess();
  return ::testing::AssertionFailure()
         << "exact " << format_nearest(exact) << " outside [" << r.lo << ", " << r.hi << "]";
}

// Seeded boxes over the analytic meshes: centres anywhere in the mesh's bounds (grown by a
// half), sizes from 1 % to the whole mesh, any orientation.
std::vector<Obb> random_boxes(const Mesh& mesh, int count, uint64_t seed) {
  std::mt19937_64 rng(seed);
  auto uniform = [&](double a, double b) { return a + (b - a) * (double(rng() >> 11) * 0x1p-53); };
  Aabb bounds;
  for (const Vec3& v : mesh.vertices) bounds.extend(v);
  const Vec3 size = bounds.hi - bounds.lo;
  std::vector<Obb> boxes;
  for (int i = 0; i < count; ++i) {
    Vec3 c, h;
    for (int k = 0; k < 3; ++k)
      c[k] = uniform(bounds.lo[k] - 0.5 * size[k], bounds.hi[k] + 0.5 * size[k]);
    const double s = std::exp(uniform(std::log(0.01), std::log(1.0))) * size.maxCoeff();
    for (int k = 0; k < 3; ++k) h[k] = s * uniform(0.2, 1.0);
    boxes.push_back(rotated_box(c, h, uniform(0, 3.14159),
                                Vec3(uniform(-1, 1), uniform(-1, 1), uniform(0.1, 1))));
  }
  return boxes;
}

struct Tally {
  int boxes = 0, exact_boxes = 0, exact_faces = 0, exact_signs = 0;
  double worst_width_ratio = 0;  // width / width_bound over the interval-evaluated boxes
};

void check_all(const Mesh& mesh, const std::vector<Obb>& boxes, Tally* tally,
               const std::string& what) {
  const PolyObvSolver poly(mesh);
  const std::vector<PolyObv> got = poly.evaluate(boxes);
  for (size_t i = 0; i < boxes.size(); ++i) {
    SCOPED_TRACE(what + " box " + std::to_string(i));
    const PolyObv& r = got[i];
    ASSERT_TRUE(std::isfinite(r.lo) && std::isfinite(r.hi) && std::isfinite(r.estimate));
    ASSERT_LE(r.lo, r.estimate);
    ASSERT_LE(r.estimate, r.hi);
    EXPECT_TRUE(encloses(r, poly.exact(boxes[i])));
    ++tally->boxes;
    tally->exact_faces += r.exact_faces;
    tally->exact_signs += r.exact_signs;
    const double bound = width_bound(r, boxes[i], mesh);
    if (r.exact_box) {
      ++tally->exact_boxes;
      // A box goes to rationals for its width only where that width was above the solver's
      // threshold, and still within its derived bound: wider, the intervals lost accuracy
      // (AWideIntervalSendsTheBoxToRationals makes such boxes; these seeded ones need none).
      if (r.why.find("wider than") != std::string::npos) {
        EXPECT_GT(r.rejected_width, kMaxRelativeWidth * volume(boxes[i])) << r.why;
        EXPECT_LE(r.rejected_width, bound) << r.why;
      }
      continue;
    }
    tally->worst_width_ratio = std::max(tally->worst_width_ratio, (r.hi - r.lo) / bound);
  }
}

// Seeded boxes in general position: at least 1,000 checked, the intervals decided every box,
// and every width lies within its bound.
void expect_ordinary(const Tally& tally, const char* what) {
  EXPECT_GE(tally.boxes, 1000);
  EXPECT_EQ(tally.exact_boxes, 0);
  EXPECT_LE(tally.worst_width_ratio, 1.0);
  std::printf("%s: %d boxes, %d exact signs, %d exact faces, worst width / bound %.3g\n", what,
              tally.boxes, tally.exact_signs, tally.exact_faces, tally.worst_width_ratio);
}

TEST(PolySolver, EnclosesTheExactValueOnAnalyticMeshes) {
  Tally tally;
  uint64_t seed = 1;
  for (const AnalyticMesh& a : analytic::all())
    check_all(a.mesh, random_boxes(a.mesh, 200, seed++), &tally, a.name);
  expect_ordinary(tally, "analytic");
}

TEST(PolySolver, EnclosesTheExactValueOnRealMeshesAtEverySize) {
  using validate::BoxSize;
  Tally tally;
  int meshes = 0;
  for (const char* name : {"dino", "knot1", "elephant"}) {
    if (!test::exists(test::real_mesh(name))) continue;
    ++meshes;
    LoadedMesh lm;
    ASSERT_TRUE(load_solid(test::real_mesh(name), &lm));
    uint64_t seed = 7;
    for (auto [size, count] :
         {std::pair{BoxSize::kLeaf, 200}, {BoxSize::kMid, 100}, {BoxSize::kRoot, 34}})
      check_all(lm.mesh, validate::box_corpus(lm.mesh, size, count, seed++), &tally,
                std::string(name) + " " + validate::to_string(size));
  }
  if (meshes < 3) VOBB_SKIP_WITHOUT_REAL_MESHES("dino, knot1 and elephant are needed");
  expect_ordinary(tally, "real");
}

// The double estimate (the builder's) against the exact value. Each box: the estimate runs the
// interval path's operations in double, rounded to nearest (half of the 2^-52 per operation
// that width_bound counts), so its error, plus the exact value's rounding to double (half an
// ulp of a value at most vol(B)), lies within width_bound. Over the boxes: the median the
// header states, at most 1e-12 of the box's volume.
TEST(PolySolver, DoubleEstimateIsExactToRoundOff) {
  const AnalyticMesh torus = analytic::polygonal_torus();
  const std::vector<Obb> boxes = random_boxes(torus.mesh, 200, 99);
  const PolyObvSolver poly(torus.mesh);
  const std::vector<double> est = poly.estimate(boxes);
  std::vector<double> rel;
  for (size_t i = 0; i < boxes.size(); ++i) {
    const double err = std::abs(est[i] - to_double_nearest(poly.exact(boxes[i])));
    EXPECT_LE(err, width_bound(poly.evaluate(boxes[i]), boxes[i], torus.mesh)) << "box " << i;
    rel.push_back(err / volume(boxes[i]));
  }
  std::nth_element(rel.begin(), rel.begin() + rel.size() / 2, rel.end());
  EXPECT_LE(rel[rel.size() / 2], 1e-12);
}

// A box centred on a plane face of the cube, reaching across it but not beyond the face's
// edges: by the box's central symmetry exactly half of it lies outside, whatever its
// orientation. vol(B) is the exact rational 8 |det U|.
TEST(PolySolver, PlaneCutBoxIsHalfOutside) {
  const AnalyticMesh cube = analytic::cube(2.0);  // [-1, 1]^3 or [0, 2]^3: read its bounds
  Aabb bounds;
  for (const Vec3& v : cube.mesh.vertices) bounds.extend(v);
  const Vec3 mid = 0.5 * (bounds.lo + bounds.hi);
  const PolyObvSolver poly(cube.mesh);
  for (int face = 0; face < 3; ++face)
    for (double angle : {0.0, 0.3, 1e-9, 1.2}) {
      Vec3 c = mid;
      c[face] = bounds.hi[face];
      const Obb b = rotated_box(c, Vec3(0.3, 0.2, 0.25), angle, Vec3(0.2, 1, 0.5));
      const Rational half_volume = exact_volume(b) / 2;
      const PolyObv r = poly.evaluate(b);
      SCOPED_TRACE("face " + std::to_string(face) + " angle " + std::to_string(angle));
      EXPECT_TRUE(encloses(r, half_volume));
      EXPECT_EQ(poly.exact(b), half_volume);
    }
}

// Boxes in special position: faces in the mesh's planes, centres on a vertex, an edge and a
// face, the cube itself and the cavity itself. The intervals cannot decide these; the exact
// fallback must, and the result still encloses the rational.
TEST(PolySolver, SpecialPositionsFallBackToRationalsAndStillEnclose) {
  const AnalyticMesh cube = analytic::cube(2.0);
  Aabb bounds;
  for (const Vec3& v : cube.mesh.vertices) bounds.extend(v);
  const Vec3 mid = 0.5 * (bounds.lo + bounds.hi), half = 0.5 * (bounds.hi - bounds.lo);
  const PolyObvSolver poly(cube.mesh);
  std::vector<Obb> boxes = {
      rotated_box(mid, half),                                              // the cube itself
      rotated_box(bounds.hi, 0.25 * half),                                 // centred on a vertex
      rotated_box(Vec3(mid[0], bounds.hi[1], bounds.hi[2]), 0.25 * half),  // an edge
      rotated_box(Vec3(mid[0], mid[1], bounds.hi[2]), 0.25 * half),        // a face
      rotated_box(mid + Vec3(0, 0, 0.5 * half[2]), Vec3(half[0], half[1], 0.5 * half[2]))};
  int fell_back = 0;
  for (size_t i = 0; i < boxes.size(); ++i) {
    const PolyObv r = poly.evaluate(boxes[i]);
    EXPECT_TRUE(encloses(r, poly.exact(boxes[i]))) << "box " << i;
    fell_back += r.exact_signs > 0 || r.exact_faces > 0 || r.exact_box;
  }
  EXPECT_GT(fell_back, 0);
  // The closed forms, as rationals: the cube and its upper half have no outer volume in
  // themselves; an aligned box centred on a vertex, an edge or a face (and inside the face's
  // edges) has 1/8, 1/4 or 1/2 of its volume inside the cube.
  EXPECT_EQ(poly.exact(boxes[0]), Rational(0));
  EXPECT_EQ(poly.exact(boxes[1]), exact_volume(boxes[1]) * 7 / 8);
  EXPECT_EQ(poly.exact(boxes[2]), exact_volume(boxes[2]) * 3 / 4);
  EXPECT_EQ(poly.exact(boxes[3]), exact_volume(boxes[3]) / 2);
  EXPECT_EQ(poly.exact(boxes[4]), Rational(0));
  // The cavity [1, 3]^3 of the cube [0, 4]^3 (analytic_meshes.h): a box on its very faces is
  // outside the solid whole, 8 units; and the same turned by 1e-9 rad.
  const AnalyticMesh cav = analytic::cube_with_cavity();
  const PolyObvSolver pc(cav.mesh);
  const Obb cavity = rotated_box(Vec3(2, 2, 2), Vec3(1, 1, 1));
  const PolyObv rc = pc.evaluate(cavity);
  EXPECT_TRUE(encloses(rc, Rational(8)));
  EXPECT_GT(rc.exact_signs + rc.exact_faces + int(rc.exact_box), 0);
  const Obb turned = rotated_box(Vec3(2, 2, 2), Vec3(1, 1, 1), 1e-9);
  EXPECT_TRUE(encloses(pc.evaluate(turned), pc.exact(turned)));
}

// Far offsets, scales of 2^+-20, thin slabs and needles: still enclosed and finite.
TEST(PolySolver, StiffScalesAndShapes) {
  const AnalyticMesh torus = analytic::polygonal_torus();
  for (double scale : {0x1p-20, 1.0, 0x1p20})
    for (double offset : {0.0, 1e6}) {
      Mesh m = torus.mesh;
      for (Vec3& v : m.vertices) v = scale * v + Vec3(offset, -offset, 0.5 * offset);
      std::vector<Obb> boxes = random_boxes(m, 12, 3);
      for (Obb b : random_boxes(m, 6, 4)) {  // slabs and needles
        b.half[0] *= 1e-8;
        boxes.push_back(b);
        b.half[1] *= 1e-6;
        boxes.push_back(b);
      }
      Tally tally;
      check_all(m, boxes, &tally,
                "scale " + std::to_string(scale) + " offset " + std::to_string(offset));
      EXPECT_LE(tally.worst_width_ratio, 1.0);
    }
}

// Degenerate and extreme inputs: a flat box is [0, 0]; a box beyond the intervals' safe range
// says so and is evaluated in rationals; nothing is NaN or infinite.
TEST(PolySolver, DegenerateAndOutOfRangeBoxes) {
  const AnalyticMesh cube = analytic::cube(2.0);
  const PolyObvSolver poly(cube.mesh);
  Obb flat = rotated_box(Vec3(0.5, 0.5, 0.5), Vec3(0.3, 0, 0.2));
  const PolyObv f = poly.evaluate(flat);
  EXPECT_EQ(f.lo, 0.0);
  EXPECT_EQ(f.hi, 0.0);
  EXPECT_EQ(poly.estimate(flat), 0.0);
  EXPECT_TRUE(poly.exact(flat) == Rational(0));
  // Half extents of 2^110 (R = 2^330 unscaled): in units of 2^110 an ordinary box, enclosed by
  // the intervals.
  const Obb huge = rotated_box(Vec3(0.5, 0.5, 0.5), Vec3(0x1p110, 0x1p110, 0x1p110), 0.4);
  const PolyObv h = poly.evaluate(huge);
  EXPECT_FALSE(h.exact_box) << h.why;
  EXPECT_TRUE(encloses(h, poly.exact(huge)));
  EXPECT_TRUE(std::isfinite(poly.estimate(huge)));
  // Half extents of 2^-310 below the cube's top face: in the box's units that face lies about
  // 2^310 away, beyond the safe range 2^300, so the box goes to rationals and says so.
  const Obb needle_far = rotated_box(Vec3(0.5, 0.5, 0.5), Vec3(0x1p-310, 0x1p-310, 0x1p-310), 0.4);
  const PolyObv n = poly.evaluate(needle_far);
  EXPECT_TRUE(n.exact_box);
  EXPECT_NE(n.why.find("range"), std::string::npos) << n.why;
  EXPECT_TRUE(encloses(n, poly.exact(needle_far)));
  // Tiny: half extents of 2^-60 about a point inside: no outer volume; and about a point
  // outside: all of it outside.
  for (const Vec3& c : {Vec3(0.5, 0.5, 0.5), Vec3(7, 7, 7)}) {
    const Obb tiny = rotated_box(c, Vec3(0x1p-60, 0x1p-61, 0x1p-59), 0.7);
    const PolyObv t = poly.evaluate(tiny);
    EXPECT_TRUE(std::isfinite(t.lo) && std::isfinite(t.hi));
    const Rational expected = c[0] < 2 ? Rational(0) : exact_volume(tiny);
    EXPECT_EQ(poly.exact(tiny), expected);
    EXPECT_TRUE(encloses(t, expected));
  }
}

// A box's evaluation runs in units of 2^e near its own size, so the mesh and the boxes scaled
// by 2^k give the same numbers times 2^3k, bit for bit (box_frame_clip.h, Frame), and no box
// leaves the intervals: at 2^200 the unscaled R would lie beyond the safe range and the
// estimate's sum overflow; at 2^-200 the terms (lengths to the 9th power) underflow.
TEST(PolySolver, ScalingByAPowerOfTwoScalesTheResultsExactly) {
  const AnalyticMesh torus = analytic::polygonal_torus();
  const std::vector<Obb> boxes = random_boxes(torus.mesh, 30, 5);
  const PolyObvSolver poly(torus.mesh);
  for (const int k : {200, -200, 230}) {
    Mesh scaled = torus.mesh;
    for (Vec3& v : scaled.vertices)
      for (int i = 0; i < 3; ++i) v[i] = std::ldexp(v[i], k);
    const PolyObvSolver spoly(scaled);
    int checked_exactly = 0;
    for (const Obb& b : boxes) {
      Obb sb = b;
      for (int i = 0; i < 3; ++i) {
        sb.center[i] = std::ldexp(b.center[i], k);
        sb.half[i] = std::ldexp(b.half[i], k);
      }
      const PolyObv r = poly.evaluate(b), sr = spoly.evaluate(sb);
      ASSERT_FALSE(r.exact_box) << r.why;
      EXPECT_FALSE(sr.exact_box) << "k " << k << ": " << sr.why;
      EXPECT_EQ(sr.lo, std::ldexp(r.lo, 3 * k)) << "k " << k;
      EXPECT_EQ(sr.hi, std::ldexp(r.hi, 3 * k)) << "k " << k;
      EXPECT_EQ(spoly.estimate(sb), std::ldexp(poly.estimate(b), 3 * k)) << "k " << k;
      if (checked_exactly++ < 3) {
        EXPECT_TRUE(encloses(sr, spoly.exact(sb))) << "k " << k;
      }
    }
  }
}

// A deliberately broken evaluator is caught: one face's term with its sign flipped, or one
// face's term dropped (as a skipped clip would), makes some exact value fall outside.
TEST(PolySolver, BrokenEvaluatorIsCaught) {
  const AnalyticMesh torus = analytic::polygonal_torus();
  const std::vector<Obb> boxes = random_boxes(torus.mesh, 40, 11);
  PolyObvSolver poly(torus.mesh);
  for (PolyObvSolver::Damage damage : {PolyObvSolver::Damage([](double*lo, double*hi, int32_t f) {
                                         if (f % 7 == 3) std::swap(*lo = -*lo, *hi = -*hi);
                                       }),
                                       PolyObvSolver::Damage([](double*lo, double*hi, int32_t f) {
                                         if (f % 7 == 3) *lo = *hi = 0;
                                       })}) {
    poly.set_damage_for_tests(damage);
    int caught = 0;
    for (const Obb& b : boxes) {
      const PolyObv r = poly.evaluate(b);
      caught += !encloses(r, poly.exact(b));
    }
    EXPECT_GT(caught, 0);
  }
}

// An interval wider than kMaxRelativeWidth of the box's volume sends the box to rationals. One
// face in seven is given a term a unit wider each way. In the box's units R = h0 h1 h2 (about)
// lies in [1, 32) (docs/derivations.md, "Interval range"), so each such face whose term is added
// (a face the clip leaves nothing of adds none) widens the OBV by at least 2 / (6 R^2) > 3e-4, far
// above 1e-9 of the volume 8 R < 256. A box goes to rationals only where its column (the faces
// evaluate visits) holds such a face; it says so, gives the width it rejected, and returns the
// rational value's enclosure. The others are still enclosed by intervals (these boxes need no
// rationals undamaged: EnclosesTheExactValueOnAnalyticMeshes).
TEST(PolySolver, AWideIntervalSendsTheBoxToRationals) {
  const AnalyticMesh torus = analytic::polygonal_torus();
  const std::vector<Obb> boxes = random_boxes(torus.mesh, 40, 12);
  PolyObvSolver poly(torus.mesh);
  poly.set_damage_for_tests([](double* lo, double* hi, int32_t f) {
    if (f % 7 == 3) *lo -= 1, *hi += 1;
  });
  const AabbTree tree = AabbTree::over_faces(torus.mesh);
  int wide = 0;
  for (const Obb& b : boxes) {
    const PolyObv r = poly.evaluate(b);
    const Rational exact = poly.exact(b);
    EXPECT_TRUE(encloses(r, exact));
    const box_clip::Column column = box_clip::fewest_faces_column(b, torus.mesh, tree);
    const bool damaged =
        std::any_of(column.faces.begin(), column.faces.end(), [](int32_t f) { return f % 7 == 3; });
    if (!r.exact_box) continue;
    EXPECT_TRUE(damaged) << "no damaged face, yet " << r.why;
    ASSERT_NE(r.why.find("wider than"), std::string::npos) << r.why;
    ++wide;
    EXPECT_GT(r.rejected_width, kMaxRelativeWidth * volume(b)) << r.why;
    EXPECT_EQ(r.estimate, to_double_nearest(exact));
    double lo, hi;
    enclose(exact, &lo, &hi);
    EXPECT_EQ(r.lo, lo);
    EXPECT_EQ(r.hi, hi);
  }
  EXPECT_GT(wide, 0);
}

}  // namespace
}  // namespace vobb
