// The cubemap estimator against the exact OBV (issue 4's accuracy tests): the GL estimator on
// seeded corpora of leaf, mid and root-sized boxes over dino, knot1 and elephant
// (validate/box_corpus.h), the exact values from the clipping path of the exact solver.
#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdlib>
#include <map>

#include "common/io/mesh_report.h"
#include "data/analytic_meshes.h"
#include "exact/outer_volume.h"
#include "fast/cubemap_bound.h"
#include "fast/estimator_test_util.h"
#include "fast/gl_estimator.h"
#include "fast/gl_test_util.h"
#include "test_common.h"
#include "validate/box_corpus.h"
#include "validate/estimators.h"

namespace vobb {
namespace {

double median(std::vector<double> v) {
  std::sort(v.begin(), v.end());
  const size_t n = v.size();
  return n % 2 ? v[n / 2] : 0.5 * (v[n / 2 - 1] + v[n / 2]);
}

// The CPU prototype's median relative errors at m = 32 (DESIGN §4): leaf, mid, root.
const std::map<validate::BoxSize, double> kPrototypeMedian32 = {{validate::BoxSize::kLeaf, 4.5e-4},
                                                                {validate::BoxSize::kMid, 1.2e-4},
                                                                {validate::BoxSize::kRoot, 6.4e-5}};

TEST(EstimatorAccuracy, RealMeshesMatchThePrototypeAndConvergeWithM) {
  using validate::BoxSize;
  const int kResolutions[] = {16, 32, 64};
  std::map<BoxSize, std::map<int, std::vector<double>>> rel;  // size -> m -> relative errors
  int meshes = 0;
  for (const char* name : {"dino", "knot1", "elephant"}) {
    if (!test::exists(test::real_mesh(name))) {
      if (test::real_meshes_required())
        ADD_FAILURE() << name << " is absent (VOBB_REQUIRE_REAL_MESHES=1)";
      continue;
    }
    ++meshes;
    LoadedMesh lm;
    ASSERT_TRUE(load_solid(test::real_mesh(name), &lm));
    VOBB_MAKE_GL(gl, lm.mesh);
    ASSERT_TRUE(gl);
    const exact::ClipSolver exact(lm.mesh);
    uint64_t seed = 100;
    for (BoxSize size : {BoxSize::kLeaf, BoxSize::kMid, BoxSize::kRoot}) {
      const std::vector<Obb> boxes = validate::box_corpus(lm.mesh, size, 30, seed++);
      std::vector<Rational> obv;
      std::vector<double> truth;
      for (const Obb& b : boxes) {
        obv.push_back(exact.obv(b));
        truth.push_back(to_double_nearest(obv.back()));
      }
      for (int m : kResolutions) {
        const std::vector<double> est = gl->estimate(boxes, m);
        for (size_t i = 0; i < boxes.size(); ++i) {
          ASSERT_TRUE(std::isfinite(est[i]));
          // The GL backend's rigorous bound (fast/cubemap_bound.h) holds for every box, against
          // the exact rational.
          EXPECT_LE(abs(Rational(est[i]) - obv[i]),
                    Rational(cubemap_bound(gl->planner(), true, boxes[i], m)))
              << name << " " << validate::to_string(size) << " box " << i << " m " << m;
          if (truth[i] > 0) rel[size][m].push_back(std::abs(est[i] - truth[i]) / truth[i]);
        }
      }
    }
  }
  if (meshes == 0) VOBB_SKIP_WITHOUT_REAL_MESHES("no real meshes");
  for (const auto& [size, by_m] : rel) {
    const double m16 = median(by_m.at(16)), m32 = median(by_m.at(32)), m64 = median(by_m.at(64));
    std::printf(
        "%-5s boxes %3zu  median relative error  m=16 %.2e  m=32 %.2e  m=64 %.2e  (prototype m=32 "
        "%.1e)\n",
        validate::to_string(size), by_m.at(32).size(), m16, m32, m64, kPrototypeMedian32.at(size));
    // The criterion: at least as good as the prototype within a factor of 2.
    EXPECT_LE(m32, 2 * kPrototypeMedian32.at(size)) << validate::to_string(size);
    EXPECT_LT(m64, m16) << validate::to_string(size);
  }
}

// On analytic meshes too the error falls as m doubles: medians over seeded boxes of all sizes.
TEST(EstimatorAccuracy, AnalyticMeshesConvergeWithM) {
  for (const auto& a :
       {analytic::polygonal_torus(), analytic::cube_with_cavity(), analytic::octahedron()}) {
    VOBB_MAKE_GL(gl, a.mesh);
    ASSERT_TRUE(gl);
    const exact::ClipSolver exact(a.mesh);
    std::vector<Obb> boxes;
    for (auto size :
         {validate::BoxSize::kLeaf, validate::BoxSize::kMid, validate::BoxSize::kRoot}) {
      const auto part = validate::box_corpus(a.mesh, size, 20, 7);
      boxes.insert(boxes.end(), part.begin(), part.end());
    }
    std::vector<double> truth;
    for (const Obb& b : boxes) truth.push_back(to_double_nearest(exact.obv(b)));
    std::map<int, std::vector<double>> rel;
    for (int m : {16, 64}) {
      const std::vector<double> est = gl->estimate(boxes, m);
      for (size_t i = 0; i < boxes.size(); ++i)
        if (truth[i] > 0) rel[m].push_back(std::abs(est[i] - truth[i]) / truth[i]);
    }
    EXPECT_LT(median(rel[64]), median(rel[16])) << a.name;
  }
}

// The plan's own rounding (texel_plan.h). A review found thin boxes lying against a face of a
// rotated cube, into which the face reaches by less than the rounding of the local
// coordinates (about u |v - c| / h_min box units): the face was culled, both bounds were 0,
// and the exact OBV was 2e-18 on a box of volume 1.2e-4 (against a round-off term of 8.7e-19),
// and 4e-19 on one of volume 5e-13. Those boxes, as the review wrote them: every estimate must
// lie within the rigorous bound, on both backends and at every m.
TEST(EstimatorAccuracy, ThinBoxesAgainstAFaceStayWithinTheRigorousBound) {
  const Vec3 &a0 = test::kTurnedA0, &a1 = test::kTurnedA1, &a2 = test::kTurnedA2;
  const Mesh cube = test::turned_cube();
  const struct {
    Vec3 centre;
    double thin;
  } found[] = {
      {{0.2550162032366137, 0.06512389725871584, -0.9974337767986817}, 0.0001705437121817394},
      {{0.9132887639120676, -0.25147759077902765, -0.6813402486892141}, 0.00014672583113627726},
      {{0.7055328873198455, 0.35460583464325646, -0.8621970457854268}, 6.974842986710948e-13},
      {{0.5497074482787226, -0.23532724463281296, -0.8307250250171522}, 1.2654520027763984e-13},
      {{0.3330992093261267, 0.07464661967511539, -0.9676491201896293}, 5.484320266453931e-12},
  };
  std::vector<Obb> boxes;
  for (const auto& f : found) {
    Obb b;
    b.center = f.centre;
    b.axes = {a0, a1, a2};
    b.half = Vec3(0.3, 0.3, f.thin);
    boxes.push_back(b);
  }
  const exact::ClipSolver exact(cube);
  validate::EstimatorSet estimators(cube, true);
  ASSERT_TRUE(estimators.has_gl()) << estimators.gl_status();
  std::vector<double> truth;
  for (const Obb& b : boxes) {
    truth.push_back(to_double_nearest(exact.obv(b)));
    EXPECT_GT(truth.back(), 0);  // the face reaches into every one of them
  }
  for (validate::Backend backend : {validate::Backend::kCpu, validate::Backend::kGl})
    for (int m : {1, 4, 32}) {
      std::vector<double> seconds;
      const std::vector<double> est = estimators.estimate(backend, boxes, m, &seconds);
      for (size_t i = 0; i < boxes.size(); ++i)
        EXPECT_LE(std::abs(est[i] - truth[i]), estimators.rigorous_bound(boxes[i], m))
            << validate::to_string(backend) << " m " << m << " box " << i << " exact " << truth[i]
            << " estimate " << est[i];
    }
}

// Rays through a vertex of many faces (texel_plan.h, LocalTriangle): bipyramids whose apexes
// lie exactly on a texel ray of m = 8 and m = 24, with 48 faces at each. Decided on the rounded
// edge crosses, such a ray was claimed by about a dozen faces at each apex, and the CPU twin's
// estimate was off by several pyramids, where its own bound (resolution_bound, one pyramid per
// texel the surface crosses, plus cpu_rounding_bound and the round-off term) allowed about
// one. The CPU twin must lie within that bound, the GL estimator within its rigorous bound
// (which adds its float deviation: every such tie is an uncertain pair there).
TEST(EstimatorAccuracy, RaysThroughAVertexOfManyFacesStayWithinTheRigorousBound) {
  const Vec3 d(1, 0.375, -0.375);  // texel (5, 2) of cubemap face +x at m = 8, (16, 7) at m = 24
  Obb box;
  box.center = Vec3::Zero();
  box.half = Vec3(1, 1, 1);
  for (unsigned seed = 0; seed < 6; ++seed) {
    const Mesh mesh = test::bipyramid_on_ray(d, 48, seed);
    const double truth = to_double_nearest(exact::ClipSolver(mesh).obv(box));
    validate::EstimatorSet estimators(mesh, true);
    ASSERT_TRUE(estimators.has_gl()) << estimators.gl_status();
    for (validate::Backend backend : {validate::Backend::kCpu, validate::Backend::kGl})
      for (int m : {8, 24}) {
        std::vector<double> seconds;
        const double est = estimators.estimate(backend, {box}, m, &seconds)[0];
        const validate::EstimatorSet::Bounds b = estimators.bounds(box, m);
        const double bound = backend == validate::Backend::kCpu ? b.cpu_rigorous() : b.rigorous();
        EXPECT_LE(std::abs(est - truth), bound)
            << validate::to_string(backend) << " m " << m << " seed " << seed << " exact " << truth
            << " estimate " << est;
      }
  }
}

// Boxes so small that their volume is subnormal (half extents near 1e-108): the volume scale
// |det[h0 a0, h1 a1, h2 a2]| then loses up to half a subnormal step (2^-1075) per operation
// instead of a relative eps, so a bound made of relative terms (32 eps vol, 0 here) allowed
// no error at all, while the estimate was off by several steps. The round-off term carries an
// absolute allowance for underflow; every estimate must lie within the rigorous bound. The
// boxes lie outside the solid (the needles run along x at y = z = 5), so the exact OBV is the
// box's volume, taken exactly.
TEST(EstimatorAccuracy, BoxesOfSubnormalVolumeStayWithinTheRigorousBound) {
  const Mesh cube = analytic::cube().mesh;
  validate::EstimatorSet estimators(cube, true);
  ASSERT_TRUE(estimators.has_gl()) << estimators.gl_status();
  const exact::ClipSolver exact(cube);
  std::vector<Obb> boxes;
  for (double h : {3e-108, 1e-108, 4e-109, 1e-110}) {
    Obb box;
    box.center = Vec3(5, 5, 5);
    box.axes = {test::kTurnedA0, test::kTurnedA1, test::kTurnedA2};
    box.half = Vec3(h, 1.3 * h, 0.7 * h);
    boxes.push_back(box);
  }
  // Needles whose volume is normal while h0 h1 is not (a review: multiplied left to right the
  // volume lost its digits, or became 0 and the box flat).
  for (const Vec3& h :
       {Vec3(1.1 * 0x1p-540, 1.3 * 0x1p-520, 0x1p200), Vec3(0x1p-600, 0x1p-500, 0x1p200)}) {
    Obb box;
    box.center = Vec3(5, 5, 5);
    box.half = h;
    boxes.push_back(box);
  }
  for (const Obb& box : boxes) {
    const double h = box.half[0];
    const double truth = to_double_nearest(exact.obv(box));
    for (validate::Backend backend : {validate::Backend::kCpu, validate::Backend::kGl}) {
      std::vector<double> seconds;
      const double est = estimators.estimate(backend, {box}, 4, &seconds)[0];
      EXPECT_LE(std::abs(est - truth), estimators.rigorous_bound(box, 4))
          << validate::to_string(backend) << " h " << h << " exact " << truth << " estimate "
          << est;
    }
  }
}

// Boxes whose view of the mesh doubles cannot hold (texel_plan.h, BoxPlan::unresolved), found
// by a review: a half extent of 1e-306 beside faces a unit away puts them 1e306 box units out,
// where local coordinates overflow (the CPU twin then crashed in GMP on an infinite cross,
// or dropped every face, estimate 0 against an exact 2e-306 with a bound of 6e-320), and axes
// whose determinant double rounds to 0 although the box has volume (box_frame aborted). Each
// gets half its volume, with the other half as its bound, on both backends; the suite's front
// door refuses the last (its axes are not orthonormal).
TEST(EstimatorAccuracy, BoxesTheDoublesCannotPlanStayWithinTheRigorousBound) {
  const Mesh cube = analytic::cube(400.0, Vec3(-200, -200, -200)).mesh;
  validate::EstimatorSet estimators(cube, true);
  ASSERT_TRUE(estimators.has_gl()) << estimators.gl_status();
  const exact::ClipSolver exact(cube);
  std::vector<Obb> boxes(3);
  boxes[0].center = Vec3(0, 0, 200);  // on the top face
  boxes[1].center = Vec3(0, 0, 199.5);
  boxes[0].half = boxes[1].half = Vec3(1e-306, 1, 1);
  boxes[2].center = Vec3(0, 0, 199.5);
  boxes[2].half = Vec3(1, 1, 1);
  boxes[2].axes = {Vec3(0, 0.20000000000000001, -0.20000000000000001),
                   Vec3(-0.30000000000000004, 0.20000000000000001, 0),
                   Vec3(-0.30000000000000004, 0.40000000000000008, -0.20000000000000001)};
  ASSERT_GT(volume(boxes[2]), 0);
  EXPECT_FALSE(estimators.check_request(validate::Backend::kCpu, boxes[2], 4));
  // The truths in closed form, so that the test does not rest on the bound alone (any value in
  // [0, vol] is within vol / 2 of half the volume): box 0 straddles the face z = 200 at its
  // middle, so half of it is outside; box 1 spans z in [198.5, 200.5], a quarter outside.
  const Rational vol01 = Rational(8) * Rational(1e-306);
  EXPECT_TRUE(exact.obv(boxes[0]) == vol01 / 2);
  EXPECT_TRUE(exact.obv(boxes[1]) == vol01 / 4);
  const BoxPlanner planner(cube);
  for (size_t i = 0; i < boxes.size(); ++i) {
    EXPECT_TRUE(planner.plan(boxes[i], 4).unresolved) << "box " << i;
    const double truth = to_double_nearest(exact.obv(boxes[i]));
    for (validate::Backend backend : {validate::Backend::kCpu, validate::Backend::kGl}) {
      std::vector<double> seconds;
      const double est = estimators.estimate(backend, {boxes[i]}, 4, &seconds)[0];
      // Exactly half the volume: the planner's volume / 8 times 4, powers of two of a normal
      // double. An estimate of 0 (every face dropped, the defect this test was written for)
      // fails here although it is within the bound of box 1's truth.
      EXPECT_EQ(est, volume(boxes[i]) / 2) << validate::to_string(backend) << " box " << i;
      EXPECT_LE(std::abs(est - truth), estimators.rigorous_bound(boxes[i], 4))
          << validate::to_string(backend) << " box " << i << " exact " << truth << " estimate "
          << est;
    }
  }
}

}  // namespace
}  // namespace vobb
