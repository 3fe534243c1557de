// The pairwise overlap term (fast/poly_overlap.h): its exact value is the clipping path's,
// its interval holds it, its double lies in the interval, and with it inclusion-exclusion
// gives the exact OMV of two boxes and brackets that of three.
#include "fast/poly_overlap.h"

#include <gtest/gtest.h>

#include <cmath>
#include <random>

#include "common/cell_clip.h"
#include "data/analytic_meshes.h"
#include "exact/outer_volume.h"
#include "fast/poly_solver.h"

namespace vobb {
namespace {

double uniform(std::mt19937_64& rng, double a, double b) { return a + (b - a) * (double(rng() >> 11) * 0x1p-53); }

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
    return rotated_box(c, h, uniform(rng, 0, 3.14159), Vec3(uniform(rng, -1, 1), uniform(rng, -1, 1), uniform(rng, 0.1, 1)));
  };
  const Obb a = box_near(0.5 * (bounds.lo + bounds.hi), 0.5 * size.maxCoeff());
  const Obb b = box_near(a.center, a.half.maxCoeff());
  return {a, b};
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
      const Rational got = poly.exact(a, b);
      EXPECT_EQ(got, expected);
      EXPECT_EQ(poly.exact(b, a), expected);  // either order
      const PolyOverlap r = poly.evaluate(a, b);
      EXPECT_LE(Rational(r.lo), expected);
      EXPECT_LE(expected, Rational(r.hi));
      // Same faces, same decisions (every sign decided by the intervals): every double
      // operation's result lies in its interval's, so the estimate does too.
      if (!r.exact) {
        const double e = poly.estimate(a, b);
        EXPECT_LE(r.lo, e);
        EXPECT_LE(e, r.hi);
      }
      ++pairs;
      fallbacks += r.exact;
      overlapping += sgn(expected) > 0;
      // Partly inside the solid: the term is neither 0 nor the whole intersection.
      const Rational whole = cell_clip::box_pair_cell<Rational>(a, b).volume();
      partial += sgn(expected) > 0 && expected < whole;
    }
  }
  // The cases exercise what they claim to: most pairs overlap, and many cut the surface.
  EXPECT_GE(overlapping, pairs / 2);
  EXPECT_GE(partial, pairs / 4);
  EXPECT_LT(fallbacks, pairs / 4);
}

TEST(PolyOverlap, TwoBoxesGiveTheirExactOmv) {
  for (const analytic::AnalyticMesh& am : {analytic::cube_with_cavity(), analytic::polygonal_torus()}) {
    SCOPED_TRACE(am.name);
    const PolyOverlapSolver poly(am.mesh);
    const PolyObvSolver obv(am.mesh);
    const exact::ClipSolver clip(am.mesh);
    std::mt19937_64 rng(5);
    for (int i = 0; i < 6; ++i) {
      const auto [a, b] = random_pair(am.mesh, rng);
      // OMV_pair for two boxes is inclusion-exclusion in full.
      EXPECT_EQ(obv.exact(a) + obv.exact(b) - poly.exact(a, b), clip.omv({a, b}));
    }
  }
  // And once against Nef, the independent path.
  const analytic::AnalyticMesh am = analytic::cube_with_cavity();
  const PolyOverlapSolver poly(am.mesh);
  const PolyObvSolver obv(am.mesh);
  const Obb a = rotated_box(Vec3(1.5, 2.0, 1.8), Vec3(1.6, 1.1, 1.3), 0.4);
  const Obb b = rotated_box(Vec3(2.6, 2.4, 2.2), Vec3(1.4, 1.5, 0.9), 1.1, Vec3(-1, 2, 0.5));
  const Rational pair = obv.exact(a) + obv.exact(b) - poly.exact(a, b);
  EXPECT_GT(poly.exact(a, b), 0);
  EXPECT_EQ(pair, exact::NefSolver(am.mesh).omv({a, b}));
}

TEST(PolyOverlap, ThreeBoxesAreBracketedAndTheGapIsTheTripleTerm) {
  const analytic::AnalyticMesh am = analytic::polygonal_torus();
  const PolyOverlapSolver poly(am.mesh);
  const PolyObvSolver obv(am.mesh);
  const exact::ClipSolver clip(am.mesh);
  // Three boxes around one point of the torus's hole, each reaching into the other two.
  const Obb boxes[3] = {rotated_box(Vec3(0.3, 0.1, 0.2), Vec3(0.9, 0.5, 0.6), 0.3),
                        rotated_box(Vec3(-0.2, 0.3, 0.1), Vec3(0.6, 0.9, 0.5), 0.9, Vec3(1, -1, 2)),
                        rotated_box(Vec3(0.1, -0.3, -0.1), Vec3(0.7, 0.6, 0.8), 1.7, Vec3(0, 1, 1))};
  Rational sum_obv = 0, pairs = 0;
  for (int i = 0; i < 3; ++i) {
    sum_obv += obv.exact(boxes[i]);
    for (int j = i + 1; j < 3; ++j) pairs += poly.exact(boxes[i], boxes[j]);
  }
  const Rational omv = clip.omv({boxes[0], boxes[1], boxes[2]});
  // Bonferroni: sum OBV - sum pairs <= OMV <= sum OBV.
  EXPECT_LE(sum_obv - pairs, omv);
  EXPECT_LE(omv, sum_obv);
  // The lower bound misses exactly vol((A ∩ B ∩ C) \ X), here not 0.
  cell_clip::Cell<Rational> triple = cell_clip::box_pair_cell<Rational>(boxes[0], boxes[1]);
  const box_clip::Frame<Rational> fc = box_clip::make_frame<Rational>(boxes[2]);
  for (const auto& h : cell_clip::box_planes(fc, sgn(fc.det))) triple = triple.clipped(h);
  Aabb reach;
  for (const Obb& b : boxes)
    for (const Vec3& p : corners(b)) reach.extend(p);
  const AabbTree faces = AabbTree::over_faces(am.mesh);
  const Rational triple_term = cell_clip::outside_volume(am.mesh, faces, triple, reach);
  EXPECT_GT(triple_term, 0);
  EXPECT_LT(sum_obv - pairs, omv);
  EXPECT_EQ(sum_obv - pairs + triple_term, omv);
}

TEST(PolyOverlap, ApartOrTouchingBoxesShareNothing) {
  const analytic::AnalyticMesh am = analytic::cube(2.0);
  const PolyOverlapSolver poly(am.mesh);
  const Obb a = rotated_box(Vec3(0.5, 0.5, 0.5), Vec3(1, 1, 1));
  const Obb far = rotated_box(Vec3(4, 0.5, 0.5), Vec3(1, 1, 1), 0.7);
  EXPECT_TRUE(PolyOverlapSolver::apart(a, far));
  EXPECT_EQ(poly.estimate(a, far), 0.0);
  const PolyOverlap r = poly.evaluate(a, far);
  EXPECT_EQ(r.lo, 0.0);
  EXPECT_EQ(r.hi, 0.0);
  // Sharing the face x = 1.5 exactly: no separating gap, and no volume in common.
  const Obb touching = rotated_box(Vec3(2.5, 0.5, 0.5), Vec3(1, 1, 1));
  EXPECT_FALSE(PolyOverlapSolver::apart(a, touching));
  EXPECT_EQ(poly.exact(a, touching), 0);
  EXPECT_EQ(poly.evaluate(a, touching).hi, 0.0);
  EXPECT_EQ(poly.estimate(a, touching), 0.0);
}

TEST(PolyOverlap, ABatchGivesEachPairsOwnValue) {
  const analytic::AnalyticMesh am = analytic::polygonal_torus();
  const PolyOverlapSolver poly(am.mesh);
  std::mt19937_64 rng(9);
  std::vector<std::pair<Obb, Obb>> pairs;
  for (int i = 0; i < 40; ++i) pairs.push_back(random_pair(am.mesh, rng));
  const std::vector<double> batch = poly.estimate(pairs);
  for (size_t i = 0; i < pairs.size(); ++i) EXPECT_EQ(batch[i], poly.estimate(pairs[i].first, pairs[i].second));
}

}  // namespace
}  // namespace vobb
