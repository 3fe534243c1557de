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
#include "fast/cubemap_bound.h"
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

  // The rigorous bound on |estimate - exact OBV| for one box at resolution m, for either
  // backend, and its parts (fast/cubemap_bound.h).
  double rigorous_bound(const Obb& box, int m) const;
  using Bounds = CubemapBounds;
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

}  // namespace vobb::validate
