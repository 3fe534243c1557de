#include "fast/texel_plan.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <cfenv>
#if defined(__SSE2__)
#include <xmmintrin.h>
#endif
#include <cmath>
#include <map>
#include <random>
#include <tuple>
#include <vector>

#include "common/obb.h"
#include "fast/estimator_test_util.h"

namespace vobb {
namespace {

// Thin boxes tilted by 0.3 rad against a face of a rotated cube, their centres half their
// thin extent from its plane, at aspects 1e-3, 1e-4 and 1e-6. In box units the face passes
// at about 0.5 aspect / sin(0.3) from the centre (1.6e-6 at aspect 1e-6), and the faces'
// vertices lie up to 1 / aspect out along the thin axis. The plane the plan holds is off by u
// times the terms that make it up (texel_plan.cpp), which here stays below 1e-9 of the face's
// distance, far below the 2^-20 that would make the face "near the centre" and double the
// resolution bound. A bound of that rounding by vector norms counted the stretched axis twice
// and flagged these faces at aspects 1e-4 and 1e-6. (At 1e-8 the face passes 1.6e-8 box units
// from the centre and the componentwise bound is 1.6e-6 of that: such a box is flagged, and
// its bound doubled, rightly within the 2^-20 rule.)
TEST(TexelPlan, ThinBoxesDoNotTakeFarFacesAsNearTheCentre) {
  const Vec3 &a0 = test::kTurnedA0, &a1 = test::kTurnedA1, &a2 = test::kTurnedA2;
  const Mesh cube = test::turned_cube();
  const BoxPlanner planner(cube);
  // The face x = 1 of the cube's frame has outward normal a2. The boxes' thin axis is a2
  // turned by 0.3 rad towards a0.
  const double tilt = 0.3;
  const Vec3 thin = std::cos(tilt) * a2 + std::sin(tilt) * a0;
  const Vec3 across = -std::sin(tilt) * a2 + std::cos(tilt) * a0;
  for (double aspect : {1e-3, 1e-4, 1e-6}) {
    for (const Vec3& spot : {Vec3(0.1, 0.2, 0.0), Vec3(-0.3, 0.05, 0.1), Vec3(0.25, -0.4, -0.2)}) {
      Obb box;
      box.axes = orthonormalize({across, a1, thin});
      box.half = Vec3(0.3, 0.3, 0.3 * aspect);
      // On the face at (spot.x, spot.y) in its (a0, a1) coordinates, then moved inside along
      // the thin axis by half its extent.
      box.center = a2 + spot.x() * a0 + spot.y() * a1 - 0.5 * box.half.z() * box.axes[2];
      for (int m : {4, 32}) {
        const BoxPlan plan = planner.plan(box, m);
        ASSERT_FALSE(plan.tris.empty()) << "aspect " << aspect;  // the face crosses the box
        EXPECT_FALSE(plan.centre_near_surface) << "aspect " << aspect << " m " << m;
        for (const LocalTriangle& t : plan.tris) EXPECT_FALSE(t.near_centre) << "aspect " << aspect;
      }
    }
  }
}

// A box centred on a mesh vertex, on the midpoint of a face's diagonal, or on an edge's midpoint
// has edges whose line passes through the centre (E* = 0 exactly). plan() marks exactly those,
// as a rational evaluation of E* says, and an edge test on a marked edge gives 0 for every
// texel, as the full rational test does.
TEST(TexelPlan, EdgesThroughTheCentreAreMarkedExactly) {
  Mesh cube;
  for (int i = 0; i < 8; ++i) cube.vertices.emplace_back(i & 1, (i >> 1) & 1, (i >> 2) & 1);
  test::add_cube_faces(&cube);
  const BoxPlanner planner(cube);
  int marked = 0, unmarked = 0;
  for (const Vec3& c : {Vec3(0, 0, 0), Vec3(0.5, 0.5, 0), Vec3(0.5, 0, 0), Vec3(0.3, 0.2, 0.1)}) {
    Obb box;
    box.center = c;
    box.axes = {Vec3::UnitX(), Vec3::UnitY(), Vec3::UnitZ()};
    box.half = Vec3(0.3, 0.2, 0.3);
    const int m = 8;
    const BoxPlan plan = planner.plan(box, m);
    for (const LocalTriangle& t : plan.tris)
      for (int k = 0; k < 3; ++k) {
        const Vec3 &p = t.p[k], &q = t.p[(k + 1) % 3];
        bool zero = true;
        for (int a = 0; a < 3; ++a) {
          const int a1 = (a + 1) % 3, a2 = (a + 2) % 3;
          zero = zero && Rational(p[a1]) * Rational(q[a2]) == Rational(p[a2]) * Rational(q[a1]);
        }
        EXPECT_EQ(t.edge_zero[k], zero) << "centre " << c.transpose() << " edge " << k;
        (zero ? marked : unmarked) += 1;
        if (!zero) continue;
        for (int f = 0; f < 6; ++f)
          for (int i = 0; i < m; ++i)
            for (int j = 0; j < m; ++j) {
              const Texel x{f, i, j, m,
                            cubemap_direction(f, texel_center(i, m), texel_center(j, m))};
              EXPECT_EQ(exact_edge_side(t, k, x), 0);
            }
      }
  }
  // Around the vertex, the diagonal's midpoint and the edge's midpoint, some edges pass
  // through the centre; most do not.
  EXPECT_GE(marked, 6);
  EXPECT_GT(unmarked, marked);
}

// exact_edge_side decides by floating-point expansions where every product of two
// coordinates is 0 or in [2^-800, 2^1000], and gives the sign that rationals give. Edges:
// random coordinates; exactly collinear pairs (q = 2 p: E* = 0, side 0); pairs one ulp off
// collinear (E* tiny against the products, the case the double test leaves to this one);
// pairs in a coordinate plane (E* along an axis: a texel whose weight there is 0 has a dot of
// 0, and the perturbation decides); pairs whose E* is orthogonal to one of the texel rays
// without cancelling (a dot of 0 that the double dot makes noise of), and one ulp off that;
// products from 2^998 down to 2^-800 in one dot; a component 0. Texels
// on every face at m from 1 to 4096, with the centre rows, where a weight is 0. Products just
// out of range (2^-801, 2^1001, an underflow to 0) and a rounding mode other than to nearest
// are refused, and rationals decide.
TEST(TexelPlan, ExactEdgeSidesByExpansionAreTheRationalOnes) {
  std::mt19937_64 rng(11);
  auto uniform = [&] { return static_cast<double>(rng() >> 11) * 0x1.0p-53 * 2 - 1; };
  auto random_vec = [&](double scale) -> Vec3 {
    return Vec3(uniform(), uniform(), uniform()) * scale;
  };
  struct Edge {
    Vec3 p, q;
    bool in_range;
  };
  std::vector<Edge> edges;
  for (int n = 0; n < 200; ++n) {
    const Vec3 p = random_vec(1), q = random_vec(1);
    edges.push_back({p, q, true});
    const Vec3 twice = p * 2;  // exactly collinear
    edges.push_back({p, twice, true});
    Vec3 off = twice;
    off[n % 3] = std::nextafter(off[n % 3], 10.0);  // one ulp from collinear
    edges.push_back({p, off, true});
    Vec3 zero = q;
    zero[n % 3] = 0;
    edges.push_back({p, zero, true});
    // Products from about 2^998 down to 2^-800 in one dot: magnitudes in [1/2, 1) scaled so
    // that p0 q1 is near 2^998 and p2 q0 near 2^-798.
    auto magnitude = [&] { return (0.5 + 0.25 * (uniform() + 1)) * (rng() & 1 ? 1 : -1); };
    edges.push_back({Vec3(0x1p499 * magnitude(), magnitude(), 0x1p-399 * magnitude()),
                     Vec3(0x1p-399 * magnitude(), 0x1p499 * magnitude(), magnitude()), true});
    Vec3 pz = p, qz = q;  // E* along an axis: a texel whose weight there is 0 has dot 0
    pz[n % 3] = qz[n % 3] = 0;
    edges.push_back({pz, qz, true});
    // q along one of the loop's texel rays, m d* scaled by 2^-12: E* is orthogonal to that
    // ray, so its dot is exactly 0 while the products do not cancel (the double dot is
    // rounding noise, which the filter's bound must not take for a sign); and q one ulp off
    // it, a dot far below that noise.
    const int m = n % 2 == 0 ? 32 : 4096, f = n % 6, fk = f / 2;
    const int i = std::array<int, 3>{0, m / 2, m - 1}[n % 3];
    const int j = std::array<int, 3>{0, (m - 1) / 2, m - 1}[(n / 3) % 3];
    Vec3 ray;
    ray[fk] = f % 2 == 0 ? m : -m;
    ray[(fk + 1) % 3] = 2 * i + 1 - m;
    ray[(fk + 2) % 3] = 2 * j + 1 - m;
    edges.push_back({p, ray * 0x1p-12, true});
    Vec3 nudged = ray * 0x1p-12;
    nudged[(fk + 1 + n % 2) % 3] = std::nextafter(nudged[(fk + 1 + n % 2) % 3], 10.0);
    edges.push_back({p, nudged, true});
  }
  // Just out of range, refused: a product of 2^-801, one of 2^1001, one that underflows to 0.
  edges.push_back({Vec3(0x1p-401, 1, 1), Vec3(1, 0x1p-400, 1), false});
  edges.push_back({Vec3(0x1p501, 1, 1), Vec3(1, 0x1p500, 1), false});
  edges.push_back({Vec3(0x1p-600, 1, 1), Vec3(1, 0x1p-600, 1), false});
  int decided = 0, zero_dots = 0;
  for (const Edge& e : edges)
    for (const bool canonical : {true, false}) {
      LocalTriangle t{};
      t.p[0] = e.p;
      t.p[1] = e.q;
      t.p[2] = Vec3(0.5, 0.25, 0.125);
      t.id[0] = canonical ? 1 : 2;
      t.id[1] = canonical ? 2 : 1;
      t.id[2] = 3;
      for (const int m : {1, 2, 7, 32, 4096})
        for (int f = 0; f < 6; ++f)
          for (const int i : {0, m / 2, m - 1})
            for (const int j : {0, (m - 1) / 2, m - 1}) {
              const Texel x{f, i, j, m,
                            cubemap_direction(f, texel_center(i, m), texel_center(j, m))};
              int side = 7;
              const bool by_expansion = exact_edge_side_by_expansion(t, 0, x, &side);
              EXPECT_EQ(by_expansion, e.in_range) << e.p.transpose() << " / " << e.q.transpose();
              const int rational = exact_edge_side_rational(t, 0, x);
              if (by_expansion) {
                EXPECT_EQ(side, rational) << e.p.transpose() << " / " << e.q.transpose();
                ++decided;
              }
              EXPECT_EQ(exact_edge_side(t, 0, x), rational);
              // Whether the exact dot was 0 with E* not 0 (the perturbation decided): counted
              // from the rationals, so the case is seen to occur.
              const int fk = f / 2, fa = (fk + 1) % 3, fb = (fk + 2) % 3;
              Rational E[3];
              for (int c = 0; c < 3; ++c)
                E[c] = Rational(e.p[(c + 1) % 3]) * Rational(e.q[(c + 2) % 3]) -
                       Rational(e.p[(c + 2) % 3]) * Rational(e.q[(c + 1) % 3]);
              const Rational dot =
                  (f % 2 == 0 ? m : -m) * E[fk] + (2 * i + 1 - m) * E[fa] + (2 * j + 1 - m) * E[fb];
              zero_dots += sgn(dot) == 0 && (sgn(E[0]) != 0 || sgn(E[1]) != 0 || sgn(E[2]) != 0);
            }
    }
  EXPECT_GT(decided, 100000);
  EXPECT_GT(zero_dots, 1000);
  // In another rounding mode two_sum is not exact: refused, and rationals decide.
  LocalTriangle t{};
  t.p[0] = Vec3(0.3, -0.7, 0.2);
  t.p[1] = Vec3(0.6, -1.4, 0.4000000000000001);
  t.p[2] = Vec3(0.5, 0.25, 0.125);
  t.id[0] = 1;
  t.id[1] = 2;
  t.id[2] = 3;
  const Texel x{0, 3, 4, 8, cubemap_direction(0, texel_center(3, 8), texel_center(4, 8))};
  int side = 0;
  ASSERT_TRUE(exact_edge_side_by_expansion(t, 0, x, &side));
  ASSERT_EQ(std::fesetround(FE_UPWARD), 0);
  int upward = 7;
  const bool by_expansion = exact_edge_side_by_expansion(t, 0, x, &upward);
  const int decided_upward = exact_edge_side(t, 0, x);
  std::fesetround(FE_TONEAREST);
  EXPECT_FALSE(by_expansion);
  EXPECT_EQ(decided_upward, side);
  EXPECT_EQ(side, exact_edge_side_rational(t, 0, x));
#if defined(__SSE2__)
  // The SSE rounding mode set alone, as CGAL's Protect_FPU_rounding sets it (fegetround reads
  // the x87 word, and still says to nearest): refused too. Rounded upward, the expansion would
  // give this edge the side opposite to the rationals' (a case an audit found by search).
  LocalTriangle u{};
  u.p[0] = Vec3(0x1.574p-1, -0x1.fap-5, -0x1.d740000000001p-2);
  u.p[1] = Vec3(-0x1.556b660c186bfp+11, 0x1.f74d36c82e713p+7, 0x1.d4bca7828755p+10);
  u.p[2] = Vec3(1, 2, 3);
  u.id[0] = 0;
  u.id[1] = 1;
  u.id[2] = 2;
  const Texel y{0, 1246, 430, 2746,
                cubemap_direction(0, texel_center(1246, 2746), texel_center(430, 2746))};
  const int rational = exact_edge_side_rational(u, 0, y);
  const unsigned csr = _mm_getcsr();
  _MM_SET_ROUNDING_MODE(_MM_ROUND_UP);
  int sse_upward = 7;
  const bool sse_by_expansion = exact_edge_side_by_expansion(u, 0, y, &sse_upward);
  const int sse_decided = exact_edge_side(u, 0, y);
  _mm_setcsr(csr);
  EXPECT_FALSE(sse_by_expansion);
  EXPECT_EQ(sse_decided, rational);
#endif
}

// A plan written into a BoxPlan that held other plans equals a fresh one, field by field:
// the CPU twin and the GL estimator plan every box into one reused BoxPlan (for its vectors'
// capacity), so anything a plan left behind would change the next box's value. The boxes
// alternate between large and small plans and the early exits: the whole mesh, a small box at
// a rim vertex, a flat box, a thin box whose faces lie beyond 2^300 box units (unresolved), a
// box across the rim. (Which order-keeping path a box takes is
// CulledPlansKeepTheFacesInMeshOrder's.)
TEST(TexelPlan, APlanReusedAfterOthersEqualsAFreshOne) {
  const Vec3 d(4.0, 1.2, 0.8);
  const Mesh mesh = test::bipyramid_on_ray(d, 2000, 7);
  const BoxPlanner planner(mesh);
  auto aligned = [](const Vec3& c, const Vec3& h) {
    Obb b;
    b.center = c;
    b.axes = {Vec3::UnitX(), Vec3::UnitY(), Vec3::UnitZ()};
    b.half = h;
    return b;
  };
  const Obb whole = aligned(0.5 * d, Vec3::Constant(0.5 * d.norm()));
  const Obb rim = aligned(mesh.vertices[2], Vec3::Constant(1e-4));
  const Obb flat = aligned(0.5 * d, Vec3(0.1, 0.1, 0.0));
  const Obb thin = aligned(0.5 * d, Vec3(1e-300, 1, 1));
  const Obb middle = aligned(0.5 * d, Vec3::Constant(0.03 * d.norm()));  // cuts the rim
  BoxPlan reused;
  int seen_unresolved = 0, seen_flat = 0;
  for (const Obb& box : {whole, rim, flat, thin, middle, rim, whole, thin, middle}) {
    for (int m : {4, 32}) {
      planner.plan(box, m, &reused);
      const BoxPlan fresh = planner.plan(box, m);
      seen_unresolved += fresh.unresolved;
      seen_flat += fresh.flat;
      EXPECT_EQ(reused.frame.to_local, fresh.frame.to_local);
      EXPECT_EQ(reused.frame.center, fresh.frame.center);
      EXPECT_EQ(reused.frame.volume_scale, fresh.frame.volume_scale);
      EXPECT_EQ(reused.frame.mirrored, fresh.frame.mirrored);
      EXPECT_EQ(reused.frame.inverse_error, fresh.frame.inverse_error);
      EXPECT_EQ(reused.frame.half, fresh.frame.half);
      EXPECT_EQ(reused.frame.valid, fresh.frame.valid);
      EXPECT_EQ(reused.where, fresh.where);
      EXPECT_EQ(reused.far_count, fresh.far_count);
      EXPECT_EQ(reused.constant, fresh.constant);
      EXPECT_EQ(reused.flat, fresh.flat);
      EXPECT_EQ(reused.centre_near_surface, fresh.centre_near_surface);
      EXPECT_EQ(reused.unresolved, fresh.unresolved);
      ASSERT_EQ(reused.tris.size(), fresh.tris.size());
      for (size_t i = 0; i < fresh.tris.size(); ++i) {
        const LocalTriangle &a = reused.tris[i], &b = fresh.tris[i];
        for (int k = 0; k < 3; ++k) {
          EXPECT_EQ(a.p[k], b.p[k]);
          EXPECT_EQ(a.id[k], b.id[k]);
          EXPECT_EQ(a.edge_cross[k], b.edge_cross[k]);
          EXPECT_EQ(a.edge_tie[k], b.edge_tie[k]);
          EXPECT_EQ(a.edge_zero[k], b.edge_zero[k]);
        }
        EXPECT_EQ(a.normal, b.normal);
        EXPECT_EQ(a.plane, b.plane);
        EXPECT_EQ(a.near_centre, b.near_centre);
      }
      ASSERT_EQ(reused.spans.size(), fresh.spans.size());
      for (size_t i = 0; i < fresh.spans.size(); ++i) {
        const TexelSpan &a = reused.spans[i], &b = fresh.spans[i];
        EXPECT_EQ(
            std::make_tuple(a.tri, a.face, a.i0, a.i1, a.j0, a.j1, a.ci0, a.ci1, a.cj0, a.cj1),
            std::make_tuple(b.tri, b.face, b.i0, b.i1, b.j0, b.j1, b.ci0, b.ci1, b.cj0, b.cj1));
      }
    }
  }
  // Each early exit was taken: the thin box twice and the flat box once, at 2 resolutions each.
  EXPECT_EQ(seen_unresolved, 4);
  EXPECT_EQ(seen_flat, 2);
}

// The cube [-1, 1]^3 with each side cut into an n x n grid of squares, two faces each,
// outward: 12 n^2 small faces, so that a small box meets only a few of them. The faces are
// shuffled, so that mesh order is not the order in which a spatial search finds them.
Mesh grid_cube(int n) {
  Mesh mesh;
  std::map<std::array<int, 3>, int32_t> index;
  auto vertex = [&](std::array<int, 3> g) {
    auto [it, added] = index.emplace(g, static_cast<int32_t>(mesh.vertices.size()));
    if (added) mesh.vertices.push_back(Vec3(g[0], g[1], g[2]) * (2.0 / n) - Vec3::Ones());
    return it->second;
  };
  for (int axis = 0; axis < 3; ++axis) {
    const int a = (axis + 1) % 3, b = (axis + 2) % 3;
    for (int side : {0, n}) {
      for (int i = 0; i < n; ++i) {
        for (int j = 0; j < n; ++j) {
          auto at = [&](int di, int dj) {
            std::array<int, 3> g{};
            g[axis] = side;
            g[a] = i + di;
            g[b] = j + dj;
            return vertex(g);
          };
          // (a, b, axis) is right-handed: counter-clockwise about +axis on the far side.
          const int32_t v00 = at(0, 0), v10 = at(1, 0), v11 = at(1, 1), v01 = at(0, 1);
          if (side == n) {
            mesh.faces.push_back({v00, v10, v11});
            mesh.faces.push_back({v00, v11, v01});
          } else {
            mesh.faces.push_back({v00, v11, v10});
            mesh.faces.push_back({v00, v01, v11});
          }
        }
      }
    }
  }
  std::mt19937 rng(5);
  std::shuffle(mesh.faces.begin(), mesh.faces.end(), rng);
  return mesh;
}

// With culling the plan holds its faces in mesh order, as without culling (the CPU twin sums
// the faces' hits in that order, and GL blends them in it): the culled plan's faces are the
// unculled plan's in the same order, less those culled. Checked where the faces found are many
// (a box over the whole cube or a corner of it: read through a bit per face) and where they are
// few (a box on one side: sorted, which the test checks by counting the faces whose boxes meet
// a box around the plan's padded query).
TEST(TexelPlan, CulledPlansKeepTheFacesInMeshOrder) {
  const Mesh mesh = grid_cube(20);  // 4,800 faces, squares of side 0.1
  ASSERT_EQ(mesh.faces.size(), 4800u);
  const BoxPlanner culled(mesh);
  BoxPlanner all(mesh);
  all.set_culling(false);
  auto ids = [](const BoxPlan& plan) {
    std::vector<std::array<int32_t, 3>> out;
    for (const LocalTriangle& t : plan.tris) out.push_back({t.id[0], t.id[1], t.id[2]});
    return out;
  };
  Obb box;
  box.axes = orthonormalize({Vec3(1, 0.2, 0.1), Vec3(-0.2, 1, 0.05), Vec3(0, 0, 1)});
  for (const auto& [center, half, least, sorted] :
       {std::make_tuple(Vec3(0.0, 0.0, 0.0), 2.0, size_t{4800}, false),     // the whole cube
        std::make_tuple(Vec3(0.9, 0.9, 0.9), 0.3, size_t{100}, false),      // a corner
        std::make_tuple(Vec3(0.99, 0.03, 0.02), 0.04, size_t{2}, true)}) {  // on one side
    box.center = center;
    box.half = Vec3::Constant(half);
    // plan() finds the faces whose boxes meet the box's corners' bounds padded by 1e-9 of the
    // scale; padding by 1e-6 finds at least those. Under 1/256 of the mesh: the sorted path.
    Aabb query;
    for (const Vec3& c : corners(box)) query.extend(c);
    query.lo -= Vec3::Constant(1e-6);
    query.hi += Vec3::Constant(1e-6);
    size_t found = 0;
    culled.face_tree().for_each_overlap(query, [&](int32_t) { ++found; });
    EXPECT_EQ(found * 256 < mesh.faces.size(), sorted)
        << "half " << half << ": " << found << " faces found";
    const auto some = ids(culled.plan(box, 16)), every = ids(all.plan(box, 16));
    ASSERT_GE(some.size(), least) << "half " << half;
    if (least == mesh.faces.size()) {
      EXPECT_EQ(some, every);  // the whole cube: every face is kept
    }
    size_t at = 0;  // `some` must be a subsequence of `every`
    for (const auto& f : some) {
      while (at < every.size() && every[at] != f) ++at;
      ASSERT_LT(at, every.size()) << "a face out of mesh order, half " << half;
      ++at;
    }
  }
}
}  // namespace
}  // namespace vobb
