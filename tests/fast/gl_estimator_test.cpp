#include "fast/gl_estimator.h"

#include <gtest/gtest.h>
#include <tbb/info.h>
#include <tbb/task_arena.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdlib>
#include <random>
#include <string>
#include <thread>

#include "arena_threads.h"
#include "common/io/mesh_report.h"
#include "data/analytic_meshes.h"
#include "fast/cpu_estimator.h"
#include "fast/cubemap_bound.h"
#include "fast/estimator_test_util.h"
#include "fast/gl_test_util.h"
#include "test_common.h"

namespace vobb {
namespace {

Obb aabox(const Vec3& c, const Vec3& h) {
  Obb b;
  b.center = c;
  b.half = h;
  return b;
}

// Seeded boxes over a mesh: centres uniform in its bounds grown by 10 %, random orientation,
// half extents log-uniform from 1 % to 40 % of the bounds' diagonal per axis (leaf to root).
std::vector<Obb> random_boxes(const Mesh& mesh, int n, uint64_t seed) {
  Aabb bounds;
  for (const Vec3& v : mesh.vertices) bounds.extend(v);
  const Vec3 size = bounds.hi - bounds.lo;
  const double diag = size.norm();
  std::mt19937_64 rng(seed);
  auto uniform = [&] { return static_cast<double>(rng() >> 11) * 0x1.0p-53; };
  std::vector<Obb> out;
  for (int i = 0; i < n; ++i) {
    Obb b;
    for (int k = 0; k < 3; ++k)
      b.center[k] = bounds.lo[k] - 0.1 * size[k] + 1.2 * size[k] * uniform();
    b.axes =
        orthonormalize({Vec3(uniform() - 0.5, uniform() - 0.5, uniform() - 0.5),
                        Vec3(uniform() - 0.5, uniform() - 0.5, uniform() - 0.5), Vec3::Zero()});
    for (int k = 0; k < 3; ++k) b.half[k] = diag * 0.01 * std::pow(40.0, uniform());
    out.push_back(b);
  }
  return out;
}

// `boxes` with three odd ones put in at a quarter, a half and three quarters of the n + 3
// (the flat box at 50, the far one at 100 and the one beyond float at 150 for n = 197): a flat
// box (OBV 0, no plan drawn), a box far from the mesh (no record), and a box float cannot
// evaluate (the CPU twin's code).
std::vector<Obb> with_odd_boxes(std::vector<Obb> boxes) {
  const size_t q = (boxes.size() + 3) / 4;
  boxes.insert(boxes.begin() + q, aabox(Vec3::Zero(), Vec3(1, 1, 0)));
  boxes.insert(boxes.begin() + 2 * q, aabox(Vec3(1e3, 0, 0), Vec3(1, 1, 1)));
  boxes.insert(boxes.begin() + 3 * q, aabox(Vec3::Zero(), Vec3(1e38, 1e38, 1e38)));
  return boxes;
}

// GL against the CPU twin: every box within gl_deviation_bound (gl_estimator.cpp derives it
// from the shaders' float32 arithmetic). Returns the median of bound / |value| so callers can
// check that the bound is informative, not vacuous.
double expect_gl_matches_cpu(const Mesh& mesh, GlObvEstimator& gl, const std::vector<Obb>& boxes,
                             int m) {
  const CpuObvEstimator cpu(mesh);
  const size_t fallbacks = gl.cpu_fallbacks();
  const std::vector<double> g = gl.estimate(boxes, m), c = cpu.estimate(boxes, m);
  EXPECT_EQ(gl.cpu_fallbacks(), fallbacks) << "ordinary boxes are evaluated by GL, not in double";
  std::vector<double> relative_bounds;
  for (size_t i = 0; i < boxes.size(); ++i) {
    const BoxPlan plan = gl.planner().plan(boxes[i], m);
    const double bound = gl_deviation_bound(plan, m);
    EXPECT_TRUE(std::isfinite(g[i])) << i;
    EXPECT_LE(std::abs(g[i] - c[i]), bound) << "box " << i << " m " << m;
    // The exact evaluation of a plan is >= 0 (each texel's outer fraction is in [0, 1]), the
    // CPU twin is within cpu_rounding_bound of it, and GL within `bound` of the CPU twin.
    EXPECT_GE(g[i], -bound - cpu_rounding_bound(plan, m)) << i;
    relative_bounds.push_back(bound / std::max(std::abs(c[i]), 1e-300));
  }
  std::nth_element(relative_bounds.begin(), relative_bounds.begin() + relative_bounds.size() / 2,
                   relative_bounds.end());
  return relative_bounds[relative_bounds.size() / 2];
}

// 200 seeded boxes over two real meshes, at a power-of-two m (texel directions exact in float)
// and at m = 23 (rounded directions). The median bound must stay near float round-off
// (1e-5 relative is some 100 float ulps): a vacuous bound would make the comparison toothless.
TEST(GlEstimator, MatchesCpuTwinOnRealMeshesWithinDerivedFloatBound) {
  int seed = 1;
  for (const char* name : {"dino", "knot1"}) {
    VOBB_REQUIRE_REAL_MESH(name);
    LoadedMesh lm;
    ASSERT_TRUE(load_solid(test::real_mesh(name), &lm));
    VOBB_MAKE_GL(gl, lm.mesh);
    const std::vector<Obb> boxes = random_boxes(lm.mesh, 100, seed++);
    for (int m : {16, 23})
      EXPECT_LT(expect_gl_matches_cpu(lm.mesh, *gl, boxes, m), 1e-5) << name << " m " << m;
  }
}

TEST(GlEstimator, MatchesCpuTwinOnAnalyticMeshes) {
  for (const auto& a :
       {analytic::polygonal_torus(), analytic::cube_with_cavity(), analytic::octahedron()}) {
    VOBB_MAKE_GL(gl, a.mesh);
    const std::vector<Obb> boxes = random_boxes(a.mesh, 40, 7);
    for (int m : {1, 8, 32})
      EXPECT_LT(expect_gl_matches_cpu(a.mesh, *gl, boxes, m), 1e-5) << a.name << " m " << m;
  }
}

// Large m: a box's texels are summed in several slices (cubemap_bound.h), each lane looping far
// fewer times than llvmpipe allows a shader loop (65,535 trips, after which it ends the loop
// without an error: at m = 2048 one sum would take 98,304 trips a lane, and the values came out
// thousands of times too small). m = 210 is the first m of two slices. The bound's summation
// term grows with a lane's run, K = ceil(min(6 m^2, 2^18) / 256) + 9 additions (docs/
// derivations.md, "The GL deviation bound"): the median bound stays below 10 K u (the callers'
// 1e-5 at m <= 32 is about that too), far below the values it must tell apart from wrong ones.
TEST(GlEstimator, MatchesCpuTwinAtLargeMWhereTheSumTakesSlices) {
  EXPECT_EQ(reduce_slices(209), 1);
  EXPECT_EQ(reduce_slices(210), 2);
  EXPECT_EQ(reduce_slices(2048), 96);
  const analytic::AnalyticMesh a = analytic::polygonal_torus();
  VOBB_MAKE_GL(gl, a.mesh);
  const std::vector<Obb> boxes = random_boxes(a.mesh, 3, 11);
  for (int m : {210, 2048}) {
    const double K = std::ceil(std::min(6.0 * m * m, 262144.0) / 256) + 9;
    EXPECT_LT(expect_gl_matches_cpu(a.mesh, *gl, boxes, m), 10 * K * 0x1p-24) << "m " << m;
  }
}

// Boxes beyond what float can evaluate (gl_estimator.h): the cube's faces pass the centre of a
// box of half extent 2^127 at some 2^-128 box units, below FLT_MIN, where the shader's zeta
// would be 0 (GL used to answer 0 for an OBV of 8e114). A box of aspect 1e120 (1e60 wide, 1e-60
// thin) does the same along its wide axes. Each must be evaluated in double, giving the
// CPU twin's value exactly, while a box of ordinary size in the same call goes to GL.
TEST(GlEstimator, BoxesFloatCannotEvaluateGiveTheCpuTwinsValue) {
  const Mesh mesh = analytic::cube().mesh;
  VOBB_MAKE_GL(gl, mesh);
  const CpuObvEstimator cpu(mesh);
  Obb thin = aabox(Vec3(0.25, 0.5, 0.5), Vec3(1e60, 1e60, 1e-60));
  thin.axes = orthonormalize({Vec3(1, 0.5, 0.25), Vec3(-0.5, 1, 0.125), Vec3::Zero()});
  const std::vector<Obb> huge = {aabox(Vec3(0.5, 0.5, 0.5), Vec3(0x1p127, 0x1p127, 0x1p127)),
                                 aabox(Vec3(0.5, 0.5, 0.5), Vec3(1e39, 2e39, 3e39)), thin};
  for (int res : {1, 8, 23}) {
    for (size_t i = 0; i < huge.size(); ++i)
      ASSERT_FALSE(gl_evaluates_in_float(gl->planner().plan(huge[i], res))) << "box " << i;
    std::vector<Obb> boxes = huge;
    boxes.push_back(aabox(Vec3(0.5, 0.5, 0.5), Vec3(2, 2, 2)));  // an ordinary box, for GL
    const size_t before = gl->cpu_fallbacks();
    const std::vector<double> g = gl->estimate(boxes, res), c = cpu.estimate(boxes, res);
    EXPECT_EQ(gl->cpu_fallbacks() - before, huge.size()) << res;
    for (size_t i = 0; i < huge.size(); ++i) {
      EXPECT_EQ(g[i], c[i]) << "box " << i << " m " << res;
      EXPECT_EQ(gl_deviation_bound(gl->planner().plan(boxes[i], res), res), 0.0);
    }
    // The box of half extent 2^127 is centred on the unit cube's centre and aligned with it, its
    // plan exact (power-of-two half extents, a dyadic centre): the estimate is exact at any m
    // (CpuEstimator.CubeCentredInAnAlignedBoxIsExact) but for the twin's rounding. OBV = 2^384
    // - 1, whose nearest double is the box's volume: within that bound of it, and 1.
    const BoxPlan plan0 = gl->planner().plan(huge[0], res);
    EXPECT_NEAR(g[0], volume(huge[0]), cpu_rounding_bound(plan0, res) + 1) << res;
    const BoxPlan plan3 = gl->planner().plan(boxes[3], res);
    EXPECT_NEAR(g[3], 63.0, gl_deviation_bound(plan3, res) + cpu_rounding_bound(plan3, res)) << res;
  }
}

TEST(GlEstimator, DisjointBoxIsItsVolumeWithoutGpuWork) {
  const Mesh m = analytic::cube().mesh;
  VOBB_MAKE_GL(gl, m);
  const Obb b = aabox(Vec3(5, 5, 5), Vec3(1, 2, 0.5));
  const size_t trips = gl->round_trips();
  // The plan of this dyadic aligned box is exact, so |GL - volume| <= |GL - CPU| + |CPU - exact|.
  for (int res : {1, 7, 32}) {
    const BoxPlan plan = gl->planner().plan(b, res);
    EXPECT_NEAR(gl->estimate(b, res), volume(b),
                gl_deviation_bound(plan, res) + cpu_rounding_bound(plan, res));
  }
  EXPECT_EQ(gl->round_trips(), trips);  // nothing drawn, nothing read back
}

// A box holding the whole mesh: vol(box) - vol(mesh), to the estimator's resolution
// (resolution_bound: the texels the surface crosses, each off by at most its pyramid). Centred
// on the aligned cube the estimate is exact, up to float round-off (gl_deviation_bound).
TEST(GlEstimator, WholeMeshBoxIsBoxVolumeMinusMeshVolume) {
  const auto cube = analytic::cube();
  VOBB_MAKE_GL(gl, cube.mesh);
  // Half extents 2 keep the plan exact (cpu_estimator_test.cpp), so exact(plan) = 64 - 1.
  const Obb centred = aabox(Vec3(0.5, 0.5, 0.5), Vec3(2, 2, 2));
  for (int res : {1, 3, 16, 64}) {
    const BoxPlan plan = gl->planner().plan(centred, res);
    EXPECT_NEAR(gl->estimate(centred, res), 63.0,
                gl_deviation_bound(plan, res) + cpu_rounding_bound(plan, res))
        << res;
  }
  for (const auto& a : {analytic::polygonal_torus(), analytic::cube_with_cavity()}) {
    VOBB_MAKE_GL(est, a.mesh);
    Aabb bounds;
    for (const Vec3& v : a.mesh.vertices) bounds.extend(v);
    Obb b;
    b.axes = orthonormalize({Vec3(1, 0.2, 0.1), Vec3(-0.1, 1, 0.3), Vec3::Zero()});
    b.center = bounds.hi + 0.25 * (bounds.hi - bounds.lo);  // outside the mesh's bounding box
    // Every vertex is within 1.25 diagonals of the centre (beyond the far corner by a quarter
    // of the diagonal's components), so half extents of 1.5 diagonals hold the mesh in any
    // orientation of the box.
    b.half = Vec3::Constant(1.5 * (bounds.hi - bounds.lo).norm());
    const Rational exact = exact_volume(b) - a.volume;  // the box holds the whole solid
    for (int res : {8, 32}) {
      const BoxPlan plan = est->planner().plan(b, res);
      const double v = est->estimate(b, res);
      // Not vacuous. The centre lies beyond the mesh's bounding box in all three coordinates,
      // so every mesh point is seen in one open octant of directions (solid angle pi / 2). The
      // cube box (half extent h) holds r(u)^3 / 3 <= (sqrt(3) h)^3 / 3 per steradian in any
      // direction, so at most sqrt(3) (pi / 2) h^3 = 0.34 of its 8 h^3 lies in that octant;
      // the texels straddling the octant's rim add the rest, measured 0.03-0.11 of the box in
      // all at m = 8 and 32, well under half. (Centred in cube_with_cavity's cavity, as this
      // test first was, every texel sees the surface and the bound is the whole box.)
      EXPECT_LT(resolution_bound(plan, res), volume(b) / 2) << a.name << " m " << res;
      // The GL estimate's rigorous bound (cubemap_bound.h), decided in rationals.
      const double bound = cubemap_bounds(est->planner(), b, res).rigorous();
      EXPECT_LE(abs(Rational(v) - exact), Rational(bound)) << a.name << " m " << res;
    }
  }
}

// A centre on a face, an edge or a vertex: finite (far-count mode) and consistent with the same
// box nudged off the surface both ways (which classifies the centre normally).
TEST(GlEstimator, FiniteAndConsistentForCentresOnFacesEdgesAndVertices) {
  const Mesh m = analytic::cube().mesh;
  VOBB_MAKE_GL(gl, m);
  const Vec3 h(0.3, 0.2, 0.25);
  for (const Vec3& c : {Vec3(0, 0, 0), Vec3(0.5, 0, 0), Vec3(0.5, 0.5, 0), Vec3(1, 1, 0.5)}) {
    const Obb b = aabox(c, h);
    const double v = gl->estimate(b, 32);
    ASSERT_TRUE(std::isfinite(v));
    EXPECT_TRUE(gl->planner().plan(b, 32).far_count) << c.transpose();
    const double area = 8 * (h[0] * h[1] + h[1] * h[2] + h[2] * h[0]);
    for (double eps : {1e-9, -1e-9}) {
      const Obb nudged = aabox(c + Vec3::Constant(eps), h);
      const double w = gl->estimate(nudged, 32);
      // The exact OBV moves by at most area * |eps| sqrt(3) (cpu_estimator_test.cpp); each GL
      // value is within gl_deviation_bound of its CPU twin, which is within cpu_rounding_bound
      // of its plan's exact evaluation, which is off the true value by the plan's rounding.
      const BoxPlan pb = gl->planner().plan(b, 32), pn = gl->planner().plan(nudged, 32);
      const double slack = gl_deviation_bound(pb, 32) + gl_deviation_bound(pn, 32) +
                           cpu_rounding_bound(pb, 32) + cpu_rounding_bound(pn, 32) +
                           test::aligned_plan_round_off(m, 6, b) +
                           test::aligned_plan_round_off(m, 6, nudged);
      EXPECT_NEAR(v, w, area * std::sqrt(3.0) * std::abs(eps) + slack) << c.transpose();
    }
  }
}

// Batches of any size give the same floats as one box per round trip: the blend order within a
// texel and the reduction order do not depend on the batch. At m = 256 an atlas holds 40 tiles,
// so 200 boxes take several trips and the multi-trip path runs too.
TEST(GlEstimator, BatchingChangesNothingButTheRoundTrips) {
  const Mesh m = analytic::polygonal_torus().mesh;
  VOBB_MAKE_GL(gl, m);
  const std::vector<Obb> boxes = random_boxes(m, 200, 11);
  for (int res : {8, 256}) {
    size_t trips = gl->round_trips();
    const std::vector<double> batched = gl->estimate(boxes, res);
    const size_t batched_trips = gl->round_trips() - trips;
    gl->set_batching(false);
    trips = gl->round_trips();
    const std::vector<double> single = gl->estimate(boxes, res);
    const size_t single_trips = gl->round_trips() - trips;
    gl->set_batching(true);
    EXPECT_EQ(batched, single) << res;
    EXPECT_LT(batched_trips, single_trips);
    if (res == 256) {
      EXPECT_GT(batched_trips, 1u);
    }
  }
}

// The boxes are planned on several threads, a window at a time, and packed in box order
// (gl_estimator.cpp): arenas of 1, 3 and 8 threads (windows of 2, 6 and 16 boxes, cutting the
// batch at different places, whatever the machine's cores) and the default give the same floats
// as each box estimated alone, and the same CPU fallbacks. The batch mixes ordinary boxes with
// a flat box (OBV 0, no plan drawn), a box far from the mesh (no record), and a box float cannot
// evaluate (the CPU twin's code). At m = 192 (70 tiles an atlas) the batch spans several round
// trips.
TEST(GlEstimator, ThreadsChangeNothing) {
  const Mesh m = analytic::polygonal_torus().mesh;
  VOBB_MAKE_GL(gl, m);
  const std::vector<Obb> boxes =
      with_odd_boxes(random_boxes(m, 197, 13));  // odd ones at 50, 100, 150
  for (int res : {8, 192}) {
    ASSERT_FALSE(gl_evaluates_in_float(gl->planner().plan(boxes[150], res)));
    std::vector<double> alone;
    size_t before = gl->cpu_fallbacks();
    for (const Obb& b : boxes) alone.push_back(gl->estimate(b, res));
    const size_t alone_fallbacks = gl->cpu_fallbacks() - before;
    EXPECT_EQ(alone_fallbacks, 1u) << res;
    EXPECT_EQ(alone[50], 0.0);
    for (int threads : {1, 3, 8}) {
      auto check = [&] {
        const size_t start = gl->cpu_fallbacks();
        EXPECT_EQ(gl->estimate(boxes, res), alone) << "m " << res << ", " << threads << " threads";
        EXPECT_EQ(gl->cpu_fallbacks() - start, alone_fallbacks) << res;
      };
      // Short batches: runs are repeated until a worker joins one.
      test::expect_on_threads(threads, check, "the batch's planning");
    }
    const size_t trips = gl->round_trips();
    EXPECT_EQ(gl->estimate(boxes, res), alone) << "m " << res << ", the default arena";
    if (res == 192) {
      EXPECT_GT(gl->round_trips() - trips, 1u);
    }
  }
}

// Whether the estimator draws a box with this plan (gl_estimator.cpp, plan_box): not flat,
// evaluable in float, and with a span that covers a texel centre.
bool gl_draws(const BoxPlan& plan) {
  if (plan.flat || !gl_evaluates_in_float(plan)) return false;
  for (const TexelSpan& s : plan.spans)
    if (s.i0 <= s.i1 && s.j0 <= s.j1) return true;
  return false;
}

// Calls from several threads at once (the builder's parallel node search) are drawn together
// by the estimator's drawing thread (gl_estimator.cpp): each box still gets the value it gets
// alone, whatever tile it takes and whatever shares its batch, and calls at another m wait for
// a round of their own. The drawing thread is held until six calls are queued, three at m = 8
// and three at m = 192 (an atlas of 70 tiles), each of 45 to 64 boxes (the mixed boxes of
// ThreadsChangeNothing), then released: it must draw them in exactly two rounds, one per m,
// and at m = 192 the three calls' drawn boxes fill the atlas, so that a call's boxes span two
// batches. Three such rounds, each with other slices.
TEST(GlEstimator, CallsFromSeveralThreadsAtOnceGiveEachBoxItsOwnValue) {
  const Mesh m = analytic::polygonal_torus().mesh;
  VOBB_MAKE_GL(gl, m);
  const std::vector<Obb> boxes = with_odd_boxes(random_boxes(m, 117, 17));
  const int resolutions[2] = {8, 192};
  std::vector<double> alone[2];
  for (int r = 0; r < 2; ++r)
    for (const Obb& b : boxes) alone[r].push_back(gl->estimate(b, resolutions[r]));
  constexpr int kThreads = 6;
  for (int round = 0; round < 3; ++round) {
    const size_t shared_before = gl->shared_round_trips(), trips_before = gl->round_trips();
    gl->hold_draws(true);
    std::vector<std::string> wrong(kThreads);
    std::vector<size_t> drawn(kThreads, 0);
    std::vector<std::thread> threads;
    for (int t = 0; t < kThreads; ++t)
      threads.emplace_back([&, t] {
        const int r = t % 2;
        // Thread t takes boxes [first, first + count), other slices each round.
        const size_t count = 45 + (7 * t + 5 * round) % 20;
        const size_t first = (31 * t + 17 * round) % (boxes.size() - count + 1);
        const std::vector<Obb> slice(boxes.begin() + first, boxes.begin() + first + count);
        const std::vector<double> got = gl->estimate(slice, resolutions[r]);
        for (size_t i = 0; i < count && wrong[t].empty(); ++i)
          if (got[i] != alone[r][first + i])
            wrong[t] =
                "box " + std::to_string(first + i) + " at m " + std::to_string(resolutions[r]);
        for (size_t i = 0; i < count; ++i)
          drawn[t] += gl_draws(gl->planner().plan(slice[i], resolutions[r])) ? 1 : 0;
      });
    // Each call is one request (at most 64 boxes, under either atlas's capacity).
    const auto t0 = std::chrono::steady_clock::now();
    while (gl->queued_calls() < kThreads &&
           std::chrono::steady_clock::now() - t0 < std::chrono::seconds(120))
      std::this_thread::sleep_for(std::chrono::milliseconds(1));
    EXPECT_EQ(gl->queued_calls(), static_cast<size_t>(kThreads)) << "round " << round;
    gl->hold_draws(false);
    for (std::thread& th : threads) th.join();
    for (int t = 0; t < kThreads; ++t)
      EXPECT_EQ(wrong[t], "") << "thread " << t << ", round " << round;
    EXPECT_EQ(gl->shared_round_trips() - shared_before, 2u) << "round " << round;
    const size_t drawn_192 = drawn[1] + drawn[3] + drawn[5];
    ASSERT_GT(drawn_192, 70u) << "the m = 192 calls do not fill an atlas, round " << round;
    // m = 8: one batch (capacity 4096); m = 192: ceil(drawn / 70) batches.
    EXPECT_EQ(gl->round_trips() - trips_before, 1 + (drawn_192 + 69) / 70) << "round " << round;
  }
  // The drawing thread released the context after its last round: this thread can take it.
  { GlContext::Current bound(gl->context()); }
  EXPECT_EQ(gl->estimate(boxes[0], 8), alone[0][0]);
}

// As RaysThroughVerticesAreClaimedOnce (cpu_estimator_test.cpp), on the GL side: the shader's
// simulation-of-simplicity tie rule claims a vertex ray once. Both GL values also carry float
// deviations (gl_deviation_bound) on top of the 1e-6 continuity allowance derived there.
TEST(GlEstimator, RaysThroughVerticesAreClaimedOnce) {
  const Mesh m = analytic::octahedron().mesh;
  VOBB_MAKE_GL(gl, m);
  const Obb b = aabox(Vec3::Zero(), Vec3(2, 2, 2));
  Obb turned = b;
  const double a = 1e-9;
  turned.axes = orthonormalize(
      {Vec3(std::cos(a), std::sin(a), 0), Vec3(-std::sin(a), std::cos(a), 0), Vec3::Zero()});
  for (int res : {1, 3, 9}) {
    const double slack = gl_deviation_bound(gl->planner().plan(b, res), res) +
                         gl_deviation_bound(gl->planner().plan(turned, res), res);
    EXPECT_NEAR(gl->estimate(b, res), gl->estimate(turned, res), 1e-6 * volume(b) + slack) << res;
  }
}

TEST(GlEstimator, CullingChangesNothingButTheWork) {
  const Mesh m = analytic::polygonal_torus().mesh;
  VOBB_MAKE_GL(gl, m);
  const std::vector<Obb> boxes = random_boxes(m, 30, 5);
  const std::vector<double> culled = gl->estimate(boxes, 16);
  gl->set_culling(false);
  const std::vector<double> all = gl->estimate(boxes, 16);
  gl->set_culling(true);
  for (size_t i = 0; i < boxes.size(); ++i) {
    // Without culling the faces beyond the box are drawn too, and discarded per texel; the kept
    // hits are the same, blended in the same order (plans list faces in mesh order either way):
    // the same floats.
    EXPECT_EQ(culled[i], all[i]) << i;
  }
}

}  // namespace
}  // namespace vobb
