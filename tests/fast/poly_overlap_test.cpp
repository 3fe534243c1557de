// Shared outer volume (fast/poly_overlap.h): its exact value is the clipping path's, its
// interval holds it, its double is that value to round-off, and with it a layer's OMV is exact:
// inclusion-exclusion for two boxes, Bonferroni's bracket for three, and shares for any number.
#include "fast/poly_overlap.h"

#include <gtest/gtest.h>

#include <array>
#include <cmath>
#include <map>
#include <random>
#include <tuple>

#include "builder/variational_builder.h"
#include "common/cell_clip.h"
#include "common/io/mesh_report.h"
#include "common/solidity.h"
#include "data/analytic_meshes.h"
#include "exact/outer_volume.h"
#include "fast/poly_solver.h"
#include "test_common.h"

namespace vobb {
namespace {

double uniform(std::mt19937_64& rng, double a, double b) {
  return a + (b - a) * (double(rng() >> 11) * 0x1p-53);
}

// A seeded pair of boxes that mostly overlap and cut the mesh's surface: the first anywhere
// near the mesh, the second centred within the first's reach, both in any orientation.
std::pair<Obb, Obb> random_pair(const Mesh& mesh, std::mt19937_64& rng) {
  Aabb bounds;
  for (const Vec3& v : mesh.vertices) bounds.extend(v);
  const Vec3 size = bounds.hi - bounds.lo;
  auto box_near = [&](const Vec3& around, double spread) {
    Vec3 c, h;
    for (int k = 0; k < 3; ++k) c[k] = around[k] + spread * uniform(rng, -1, 1);
    const double s = std::exp(uniform(rng, std::log(0.05), std::log(0.8))) * size.maxCoeff();
    for (int k = 0; k < 3; ++k) h[k] = s * uniform(rng, 0.2, 1.0);
    return rotated_box(c, h, uniform(rng, 0, 3.14159),
                       Vec3(uniform(rng, -1, 1), uniform(rng, -1, 1), uniform(rng, 0.1, 1)));
  };
  const Obb a = box_near(0.5 * (bounds.lo + bounds.hi), 0.5 * size.maxCoeff());
  const Obb b = box_near(a.center, a.half.maxCoeff());
  return {a, b};
}

// A ∩ B as one cell (empty where they share no volume): B split against A alone.
template <class NT>
cell_clip::Cell<NT> pair_cell(const Obb& a, const Obb& b) {
  std::vector<cell_clip::Cell<NT>> cells = cell_clip::shared_cells<NT>(b, {a});
  EXPECT_LE(cells.size(), 1u);
  return cells.empty() ? cell_clip::Cell<NT>() : std::move(cells.front());
}

// The estimate is not certified; the header promises it within 1e-9 of B's volume of the exact
// value, far below the OBV estimator's error (about 1e-4 of a box's volume), or the builder's
// objective would not be what it says. Checked here against the pair's cell, which lies in B,
// so the check is at least as strict; round-off alone is about 1e-15.
::testing::AssertionResult close_to_exact(double estimate, const Rational& exact, const Obb& a,
                                          const Obb& b) {
  const double cell = pair_cell<double>(a, b).volume();
  if (std::abs(estimate - to_double_nearest(exact)) <= 1e-9 * cell)
    return ::testing::AssertionSuccess();
  return ::testing::AssertionFailure() << "estimate " << estimate << " against exact "
                                       << format_nearest(exact) << " (cell volume " << cell << ")";
}

TEST(PolyOverlap, ExactIsTheClippingPathsAndTheIntervalHoldsIt) {
  int overlapping = 0, partial = 0, fallbacks = 0, pairs = 0;
  for (const analytic::AnalyticMesh& am : analytic::all()) {
    SCOPED_TRACE(am.name);
    const PolyOverlapSolver poly(am.mesh);
    const exact::ClipSolver clip(am.mesh);
    std::mt19937_64 rng(17);
    for (int i = 0; i < 12; ++i) {
      SCOPED_TRACE("pair " + std::to_string(i));
      const auto [a, b] = random_pair(am.mesh, rng);
      const std::vector<Obb> boxes{a, b};
      // The clipping path: box 1's share of the pair's overlap term is vol((A ∩ B) \ X).
      const Rational expected = clip.overlap_term(boxes, 1, clip.earlier_neighbours(boxes)[1]);
      const Rational got = poly.exact(a, {b});
      EXPECT_EQ(got, expected);
      EXPECT_EQ(poly.exact(b, {a}), expected);  // either order
      const PolyOverlap r = poly.evaluate(a, {b});
      EXPECT_LE(Rational(r.lo), expected);
      EXPECT_LE(expected, Rational(r.hi));
      EXPECT_TRUE(close_to_exact(poly.estimate(a, {b}), expected, a, b));
      ++pairs;
      fallbacks += r.exact;
      overlapping += sgn(expected) > 0;
      // Partly inside the solid: the term is neither 0 nor the whole intersection.
      const Rational whole = pair_cell<Rational>(a, b).volume();
      partial += sgn(expected) > 0 && expected < whole;
    }
  }
  // The cases exercise what they claim to: most pairs overlap, and many cut the surface.
  EXPECT_GE(overlapping, pairs / 2);
  EXPECT_GE(partial, pairs / 4);
  EXPECT_LT(fallbacks, pairs / 4);
}

TEST(PolyOverlap, TwoBoxesGiveTheirExactOmv) {
  for (const analytic::AnalyticMesh& am :
       {analytic::cube_with_cavity(), analytic::polygonal_torus()}) {
    SCOPED_TRACE(am.name);
    const PolyOverlapSolver poly(am.mesh);
    const PolyObvSolver obv(am.mesh);
    const exact::ClipSolver clip(am.mesh);
    std::mt19937_64 rng(5);
    for (int i = 0; i < 6; ++i) {
      const auto [a, b] = random_pair(am.mesh, rng);
      // OMV_pair for two boxes is inclusion-exclusion in full.
      EXPECT_EQ(obv.exact(a) + obv.exact(b) - poly.exact(a, {b}), clip.omv({a, b}));
    }
  }
  // And once against Nef, the independent path.
  const analytic::AnalyticMesh am = analytic::cube_with_cavity();
  const PolyOverlapSolver poly(am.mesh);
  const PolyObvSolver obv(am.mesh);
  const Obb a = rotated_box(Vec3(1.5, 2.0, 1.8), Vec3(1.6, 1.1, 1.3), 0.4);
  const Obb b = rotated_box(Vec3(2.6, 2.4, 2.2), Vec3(1.4, 1.5, 0.9), 1.1, Vec3(-1, 2, 0.5));
  const Rational pair = obv.exact(a) + obv.exact(b) - poly.exact(a, {b});
  EXPECT_GT(poly.exact(a, {b}), 0);
  EXPECT_EQ(pair, exact::NefSolver(am.mesh).omv({a, b}));
}

TEST(PolyOverlap, ThreeBoxesAreBracketedAndTheGapIsTheTripleTerm) {
  const analytic::AnalyticMesh am = analytic::polygonal_torus();
  const PolyOverlapSolver poly(am.mesh);
  const PolyObvSolver obv(am.mesh);
  const exact::ClipSolver clip(am.mesh);
  // Three boxes around one point of the torus's hole, each reaching into the other two.
  const Obb boxes[3] = {
      rotated_box(Vec3(0.3, 0.1, 0.2), Vec3(0.9, 0.5, 0.6), 0.3),
      rotated_box(Vec3(-0.2, 0.3, 0.1), Vec3(0.6, 0.9, 0.5), 0.9, Vec3(1, -1, 2)),
      rotated_box(Vec3(0.1, -0.3, -0.1), Vec3(0.7, 0.6, 0.8), 1.7, Vec3(0, 1, 1))};
  Rational sum_obv = 0, pairs = 0;
  for (int i = 0; i < 3; ++i) {
    sum_obv += obv.exact(boxes[i]);
    for (int j = i + 1; j < 3; ++j) pairs += poly.exact(boxes[i], {boxes[j]});
  }
  const Rational omv = clip.omv({boxes[0], boxes[1], boxes[2]});
  // Bonferroni: sum OBV - sum pairs <= OMV <= sum OBV.
  EXPECT_LE(sum_obv - pairs, omv);
  EXPECT_LE(omv, sum_obv);
  // The lower bound misses exactly vol((A ∩ B ∩ C) \ X), here not 0.
  cell_clip::Cell<Rational> triple = pair_cell<Rational>(boxes[0], boxes[1]);
  const box_clip::Frame<Rational> fc = box_clip::make_frame<Rational>(boxes[2]);
  for (const auto& h : cell_clip::box_planes(fc, sgn(fc.det))) triple = triple.clipped(h);
  const AabbTree faces = AabbTree::over_faces(am.mesh);
  const Rational triple_term =
      cell_clip::outside_volume(am.mesh, faces, triple, cell_clip::reach_of(triple));
  EXPECT_GT(triple_term, 0);
  EXPECT_LT(sum_obv - pairs, omv);
  EXPECT_EQ(sum_obv - pairs + triple_term, omv);
  // Each box's share of what the earlier ones hold gives the OMV exactly.
  EXPECT_EQ(sum_obv - poly.exact(boxes[1], {boxes[0]}) - poly.exact(boxes[2], {boxes[0], boxes[1]}),
            omv);
}

// Random layers: sum OBV less each box's share with the earlier ones is the layer's OMV, as
// rationals, and the estimate and the interval agree with it.
TEST(PolyOverlap, SharesGiveTheExactOmvOfALayer) {
  for (const analytic::AnalyticMesh& am :
       {analytic::polygonal_torus(), analytic::cube_with_cavity()}) {
    SCOPED_TRACE(am.name);
    const PolyOverlapSolver poly(am.mesh);
    const PolyObvSolver obv(am.mesh);
    const exact::ClipSolver clip(am.mesh);
    std::mt19937_64 rng(11);
    int sharing = 0;  // layers where some box shares outer volume with earlier ones
    for (int layer = 0; layer < 4; ++layer) {
      std::vector<Obb> boxes;
      for (int k = 0; k < 3; ++k) {
        const auto [a, b] = random_pair(am.mesh, rng);
        boxes.push_back(a);
        boxes.push_back(b);
      }
      Rational omv = 0;
      bool shared = false;
      for (size_t j = 0; j < boxes.size(); ++j) {
        const std::vector<Obb> earlier(boxes.begin(), boxes.begin() + j);
        const Rational s = poly.exact(boxes[j], earlier);
        omv += obv.exact(boxes[j]) - s;
        shared |= sgn(s) > 0;
        const PolyOverlap r = poly.evaluate(boxes[j], earlier);
        EXPECT_LE(Rational(r.lo), s);
        EXPECT_LE(s, Rational(r.hi));
        // As close_to_exact, over the box's volume (its cells lie in it).
        EXPECT_LE(std::abs(poly.estimate(boxes[j], earlier) - to_double_nearest(s)),
                  1e-9 * volume(boxes[j]));
      }
      sharing += shared;
      EXPECT_EQ(omv, clip.omv(boxes));
    }
    EXPECT_GE(sharing, 2);  // the identity is tested where it has something to subtract
  }
}

TEST(PolyOverlap, ApartOrTouchingBoxesShareNothing) {
  const analytic::AnalyticMesh am = analytic::cube(2.0);
  const PolyOverlapSolver poly(am.mesh);
  const Obb a = rotated_box(Vec3(0.5, 0.5, 0.5), Vec3(1, 1, 1));
  const Obb far = rotated_box(Vec3(4, 0.5, 0.5), Vec3(1, 1, 1), 0.7);
  EXPECT_TRUE(boxes_apart(a, far));
  EXPECT_EQ(poly.estimate(a, {far}), 0.0);
  const PolyOverlap r = poly.evaluate(a, {far});
  EXPECT_EQ(r.lo, 0.0);
  EXPECT_EQ(r.hi, 0.0);
  // Sharing the face x = 1.5 exactly: no separating gap, and no volume in common.
  const Obb touching = rotated_box(Vec3(2.5, 0.5, 0.5), Vec3(1, 1, 1));
  EXPECT_FALSE(boxes_apart(a, touching));
  EXPECT_EQ(poly.exact(a, {touching}), 0);
  EXPECT_EQ(poly.evaluate(a, {touching}).hi, 0.0);
  EXPECT_EQ(poly.estimate(a, {touching}), 0.0);
}

TEST(PolyOverlap, ABatchGivesEachPairsOwnValue) {
  const analytic::AnalyticMesh am = analytic::polygonal_torus();
  const PolyOverlapSolver poly(am.mesh);
  std::mt19937_64 rng(9);
  std::vector<ShareQuery> queries;
  for (int i = 0; i < 40; ++i) {
    const auto [a, b] = random_pair(am.mesh, rng);
    queries.push_back({a, {b, random_pair(am.mesh, rng).first}});
  }
  const std::vector<double> batch = poly.estimate(queries);
  for (size_t i = 0; i < queries.size(); ++i)
    EXPECT_EQ(batch[i], poly.estimate(queries[i].box, queries[i].earlier));
}

}  // namespace
}  // namespace vobb

namespace vobb {
namespace {

// A closed plate [0, 1]^2 x [0, t], its top and bottom tessellated n by n (two triangles a
// square), its sides n quads each: a flat part whose faces lie on its tight boxes' planes.
Mesh plate(int n, double t) {
  Mesh m;
  std::map<std::tuple<int, int, int>, int32_t> index;
  auto v = [&](int i, int j, int k) {
    const auto key = std::make_tuple(i, j, k);
    auto it = index.find(key);
    if (it != index.end()) return it->second;
    m.vertices.push_back(Vec3(double(i) / n, double(j) / n, k * t));
    return index[key] = static_cast<int32_t>(m.vertices.size() - 1);
  };
  auto quad = [&](int32_t a, int32_t b, int32_t c, int32_t d) {
    m.faces.push_back({a, b, c});
    m.faces.push_back({a, c, d});
  };
  for (int i = 0; i < n; ++i)
    for (int j = 0; j < n; ++j) {
      quad(v(i, j, 0), v(i, j + 1, 0), v(i + 1, j + 1, 0), v(i + 1, j, 0));
      quad(v(i, j, 1), v(i + 1, j, 1), v(i + 1, j + 1, 1), v(i, j + 1, 1));
    }
  for (int i = 0; i < n; ++i) {
    quad(v(i, 0, 0), v(i + 1, 0, 0), v(i + 1, 0, 1), v(i, 0, 1));
    quad(v(i, n, 0), v(i, n, 1), v(i + 1, n, 1), v(i + 1, n, 0));
    quad(v(0, i, 0), v(0, i, 1), v(0, i + 1, 1), v(0, i + 1, 0));
    quad(v(n, i, 0), v(n, i + 1, 0), v(n, i + 1, 1), v(n, i, 1));
  }
  return m;
}

// A box that a build of the 1 x 1 x 1e-3 plate (32 by 32) asked for, turned off the plate's
// axes by about 1e-4, and three earlier boxes (two the same), tight on the plate's planes: its
// cells meet mesh vertices and faces on their planes, and the rounded signs contradict each
// other at both snaps. The estimate then takes every box grown by 2^-30 of its half extents
// (fast/poly_overlap.h): the share only grows with the boxes, by less than 3.01 2^-30 of their
// volumes, so the estimate lies in [exact - r, exact + 3.01 2^-30 (V_B + sum V_E) + r], r the
// round-off that EstimatesAreTheExactValueToRoundOff allows (1e-9 of the cells' volume,
// bounded here by the box's volume). The certified interval still holds the exact value.
TEST(PolyOverlap, DegenerateContactsOfAFlatPartAreEstimatedFromGrownBoxes) {
  const Mesh mesh = plate(32, 1e-3);
  ASSERT_TRUE(check_solidity(mesh).solid());
  auto box = [](const Vec3& c, const Vec3& h, const Vec3& a0, const Vec3& a1, const Vec3& a2) {
    Obb b;
    b.center = c;
    b.half = h;
    b.axes = {a0, a1, a2};
    return b;
  };
  const Obb b = box(Vec3(0x1.b000000000001p-1, 0x1.8000000000001p-1, 0x1.0624dd2f1a9fcp-11),
                    Vec3(0x1.00009c206e9efp-2, 0x1.4001eb5c71ba8p-3, 0x1.128766f437cp-11),
                    Vec3(-0x1.ea7f8ae7b0ef1p-17, -0x1.ffffffdec22fap-1, 0x1.6bdd78fb867c2p-14),
                    Vec3(0x1.fffffffe6c8a2p-1, -0x1.ea88c47ad6f59p-17, -0x1.9f5ae1c3d9a2ap-17),
                    Vec3(0x1.9f65c68a1c193p-17, 0x1.6bdd473d39882p-14, 0x1.ffffffdf04a8dp-1));
  const Obb e0 = box(
      Vec3(0x1.8p-1, 0x1p-2, 0x1.0624dd2f1a9fcp-11), Vec3(0x1p-2, 0x1p-2, 0x1.0624dd2f1a9fcp-11),
      Vec3(-0.0, 1, 0x1.0000000000001p-63), Vec3(1, 0, 0), Vec3(0, 0x1.0000000000001p-63, -1));
  const Obb e2 = box(Vec3(0x1.5fea7423348d2p-1, 0x1.8019bedba86cdp-1, 0x1.0624dd2f1a9fcp-11),
                     Vec3(0x1.00336fe33a878p-2, 0x1.80bcea51fdac4p-3, 0x1.0624dd2f1a9fcp-11),
                     Vec3(-0x1.1319d1985148cp-9, 0x1.ffffb617dbf09p-1, -0x1.b50127378109ep-66),
                     Vec3(-0x1.ffffb617dbf09p-1, -0x1.1319d1985148cp-9, 0x1.d59c93d1279bp-75),
                     Vec3(0x1.8fffffffffffep-122, 0x1.b501664c57896p-66, 1));
  const std::vector<Obb> earlier = {e0, e0, e2};
  for (const Obb& x : {b, e0, e2}) ASSERT_EQ(box_defect(x), "");
  const AabbTree faces = AabbTree::over_faces(mesh);
  for (const double snap : {0.0, 1e-10})
    EXPECT_THROW(cell_clip::shared_outside_volume<double>(mesh, faces, b, earlier, snap),
                 cell_clip::InconsistentSides)
        << snap;
  const PolyOverlapSolver poly(mesh);
  const Rational exact = poly.exact(b, earlier);
  const double estimate = poly.estimate(b, earlier);
  const PolyOverlap certified = poly.evaluate(b, earlier);
  EXPECT_LE(Rational(certified.lo), exact);
  EXPECT_GE(Rational(certified.hi), exact);
  EXPECT_GT(exact, 0);
  const double volumes = volume(b) + volume(e0) * 2 + volume(e2);
  const double r = 1e-9 * volume(b);
  EXPECT_GE(Rational(estimate), exact - Rational(r));
  EXPECT_LE(Rational(estimate), exact + Rational(3.01 * 0x1p-30 * volumes + r));
}

// A unit cube sheared 1e8 to one (x += 1e8 z), in two tight boxes of its two halves of faces
// along frames turned by 1e-8 or less: the cuts are so ill-conditioned that double intervals
// decide none of these shares. The MPFR enclosures decide some; each enclosure holds the exact
// value, and where an MPFR enclosure or the rationals decided, the estimate is its nearest
// double.
TEST(PolyOverlap, IllConditionedCutsAreDecidedInWiderEnclosures) {
  Mesh mesh = analytic::cube().mesh;
  for (Vec3& v : mesh.vertices) v.x() += 1e8 * v.z();
  ASSERT_TRUE(check_solidity(mesh).solid());
  const PolyOverlapSolver poly(mesh);
  const std::vector<int32_t> half1 = {1, 2, 4, 7, 8, 9}, half2 = {0, 3, 5, 6, 10, 11};
  auto frame = [](double turn) {
    return orthonormalize({Vec3(1, turn, 1e-8), Vec3(-turn, 1, 0), Vec3::Zero()});
  };
  int by_doubles = 0, by_mpfr = 0, by_rationals = 0;
  for (const double t1 : {0.0, 5e-9, 1e-8, -5e-9})
    for (const double t2 : {0.0, 5e-9, 1e-8, 2e-8}) {
      SCOPED_TRACE(std::to_string(t1) + " " + std::to_string(t2));
      const Obb a = tight_box(mesh, half1, frame(t1)), b = tight_box(mesh, half2, frame(t2));
      const Rational exact = poly.exact(b, {a});
      const PolyOverlap r = poly.evaluate(b, {a});
      EXPECT_LE(Rational(r.lo), exact);
      EXPECT_LE(exact, Rational(r.hi));
      if (r.exact || r.enclosure_bits > 0) {
        EXPECT_EQ(r.estimate, to_double_nearest(exact));
      }
      if (r.enclosure_bits > 0) {
        EXPECT_TRUE(r.enclosure_bits == 128 || r.enclosure_bits == 256);
      }
      EXPECT_FALSE(r.exact && r.enclosure_bits > 0);  // one tier decided
      by_doubles += !r.exact && r.enclosure_bits == 0;
      by_mpfr += r.enclosure_bits > 0;
      by_rationals += r.exact;
    }
  EXPECT_EQ(by_doubles, 0);  // the case is as ill-conditioned as it claims
  EXPECT_GT(by_mpfr, 0);
  EXPECT_GT(by_rationals, 0);  // tight boxes touch mesh vertices: some signs are 0 exactly
}

// Sibling-like pairs on real meshes: two tight boxes of neighbouring face groups, which touch
// the same mesh vertices where the groups meet (the builder's case), and random pairs.
TEST(PolyOverlapReal, EstimatesAreTheExactValueToRoundOff) {
  VOBB_REQUIRE_REAL_MESH("dino");
  for (const std::string name : {"dino"}) {
    SCOPED_TRACE(name);
    LoadedMesh lm;
    ASSERT_TRUE(load_solid(test::real_mesh(name), &lm));
    const Mesh& mesh = lm.mesh;
    const PolyOverlapSolver poly(mesh);
    std::mt19937_64 rng(3);
    std::vector<std::pair<Obb, Obb>> pairs;
    for (int i = 0; i < 6; ++i) pairs.push_back(random_pair(mesh, rng));
    // Split the faces in two by a random plane through the mesh's middle: each side's tight
    // box in a random frame.
    Aabb bounds = mesh.bounds();
    for (int i = 0; i < 10; ++i) {
      const Vec3 n =
          Vec3(uniform(rng, -1, 1), uniform(rng, -1, 1), uniform(rng, -1, 1)).normalized();
      const Vec3 mid =
          bounds.lo + (bounds.hi - bounds.lo)
                          .cwiseProduct(Vec3(uniform(rng, 0.3, 0.7), uniform(rng, 0.3, 0.7),
                                             uniform(rng, 0.3, 0.7)));
      std::vector<int32_t> side[2];
      for (size_t f = 0; f < mesh.faces.size(); ++f)
        side[(mesh.corner(f, 0) - mid).dot(n) > 0].push_back(static_cast<int32_t>(f));
      if (side[0].empty() || side[1].empty()) continue;
      Obb box[2];
      for (int k = 0; k < 2; ++k) {
        const Obb r = rotated_box(Vec3::Zero(), Vec3::Ones(), uniform(rng, 0, 3.14159),
                                  Vec3(uniform(rng, -1, 1), uniform(rng, -1, 1), 1));
        box[k] = tight_box(mesh, side[k], r.axes);
      }
      pairs.emplace_back(box[0], box[1]);
    }
    int positive = 0;
    for (size_t i = 0; i < pairs.size(); ++i) {
      SCOPED_TRACE("pair " + std::to_string(i));
      const auto& [a, b] = pairs[i];
      const Rational q = poly.exact(a, {b});
      EXPECT_TRUE(close_to_exact(poly.estimate(a, {b}), q, a, b));
      positive += sgn(q) > 0;
    }
    EXPECT_GE(positive, 10);
  }
}

}  // namespace
}  // namespace vobb
