// The cubemap estimators as the validation suite drives them: the CPU twin and the GL
// estimator over one mesh, each evaluation timed, with the rigorous per-box error allowance
// and an optional perturbation of every estimate (the tests' injection point).
//
// The perturbation exists only so that a test can break the estimator on purpose and show
// that the suite fails (tests/validate/validation_suite_test.cpp); a run from the command line
// never sets it. It receives the estimate, the box and m, and returns the value the suite sees.
#pragma once

#include <algorithm>
#include <functional>
#include <memory>
#include <string>
#include <vector>

#include "common/mesh.h"
#include "common/obb.h"
#include "common/status.h"
#include "fast/cpu_estimator.h"
#include "fast/gl_estimator.h"
#include "fast/texel_plan.h"

namespace vobb::validate {

using EstimatePerturbation = std::function<double(double estimate, const Obb& box, int m)>;

enum class Backend { kCpu, kGl };
const char* to_string(Backend b);

class EstimatorSet {
 public:
  // Keeps a reference to `mesh`. `want_gl`: try to make a GL context; when that fails,
  // has_gl() is false and gl_status() says why in one line.
  EstimatorSet(const Mesh& mesh, bool want_gl, EstimatePerturbation perturb = {});
  ~EstimatorSet();

  bool has_gl() const { return gl_ != nullptr; }
  const std::string& gl_status() const { return gl_status_; }
  std::string renderer() const;
  int gl_max_m() const;

  // Estimates of each box at resolution m (1 <= m, and m <= gl_max_m() for GL), perturbed when
  // a perturbation is set. `seconds` gets the time per evaluation: measured per box for the
  // CPU twin, the batch's time divided by the count for GL (it evaluates the batch at once).
  std::vector<double> estimate(Backend backend, const std::vector<Obb>& boxes, int m,
                               std::vector<double>* seconds);

  // A rigorous bound on |estimate - exact OBV| for one box at resolution m, for either backend:
  // resolution_bound (texel_plan.h) plus gl_deviation_bound (or cpu_rounding_bound where GL
  // runs the twin's code) plus 32 eps vol(O) + 2^-1068. For the CPU
  // twin the float bound is kept too: it bounds the same sums' round-off in float32, so it
  // covers the twin's double round-off of the texel sum (2^29 times smaller). The last term is
  // the round-off outside the texel sum, which both bounds leave out (it matters where they
  // are 0, e.g. a box that meets no face): the volume scale h0 h1 h2 |det[a0 a1 a2]| (the
  // determinant's 5 roundings per term, its sum of |terms| at most sqrt(3) |det| for axes
  // orthonormal to round-off, then 3 products: under 9 eps), the products with the constant
  // and the texel weight (2 eps), and the exact value's rounding to the nearest double
  // (eps/2): under 12 eps, taken as 32 eps for margin; plus 2^-1068 where these underflow
  // (each operation then loses up to 2^-1075 absolutely). The plan's rounding of the
  // faces into the box's frame is in resolution_bound (texel_plan.h), which widens its texel
  // cones by it.
  double rigorous_bound(const Obb& box, int m) const;
  // The parts: resolution_bound, gl_deviation_bound (the bound on |GL - CPU twin|),
  // cpu_rounding_bound (on |CPU twin - exact evaluation of the plan|) and the round-off term.
  // rigorous() holds for either backend; cpu_rigorous() is the tighter one for the CPU twin
  // alone (its double round-off instead of the float deviation).
  struct Bounds {
    double resolution = 0, deviation = 0, cpu_rounding = 0, roundoff = 0;
    bool unresolved = false;  // the plan could not hold the box (BoxPlan::unresolved)
    // deviation bounds |GL - CPU twin| and includes cpu_rounding; where GL runs the twin's own
    // code (gl_evaluates_in_float false) it is 0, and the twin's round-off is what remains.
    double rigorous() const { return resolution + std::max(deviation, cpu_rounding) + roundoff; }
    double cpu_rigorous() const { return resolution + cpu_rounding + roundoff; }
  };
  Bounds bounds(const Obb& box, int m) const;
  // The bound for one backend's estimate (rigorous() for GL, cpu_rigorous() for the CPU
  // twin), computing only the round-off part that backend needs; `unresolved` as above.
  double bound(Backend backend, const Obb& box, int m, bool* unresolved = nullptr) const;
  // The suite's front door for one estimate: refuses, in one line, what the estimators take
  // as a programmer error (m < 1, m beyond the GL limit) and every box that box files refuse
  // (box_defect, common/obb.h: non-finite, negative or subnormal half extents, axes not
  // orthonormal, out of range) instead of aborting or estimating nonsense.
  Status check_request(Backend backend, const Obb& box, int m) const;
  // Where the centre of the box lies (the plan's exact classification).
  Location centre_location(const Obb& box) const;

 private:
  const Mesh& mesh_;
  BoxPlanner planner_;
  CpuObvEstimator cpu_;
  std::unique_ptr<GlObvEstimator> gl_;
  std::string gl_status_;
  EstimatePerturbation perturb_;
};

// A bound on |estimate - exact OBV| from the OBV's range alone: the exact OBV lies in [0, V*],
// V* = 8 h0 h1 h2 |det[a0 a1 a2]| the parallelepiped's exact volume, so |E - OBV| <=
// max(|E|, |U - E|) for any U >= V*. EstimatorSet's rigorous bound can exceed the box's volume
// (at small m each texel may be off by its whole pyramid; an unresolved plan); `vobb obv`
// reports the smaller of the two. Holds for every box that box_defect accepts (common/obb.h),
// and for an estimate outside [0, V*] too.
double range_bound(const Obb& box, double estimate);

}  // namespace vobb::validate
