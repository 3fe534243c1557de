// The upper-bound study (validate/upper_bound_study.h) on a small genus-1 solid: every layer of
// both builders' trees is certified, Σ OBV ≥ OMV holds exactly on each (with equality on the
// root's layer, one box), and the estimated sums are judged against the exact OMV with and
// without the stated allowance. The estimates are replaced here by values whose relation to OMV
// is known without the estimator: 0 (below any positive OMV) and vol(O) + estimate (above
// Σ vol(O) ≥ Σ OBV ≥ OMV), so each verdict is derived, not taken from a run.
#include "validate/upper_bound_study.h"

#include <gtest/gtest.h>

#include "common/obb.h"
#include "data/analytic_meshes.h"

namespace vobb::validate {
namespace {

constexpr int kDepth = 2;

UpperBoundResult study(const Mesh& mesh, EstimatePerturbation perturb, double c) {
  UpperBoundConfig config;
  config.meshes = {{"torus", &mesh}};
  config.depth = kDepth;
  config.variational_m = 16;
  config.lloyd_iterations = 2;
  config.max_sweeps = 1;
  config.ms = {8, 16};
  config.perturb = std::move(perturb);
  StatedBound bound;
  bound.c = c;
  bound.p = 0;  // B(m) = c vol(O) at every m
  return run_upper_bound_study(config, bound);
}

// The estimated rows of a study: both trees' kDepth + 1 layers, each at both m. The per-row
// checks below run in loops over them, so each test first checks that they are all there.
constexpr size_t kEstimateRows = 2 * (kDepth + 1) * 2;
size_t estimate_rows(const UpperBoundResult& r) {
  size_t n = 0;
  for (const LayerBoundRow& l : r.layers) n += l.estimated.size();
  return n;
}

// Both trees, every layer, exact: the layers are the trees' levels, Σ OBV ≥ OMV as rationals,
// the root's single box has OMV = OBV exactly, and the gap reported is Σ OBV − OMV.
TEST(UpperBoundStudy, EveryLayerOfBothTreesIsCertifiedExactly) {
  // The torus' root box holds its hole, so every layer sticks out of the solid: OMV > 0.
  const Mesh mesh = analytic::polygonal_torus().mesh;
  const UpperBoundResult r = study(mesh, {}, 0.0);
  ASSERT_EQ(r.trees.size(), 2u);
  EXPECT_EQ(r.trees[0].builder, "obbtree");
  EXPECT_EQ(r.trees[1].builder, "variational");
  for (const TreeCheck& t : r.trees) EXPECT_TRUE(t.containment_ok) << t.builder;
  ASSERT_EQ(r.layers.size(), 2u * (kDepth + 1));
  for (size_t i = 0; i < r.layers.size(); ++i) {
    const LayerBoundRow& l = r.layers[i];
    SCOPED_TRACE(l.builder + " level " + std::to_string(l.level));
    EXPECT_EQ(l.builder, i <= kDepth ? "obbtree" : "variational");
    EXPECT_EQ(l.level, static_cast<int>(i % (kDepth + 1)));
    EXPECT_TRUE(l.exact_holds);
    EXPECT_TRUE(l.paths_agree);
    EXPECT_TRUE(l.sum_obv >= l.omv);
    EXPECT_TRUE(l.omv > 0);
    EXPECT_EQ(l.gap, to_double_nearest(Rational(l.sum_obv - l.omv)));
    if (l.level == 0) {
      EXPECT_EQ(l.boxes, 1u);
      EXPECT_EQ(l.overlapping_boxes, 0u);
      EXPECT_TRUE(l.sum_obv == l.omv);
      EXPECT_EQ(l.gap, 0.0);
    } else {
      EXPECT_GE(l.boxes, 2u);
    }
    ASSERT_EQ(l.estimated.size(), 2u);
    EXPECT_EQ(l.estimated[0].m, 8);
    EXPECT_EQ(l.estimated[1].m, 16);
    for (const auto& e : l.estimated) EXPECT_EQ(e.allowance, 0.0);  // c = 0
  }
  EXPECT_TRUE(r.all_exact_hold());
  // A layer whose OMV paths disagree fails the study, though sum OBV >= OMV still holds there.
  UpperBoundResult split = r;
  split.layers.back().paths_agree = false;
  EXPECT_FALSE(split.all_exact_hold());
}

// Every estimate 0: below OMV, and without an allowance the study must say so; with B = vol(O)
// (c = 1, p = 0) the allowance alone is Σ vol(O) ≥ OMV, so every layer holds with it.
TEST(UpperBoundStudy, EstimatesBelowOmvFailUnlessTheAllowanceCoversThem) {
  const Mesh mesh = analytic::polygonal_torus().mesh;
  const auto zero = [](double, const Obb&, int) { return 0.0; };
  const UpperBoundResult none = study(mesh, zero, 0.0);
  EXPECT_TRUE(none.all_exact_hold());  // the perturbation reaches the estimates only
  EXPECT_FALSE(none.all_estimated_hold_with_bound());
  ASSERT_EQ(estimate_rows(none), kEstimateRows);
  for (const LayerBoundRow& l : none.layers)
    for (const auto& e : l.estimated) {
      EXPECT_EQ(e.sum, 0.0);
      EXPECT_FALSE(e.above);
      EXPECT_FALSE(e.above_with_bound);
    }
  const UpperBoundResult covered = study(mesh, zero, 1.0);
  EXPECT_TRUE(covered.all_estimated_hold_with_bound());
  ASSERT_EQ(estimate_rows(covered), kEstimateRows);
  for (const LayerBoundRow& l : covered.layers)
    for (const auto& e : l.estimated) {
      EXPECT_FALSE(e.above);
      EXPECT_TRUE(e.above_with_bound);
      EXPECT_GT(e.allowance, 0.0);
    }
}

// Every estimate raised by its box's volume: each sum is at least Σ vol(O) ≥ Σ OBV ≥ OMV (the
// estimates are never negative), so every layer is above OMV even without an allowance.
TEST(UpperBoundStudy, EstimatesAboveOmvHoldWithoutAllowance) {
  const Mesh mesh = analytic::polygonal_torus().mesh;
  const auto raised = [](double estimate, const Obb& box, int) { return estimate + volume(box); };
  const UpperBoundResult r = study(mesh, raised, 0.0);
  EXPECT_TRUE(r.all_estimated_hold_with_bound());
  ASSERT_EQ(estimate_rows(r), kEstimateRows);
  for (const LayerBoundRow& l : r.layers)
    for (const auto& e : l.estimated) {
      EXPECT_TRUE(e.above);
      EXPECT_TRUE(e.above_with_bound);
      EXPECT_TRUE(Rational(e.sum) >= l.sum_obv);
    }
}

}  // namespace
}  // namespace vobb::validate
