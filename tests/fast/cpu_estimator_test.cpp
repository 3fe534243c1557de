#include "fast/cpu_estimator.h"

#include <gtest/gtest.h>
#include <tbb/info.h>
#include <tbb/task_arena.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <random>
#include <utility>
#include <vector>

#include "arena_threads.h"
#include "data/analytic_meshes.h"
#include "fast/cubemap.h"
#include "fast/cubemap_bound.h"
#include "fast/estimator_test_util.h"
#include "fast/texel_plan.h"
#include "test_common.h"

namespace vobb {
namespace {

Obb aabox(const Vec3& c, const Vec3& h) {
  Obb b;
  b.center = c;
  b.half = h;
  return b;
}

// Tolerances: cpu_rounding_bound (texel_plan.h) bounds |CPU - exact evaluation of the plan|.
// Where the box is axis-aligned with power-of-two half extents and a dyadic centre over the
// dyadic cube, the plan itself is exact (local coordinates, crosses, planes, scale), so that
// bound is the whole tolerance against the closed form; otherwise the plan's own rounding is
// added (aligned_plan_round_off, estimator_test_util.h).

TEST(CpuEstimator, DisjointBoxIsItsVolume) {
  const Mesh m = analytic::cube().mesh;
  const CpuObvEstimator est(m);
  const Obb b = aabox(Vec3(5, 5, 5), Vec3(1, 2, 0.5));
  for (int res : {1, 7, 32})
    EXPECT_NEAR(est.estimate(b, res), volume(b),
                cpu_rounding_bound(BoxPlanner(m).plan(b, res), res))
        << res;
  EXPECT_EQ(est.faces_used(), 0u);  // culling: nothing drawn for a box that meets no face
}

// A cube centred on the viewpoint projects exactly onto the cubemap's faces, and planes
// parallel to a cubemap face are integrated exactly: the estimate is exact at any m. The box
// [-1.5, 2.5]^3 (half extents 2) keeps the plan exact; the cube is convex, so a ray from its
// centre crosses it once.
TEST(CpuEstimator, CubeCentredInAnAlignedBoxIsExact) {
  const Mesh m = analytic::cube().mesh;  // [0, 1]^3, volume 1
  const CpuObvEstimator est(m);
  const Obb b = aabox(Vec3(0.5, 0.5, 0.5), Vec3(2, 2, 2));
  for (int res : {1, 2, 3, 8, 64}) {
    const double bound = cpu_rounding_bound(BoxPlanner(m).plan(b, res), res);
    EXPECT_NEAR(est.estimate(b, res), 64.0 - 1.0, bound) << res;
    // Not vacuous: every tie was settled exactly, so the bound is round-off, far below a texel.
    EXPECT_LT(bound, 1e-6 * volume(b) * 4.0 / (3.0 * res * res)) << res;
  }
  // A box strictly inside: no outer volume.
  const Obb inside = aabox(Vec3(0.5, 0.5, 0.5), Vec3(0.25, 0.25, 0.25));
  EXPECT_NEAR(est.estimate(inside, 8), 0.0, cpu_rounding_bound(BoxPlanner(m).plan(inside, 8), 8));
}

// Off centre, the cube's faces cross cubemap faces at an angle: the error must shrink as m grows.
// The error falls about as m^-2 but often changes sign between m and 2m (DESIGN §4), so one
// box's error at 8 or 16 is compared with 4x its error at 64 (m^-2 predicts 16x from 16 to
// 64). At every m the error lies within the CPU twin's rigorous bound (cubemap_bound.h:
// resolution_bound, which holds the plan's rounding of the faces, plus the evaluation's and the
// volume scale's round-off). Both centres lie outside the cube, so that some texels miss the
// surface and the bound says something: it must stay below the box's volume.
TEST(CpuEstimator, OffCentreErrorShrinksWithResolution) {
  const Mesh m = analytic::cube().mesh;
  const CpuObvEstimator est(m);
  const BoxPlanner planner(m);
  for (const Vec3& c : {Vec3(1.25, 0.75, 0.6), Vec3(-0.5, 0.5, 0.5)}) {
    const Obb b = aabox(c, Vec3(1.5, 1.5, 1.5));  // holds the whole cube: OBV = 27 - 1
    double e[3];
    int i = 0;
    for (int res : {8, 16, 64}) {
      e[i] = std::abs(est.estimate(b, res) - 26);
      const double bound = cubemap_bounds(planner, b, res).cpu_rigorous();
      EXPECT_LT(bound, volume(b)) << c.transpose() << " m " << res;
      EXPECT_LE(e[i], bound) << c.transpose() << " m " << res;
      ++i;
    }
    EXPECT_LT(4 * e[2], std::max(e[0], e[1])) << c.transpose();
  }
}

TEST(CpuEstimator, FiniteAndConsistentForCentresOnFacesEdgesAndVertices) {
  const Mesh m = analytic::cube().mesh;
  const CpuObvEstimator est(m);
  const BoxPlanner planner(m);
  // Boxes around the corner (0,0,0): centre on a vertex, on an edge, on a face, and nearby.
  const Vec3 h(0.3, 0.2, 0.25);
  const Vec3 on[] = {Vec3(0, 0, 0), Vec3(0.5, 0, 0), Vec3(0.5, 0.5, 0), Vec3(1, 1, 0.5)};
  for (const Vec3& c : on) {
    const Obb b = aabox(c, h);
    const double v = est.estimate(b, 32);
    ASSERT_TRUE(std::isfinite(v));
    const double round_v =
        cpu_rounding_bound(planner.plan(b, 32), 32) + test::aligned_plan_round_off(m, 6, b);
    // The same box nudged off the surface both ways: the value moves continuously, so it must
    // stay within the change of the exact OBV over the nudge (at most the box's face area times
    // the nudge) plus the estimator's error, which for this aligned geometry is round-off.
    const double area = 8 * (h[0] * h[1] + h[1] * h[2] + h[2] * h[0]);  // the box's surface
    for (double eps : {1e-9, -1e-9}) {
      const Obb nudged = aabox(c + Vec3::Constant(eps), h);
      const double w = est.estimate(nudged, 32);
      const double round_w = cpu_rounding_bound(planner.plan(nudged, 32), 32) +
                             test::aligned_plan_round_off(m, 6, nudged);
      // Moving the box by |eps| sqrt(3) changes its exact OBV by at most area |eps| sqrt(3).
      EXPECT_NEAR(v, w, area * std::sqrt(3.0) * std::abs(eps) + round_v + round_w) << c.transpose();
    }
    EXPECT_GE(v, -round_v);
    EXPECT_LE(v, volume(b) + round_v);
  }
}

// Culling drops faces that cannot meet the box; the faces kept have the same local triangles,
// so the two estimates differ only by round-off (each within cpu_rounding_bound of the exact
// evaluation of its plan, and the two plans evaluate to the same exact value).
TEST(CpuEstimator, CullingChangesNothingButTheWork) {
  const Mesh m = analytic::polygonal_torus().mesh;
  CpuObvEstimator est(m);
  BoxPlanner planner(m);
  Obb b;
  b.center = Vec3(2, 1, 0.5);
  b.axes = orthonormalize({Vec3(1, 2, 0.3), Vec3(-1, 0.5, 1), Vec3::Zero()});
  b.half = Vec3(0.4, 0.3, 0.6);
  const double culled = est.estimate(b, 16);
  const double round_culled = cpu_rounding_bound(planner.plan(b, 16), 16);
  const size_t used = est.faces_used();
  est.set_culling(false);
  planner.set_culling(false);
  const double round_all = cpu_rounding_bound(planner.plan(b, 16), 16);
  EXPECT_NEAR(est.estimate(b, 16), culled, round_culled + round_all);
  EXPECT_LT(used, est.faces_used());
  // The bound is informative: far below one texel's pyramid.
  EXPECT_LT(round_culled + round_all, 1e-6 * volume(b) * 4.0 / (3.0 * 16 * 16));
}

// Rows of a span test only the columns where the face's edge dots may all lie on one side
// (sum_texel_hits). The hits, their values and their order do not change, so the sum is the
// same double, compared with ==: skipping in every row (width 1), in rows of kSkipFromWidth or
// more (the default), and in none. The cases include rays through vertices and along edges (the
// octahedron centred in aligned boxes at odd m; bipyramids whose apexes lie on a texel ray),
// where edge tests fall within edge_tie and are decided exactly; tiny tetrahedra on a texel
// ray, whose three edge dots all fall within edge_tie at a real hit, so that both sides' runs
// hold its column (a column visited twice would add the hit twice); faces seen nearly edge-on
// (thin boxes); and generic turned boxes, up to m = 264, where rows are wide. The skipping
// must also skip, at width 1 and at the default, or the check would be empty; how much it
// skips is CandidateRunsHoldEveryPossibleColumn's (the runs are exactly the possible columns).
TEST(CpuEstimator, SkippingRejectedTexelsChangesNoBit) {
  std::vector<std::pair<Mesh, std::vector<Obb>>> cases;
  std::mt19937 rng(7);
  std::uniform_real_distribution<double> uni(-1.0, 1.0);
  auto turned = [&](const Vec3& c, const Vec3& h) {
    Obb b;
    b.center = c;
    b.axes = orthonormalize(
        {Vec3(uni(rng), uni(rng), uni(rng)), Vec3(uni(rng), uni(rng), uni(rng)), Vec3::Zero()});
    b.half = h;
    return b;
  };
  {
    std::vector<Obb> boxes{aabox(Vec3::Zero(), Vec3(1.5, 1.5, 1.5)),
                           aabox(Vec3::Zero(), Vec3(1, 2, 3))};
    for (int i = 0; i < 6; ++i)
      boxes.push_back(turned(0.3 * Vec3(uni(rng), uni(rng), uni(rng)), Vec3(1.2, 0.9, 1.4)));
    cases.emplace_back(analytic::octahedron().mesh, boxes);
  }
  {
    std::vector<Obb> boxes;
    for (int i = 0; i < 12; ++i) {
      const double thin = i % 3 == 0 ? 1e-8 : 1.0;  // faces seen nearly edge-on
      boxes.push_back(
          turned(Vec3(2 * uni(rng), 2 * uni(rng), 0.3 * uni(rng)), Vec3(0.8, 0.6 * thin, 0.5)));
    }
    cases.emplace_back(analytic::polygonal_torus().mesh, boxes);
  }
  {
    std::vector<Obb> boxes;
    for (int i = 0; i < 8; ++i)
      boxes.push_back(turned(Vec3(uni(rng), uni(rng), uni(rng)), Vec3(1.5, 1.1, 0.7)));
    cases.emplace_back(test::turned_cube(), boxes);
  }
  // Bipyramids over a 48-gon with both apexes on the ray of texel (5, 2) of face 0 at m = 8,
  // which is a texel ray at every m = 8 (2k + 1) (as in
  // RaysThroughAVertexOfManyFacesAreClaimedOnce): the rounded crosses at an apex put the ray on the
  // wrong side of some of its edges, and the exact tests give it to one face; a skip decided
  // without edge_tie would drop that hit.
  const Vec3 on_ray = cubemap_direction(0, texel_center(5, 8), texel_center(2, 8));
  for (unsigned seed = 0; seed < 10; ++seed)
    cases.emplace_back(test::bipyramid_on_ray(on_ray, 48, seed),
                       std::vector<Obb>{aabox(Vec3::Zero(), Vec3(1, 1, 1))});
  // Tiny tetrahedra (1e-9 to 1e-12) at 0.3 along the ray of a texel of m = 8 (so of m = 24 too).
  for (int c = 0; c < 12; ++c) {
    const int face = c % 6, ti = (3 * c) % 8, tj = (5 * c + 1) % 8;
    const Vec3 at =
        0.3 * cubemap_direction(face, texel_center(ti, 8), texel_center(tj, 8)).normalized();
    Mesh tiny = analytic::tetrahedron(std::pow(10.0, -9 - c % 4)).mesh;
    for (Vec3& v : tiny.vertices) v += at;
    cases.emplace_back(tiny, std::vector<Obb>{aabox(Vec3::Zero(), Vec3(1, 1, 1))});
  }
  size_t tested_all = 0, tested_skipping = 0, tested_default = 0, plans = 0;
  for (const auto& [mesh, boxes] : cases) {
    const BoxPlanner planner(mesh);
    for (const Obb& box : boxes)
      for (int m : {5, 8, 24, 33, 72, 256, 264}) {
        BoxPlan plan;
        planner.plan(box, m, &plan);
        if (plan.flat || plan.spans.empty()) continue;
        ++plans;
        size_t n_all = 0, n_one = 0, n_default = 0;
        const double all = sum_texel_hits(plan, m, std::numeric_limits<int>::max(), &n_all);
        const double one = sum_texel_hits(plan, m, 1, &n_one);
        const double by_default = sum_texel_hits(plan, m, kSkipFromWidth, &n_default);
        EXPECT_EQ(one, all) << "m " << m << ", plans so far " << plans;
        EXPECT_EQ(by_default, all) << "m " << m << ", plans so far " << plans;
        EXPECT_LE(n_one, n_all);
        EXPECT_LE(n_default, n_all);
        tested_all += n_all;
        tested_skipping += n_one;
        tested_default += n_default;
      }
  }
  ASSERT_GT(plans, 50u);
  EXPECT_LT(tested_skipping, tested_all);
  EXPECT_LT(tested_default, tested_all);
}

// candidate_runs against the sets it must hold, found by testing every column: each run holds
// every column of its side (a run may be wider, never narrower). Rows are random and adversarial
// (eb zero, subnormal so that 1 / eb overflows, tiny against row, huge; row huge), with the
// guess shifted by up to a whole row either way, which the searches must recover from.
TEST(CpuEstimator, CandidateRunsHoldEveryPossibleColumn) {
  std::mt19937_64 rng(11);
  std::uniform_real_distribution<double> uni(-1.0, 1.0);
  const double scales[] = {0.0, 1e-310, 1e-300, 1e-17, 1e-3, 1.0, 1e3, 1e300};
  size_t nonempty = 0, exact = 0, rows = 0;
  for (int trial = 0; trial < 20000; ++trial) {
    const int m = 1 + static_cast<int>(rng() % 300);
    int j0 = static_cast<int>(rng() % m), j1 = static_cast<int>(rng() % m);
    if (j0 > j1) std::swap(j0, j1);
    double row[3], eb[3], inv_eb[3], tie[3];
    for (int k = 0; k < 3; ++k) {
      eb[k] = uni(rng) * scales[rng() % 8];
      row[k] = uni(rng) * scales[1 + rng() % 7];
      tie[k] = std::abs(uni(rng)) * 1e-3 * (std::abs(row[k]) + std::abs(eb[k]));
      inv_eb[k] = eb[k] != 0 ? 1 / eb[k] : 0;
    }
    const int shift = trial % 3 == 0 ? 0 : static_cast<int>(rng() % (2 * m + 1)) - m;
    TexelRun runs[2];
    candidate_runs(row, eb, inv_eb, tie, j0, j1, m, runs, shift);
    ++rows;
    for (int side = 0; side < 2; ++side) {
      const double sigma = side == 0 ? 1.0 : -1.0;
      int lo = j1 + 1, hi = j0 - 1;  // the columns that satisfy all three, tested one by one
      for (int j = j0; j <= j1; ++j) {
        bool all = true;
        for (int k = 0; k < 3; ++k)
          all = all && sigma * (row[k] + texel_center(j, m) * eb[k]) >= -tie[k];
        if (all) lo = std::min(lo, j), hi = std::max(hi, j);
      }
      if (lo <= hi) {
        ++nonempty;
        ASSERT_LE(runs[side].lo, lo) << "trial " << trial << ", side " << side;
        ASSERT_GE(runs[side].hi, hi) << "trial " << trial << ", side " << side;
        exact += runs[side].lo == lo && runs[side].hi == hi;
      } else {
        EXPECT_GT(runs[side].lo, runs[side].hi)
            << "trial " << trial << ": a run where no column can hit";
      }
      ASSERT_GE(runs[side].lo, j0);
      ASSERT_LE(runs[side].hi, j1);
    }
  }
  ASSERT_GT(nonempty, rows / 4);
  // Each condition is a run at one end of the row, so the searches find the set exactly.
  EXPECT_EQ(exact, nonempty);
}

// A batch is estimated in parallel, each box by one thread exactly as alone: its values must be
// the single-box values bit for bit (==, no tolerance: the same operations in the same order),
// under one thread and under several, and faces_used is the batch's total.

TEST(CpuEstimator, BatchEqualsSingleBoxesForAnyThreadCount) {
  const Mesh m = analytic::polygonal_torus().mesh;
  const CpuObvEstimator est(m);
  std::vector<Obb> boxes;
  for (int i = 0; i < 24; ++i) {
    Obb b;
    b.center = Vec3(0.3 * i - 3, 0.2 * (i % 5) - 0.4, 0.1 * (i % 3));
    b.axes = orthonormalize({Vec3(1, 0.1 * i, 0.3), Vec3(-0.2 * i, 1, 0.5), Vec3::Zero()});
    b.half = Vec3(0.3 + 0.05 * (i % 4), 0.6, 0.4 + 0.1 * (i % 2));
    boxes.push_back(b);
  }
  std::vector<double> single;
  size_t used = 0;
  for (const Obb& b : boxes) {
    single.push_back(est.estimate(b, 16));
    used += est.faces_used();
  }
  ASSERT_GT(used, 0u);  // the boxes meet the surface: not a batch of trivial boxes
  for (int threads : {1, 2, 4}) {
    auto check = [&] {
      const std::vector<double> batch = est.estimate(boxes, 16);
      ASSERT_EQ(batch.size(), single.size());
      for (size_t i = 0; i < boxes.size(); ++i)
        EXPECT_EQ(batch[i], single[i]) << threads << " threads, box " << i;
      EXPECT_EQ(est.faces_used(), used) << threads;
    };
    // A batch takes a few ms: runs are repeated until a worker joins one.
    test::expect_on_threads(threads, check, "the batch");
  }
}

}  // namespace
}  // namespace vobb

namespace vobb {
namespace {

// Rays through mesh vertices: the octahedron centred in a box sends the axis rays of odd m
// exactly through its six vertices. Every face at a vertex has the vertex's depth, so the
// estimate is continuous there; turning the box by 1e-9 rad moves those rays off the vertices
// and changes each texel's value by about 1e-9 relative. A tie rule that lets no face, or two,
// claim a vertex ray is off by a whole texel: at m = 9 at least 4/(3 m^2) / 8 = 2e-3 of the box.
// 1e-6 of the box volume is far above the continuity change and far below one texel.
TEST(CpuEstimator, RaysThroughVerticesAreClaimedOnce) {
  const Mesh m = analytic::octahedron().mesh;
  const CpuObvEstimator est(m);
  Obb b;
  b.center = Vec3::Zero();
  b.half = Vec3(2, 2, 2);
  Obb turned = b;
  const double a = 1e-9;
  turned.axes = orthonormalize(
      {Vec3(std::cos(a), std::sin(a), 0), Vec3(-std::sin(a), std::cos(a), 0), Vec3::Zero()});
  for (int res : {1, 3, 9})
    EXPECT_NEAR(est.estimate(b, res), est.estimate(turned, res), 1e-6 * volume(b)) << res;
}

// A bipyramid over a 48-gon whose apexes lie exactly on one texel ray, their rim vertices
// generic (not dyadic): every edge cross at an apex is rounded, and the planes of the rounded
// crosses no longer all contain the ray. Decided on the rounded crosses, each apex's ray was
// claimed by about a quarter of its 48 faces, or by none (texel_plan.h, LocalTriangle). An
// exact ray cast claims one face at each apex: the entry at depth 1/4, value -(1 - 1/64), and
// the exit at 3/4, value 1 - 27/64. Counting the claims is exact. The sum of the values is off
// by the plan's rounded planes, up to 3e-6 per hit (texel_plan.cpp, plan()), and by their
// evaluation, which cpu_rounding_bound bounds for all of the plan's hits (in texel units).
TEST(CpuEstimator, RaysThroughAVertexOfManyFacesAreClaimedOnce) {
  const int res = 8, face = 0, ti = 5, tj = 2;  // texel direction (1, 0.375, -0.375), exact
  const Vec3 d = cubemap_direction(face, texel_center(ti, res), texel_center(tj, res));
  for (unsigned seed = 0; seed < 20; ++seed) {
    const Mesh mesh = test::bipyramid_on_ray(d, 48, seed);
    Obb box;
    box.center = Vec3::Zero();
    box.half = Vec3(1, 1, 1);  // local coordinates are the world's, exactly
    const BoxPlan plan = BoxPlanner(mesh).plan(box, res);
    ASSERT_EQ(plan.where, Location::kOutside);
    const Texel x{face, ti, tj, res, d};
    int entries = 0, exits = 0;
    double sum = 0;
    for (const LocalTriangle& t : plan.tris) {
      double value;
      if (!texel_hit(t, x, false, &value)) continue;
      (value < 0 ? entries : exits) += 1;
      sum += value;
    }
    EXPECT_EQ(entries, 1) << "seed " << seed;
    EXPECT_EQ(exits, 1) << "seed " << seed;
    const double tol = 2 * 3e-6 + cpu_rounding_bound(plan, res) /
                                      (plan.frame.volume_scale * 4.0 / (3.0 * res * res));
    EXPECT_NEAR(sum, -(1 - 1.0 / 64) + (1 - 27.0 / 64), tol) << "seed " << seed;
  }
}

}  // namespace
}  // namespace vobb
