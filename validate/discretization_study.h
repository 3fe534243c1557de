// The discretization study (DESIGN §6): cubemap estimates against exact OBV over seeded
// box corpora on real meshes, for every m and both backends; error statistics per m, the
// fitted convergence rate, time per evaluation; a stated error bound B(m) fitted on one corpus
// and checked on a held-out one; the Richardson a-posteriori estimate from m and 2m and how
// often it covers the true error; and the exact solvers' times for the error-against-time plot.
//
// The reference for every box is the polyhedral solver's certified interval [lo, hi] of its exact
// OBV V (fast/poly_solver.h); on a subsample (rational_boxes_per_size per mesh and size) the
// exact rational is computed too and checked to lie inside it.
// Errors: for a box O and estimate E, the certified error max(|E - lo|, |E - hi|) >= |E - V|
//   stands for the absolute error |E - V| (mesh units^3): it exceeds it by at most the interval's
//   width, about 1e-13 vol(O) (so every coverage figure below is conservative); relative error
//   is that over V (boxes with V > 0), normalised error over vol(O), the scale-free quantity
//   that B(m) bounds.
// The stated bound (see fit_stated_bound): B(m) = C m^-p vol(O), fitted on the fit corpus so
// that a fraction 1 - alpha/2 of its normalised errors lie below it at every m, and stated at
// level alpha: at most a fraction alpha of held-out (box, m, backend) errors may exceed it.
#pragma once

#include <cmath>
#include <functional>
#include <string>
#include <vector>

#include "common/mesh.h"
#include "common/obb.h"
#include "common/point_in_solid.h"
#include "validate/box_corpus.h"
#include "validate/estimators.h"

namespace vobb::validate {

struct NamedMesh {
  std::string name;
  const Mesh* mesh = nullptr;  // not owned
};

struct DiscretizationConfig {
  std::vector<NamedMesh> fit_meshes;       // B(m) is fitted on these
  std::vector<NamedMesh> held_out_meshes;  // and checked on these, with other seeds
  int boxes_per_size = 8;                  // per mesh and box size
  uint64_t fit_seed = 1000, held_out_seed = 2000;
  std::vector<int> ms = {4, 8, 16, 32, 64, 128, 256};
  int rational_boxes_per_size = 2;  // exact rational by clipping, checked inside the interval
  // R(m) and the GL estimator on the first this many boxes per mesh and size (the CPU twin on
  // every box): R(m)'s texel plans and GL cost most of the study.
  int detail_boxes_per_size = 1 << 30;
  int nef_boxes_per_size = 2;  // timed by Nef (and checked equal to clipping) on the first fit mesh
  double alpha = 0.05;         // stated violation level of B(m)
  bool want_gl = true;
  EstimatePerturbation perturb;  // tests only
  std::function<void(const std::string&)> progress;
};

struct StudySample {
  std::string mesh;
  bool held_out = false;
  BoxSize size = BoxSize::kLeaf;
  int index = 0;  // within (mesh, size)
  Location centre = Location::kOutside;
  Obb box;
  double box_volume = 0;
  double exact =
      0;  // the reference: the interval's midpoint (the rational's nearest double where computed)
  double lo = 0, hi = 0;    // the certified interval of the exact OBV
  double poly_seconds = 0;  // the polyhedral solver's time for this box (batch time amortised)
  int rational = 0;  // the exact rational: 0 not computed, 1 inside [lo, hi], -1 outside (a defect)
};

struct StudyEval {
  size_t sample = 0;
  Backend backend = Backend::kCpu;
  int m = 0;
  double estimate = 0;
  double seconds = 0;  // per evaluation
  // On the detail subsample only (NaN elsewhere): the backend's rigorous bound R(m)
  // (CubemapBounds::cpu_rigorous for the CPU twin, rigorous for GL), and gl_deviation_bound +
  // round-off, the allowed |GL - CPU|.
  double rigorous = NAN;
  double deviation = NAN;
  bool has_rigorous() const { return !std::isnan(rigorous); }
  double abs_error(const StudySample& s) const;  // certified: max(|E - lo|, |E - hi|)
};

struct ErrorStats {  // over a set of evaluations
  size_t n = 0, n_rel = 0;
  double rel_median = 0, rel_p95 = 0, rel_max = 0;
  double abs_median = 0, abs_p95 = 0, abs_max = 0;
  double norm_median = 0, norm_p95 = 0, norm_max = 0;
  double seconds_mean = 0;
  double rigorous_norm_median = 0;  // rigorous bound / vol(O), median (where computed)
  size_t rigorous_violations = 0;   // evaluations outside the rigorous bound (where computed)
  size_t non_finite = 0;
};

struct PerMStats {
  Backend backend;
  int m;
  ErrorStats all;
};

// Least-squares slope of log(statistic) against log(m).
struct RateFit {
  Backend backend;
  double median_slope = 0, p95_slope = 0, max_slope = 0;
};

struct StatedBound {
  double alpha = 0.05;      // stated level: the largest held-out violation rate allowed
  double quantile = 0.975;  // fitted quantile of the normalised errors (1 - alpha/2)
  double c = 0, p = 0;      // B(m) = c m^-p vol(O)
  std::vector<std::pair<int, double>> fitted_quantiles;  // (m, quantile of the fit corpus)
  size_t fit_n = 0, fit_violations = 0;
  size_t held_out_n = 0, held_out_violations = 0;
  std::vector<std::pair<int, double>> held_out_rate_per_m;
  double per_volume(int m) const;  // c m^-p
  double held_out_rate() const {
    return held_out_n ? double(held_out_violations) / held_out_n : 0.0;
  }
  bool holds() const { return held_out_rate() <= alpha; }
};

struct RichardsonRow {
  Backend backend;
  int m;  // pair (m, 2m); the estimate judged is the one at 2m
  size_t n = 0;
  double cover_third = 0, cover_one = 0,
         cover_two = 0;  // fraction with |E(2m)-V| <= k |E(m)-E(2m)|
};

struct ExactTiming {
  std::string solver;  // "clip" or "nef"
  size_t n = 0;
  double mean_seconds = 0;
  std::string note;
};

struct DiscretizationResult {
  std::vector<StudySample> samples;
  std::vector<StudyEval> evals;
  std::vector<PerMStats> per_m;
  // Per backend, box size and centre class, at m = 32 (when studied).
  struct ClassRow {
    Backend backend;
    BoxSize size;
    Location centre;
    ErrorStats stats;
  };
  std::vector<ClassRow> per_class_m32;
  std::vector<RateFit> rates;
  StatedBound bound;
  std::vector<RichardsonRow> richardson;
  std::vector<ExactTiming> exact_timings;
  bool nef_agrees = true;  // Nef == clipping on every box timed by both
  size_t nef_compared = 0;
  size_t rational_checked = 0, rational_outside = 0;  // rationals outside their interval: a defect
  double poly_certified_rel_median =
      0;                          // median over boxes with V > 0 of the interval's width / lo
  std::vector<Backend> backends;  // those that ran
  std::string gl_note;            // why GL did not run, or the renderer
  double seconds = 0;
};

DiscretizationResult run_discretization_study(const DiscretizationConfig& config);

// Statistics of the evaluations selected by `keep`.
ErrorStats error_stats(const DiscretizationResult& r,
                       const std::function<bool(const StudyEval&)>& keep);

// Whether an evaluation counts toward B(m): the CPU twin's, one estimate per box and m. GL's
// estimates of the same boxes lie within its float bound of the twin's (a check of its own),
// and counted too they would count those boxes twice.
inline bool counts_toward_bound(const StudyEval& e) { return e.backend == Backend::kCpu; }

// Fits B(m) on the fit corpus's evaluations that count toward it, and counts violations on
// both corpora's.
StatedBound fit_stated_bound(const DiscretizationResult& r, double alpha);

double quantile(std::vector<double> v, double q);  // linear interpolation; v non-empty
double median(std::vector<double> v);
double lsq_slope(const std::vector<double>& x, const std::vector<double>& y);

}  // namespace vobb::validate
