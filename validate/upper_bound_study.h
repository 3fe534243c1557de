// The upper bound sum OBV >= OMV (DESIGN §1, §6) on the layers of real trees: trees of
// the OBB-Tree baseline and of the variational builder (CPU twin estimator) are built in
// process and certified exactly (exact/certify.h); per layer the exact sum of OBV and OMV are
// compared as rationals, with the gap (the overlap term). Then, per layer and m, whether the
// *estimated* sum of OBV stays above the exact OMV once the stated bound B(m) is allowed for:
//   sum_j E_m(O_j) + sum_j B(m) vol(O_j) >= OMV_exact,
// compared exactly (the double sums as computed, turned into rationals without rounding).
#pragma once

#include <functional>
#include <string>
#include <vector>

#include "common/exact_predicates.h"
#include "validate/discretization_study.h"

namespace vobb::validate {

struct UpperBoundConfig {
  std::vector<NamedMesh> meshes;
  int depth = 4;
  int variational_m = 32;  // the builder's estimator resolution
  int lloyd_iterations = 4;
  int max_sweeps = 3;             // the variational builder's bottom-up merging sweeps
  std::vector<int> ms = {8, 32};  // resolutions of the estimated sums
  bool want_gl = false;           // the estimated sums use the CPU twin (same texels as GL)
  EstimatePerturbation perturb;   // tests only
  std::function<void(const std::string&)> progress;
};

struct LayerBoundRow {
  std::string mesh, builder;
  int level = 0;
  size_t boxes = 0, overlapping_boxes = 0;
  Rational omv, sum_obv;
  bool exact_holds = false;  // sum_obv >= omv, as rationals
  bool paths_agree = false;  // the OMV's second path agrees with it (exact::LayerCertificate)
  double gap = 0;            // sum_obv - omv, nearest double
  double gap_relative = 0;   // gap / omv
  std::string omv_path;
  struct Estimated {
    int m = 0;
    double sum = 0;                 // sum of estimates
    double allowance = 0;           // sum of B(m) vol(O_j)
    bool above = false;             // sum >= OMV_exact
    bool above_with_bound = false;  // sum + allowance >= OMV_exact
  };
  std::vector<Estimated> estimated;
};

struct TreeCheck {
  std::string mesh, builder;
  bool containment_ok = false;
  double build_seconds = 0, certify_seconds = 0;
  double weighted_error = 0;
};

struct UpperBoundResult {
  std::vector<LayerBoundRow> layers;
  std::vector<TreeCheck> trees;
  bool all_exact_hold() const;
  bool all_estimated_hold_with_bound() const;
  double seconds = 0;
};

UpperBoundResult run_upper_bound_study(const UpperBoundConfig& config, const StatedBound& bound);

}  // namespace vobb::validate
