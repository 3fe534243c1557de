#include "validate/estimators.h"

#include <chrono>
#include <cmath>
#include <limits>

#include "common/stopwatch.h"

namespace vobb::validate {
const char* to_string(Backend b) { return b == Backend::kCpu ? "cpu" : "gl"; }

EstimatorSet::EstimatorSet(const Mesh& mesh, bool want_gl, EstimatePerturbation perturb)
    : mesh_(mesh), planner_(mesh), cpu_(mesh), perturb_(std::move(perturb)) {
  if (!want_gl) {
    gl_status_ = "GL not requested";
    return;
  }
  const Status s = GlObvEstimator::create(mesh, &gl_);
  if (!s) gl_status_ = s.message();
}

EstimatorSet::~EstimatorSet() = default;

std::string EstimatorSet::renderer() const { return gl_ ? gl_->renderer() : std::string("none"); }
int EstimatorSet::gl_max_m() const { return gl_ ? gl_->max_m() : 0; }

std::vector<double> EstimatorSet::estimate(Backend backend, const std::vector<Obb>& boxes, int m,
                                           std::vector<double>* seconds) {
  VOBB_ASSERT(m >= 1, "cubemap resolution m >= 1");
  std::vector<double> out;
  seconds->assign(boxes.size(), 0.0);
  if (backend == Backend::kCpu) {
    out.reserve(boxes.size());
    for (size_t i = 0; i < boxes.size(); ++i) {
      const auto t0 = std::chrono::steady_clock::now();
      out.push_back(cpu_.estimate(boxes[i], m));
      (*seconds)[i] = seconds_since(t0);
    }
  } else {
    VOBB_ASSERT(gl_ != nullptr && m <= gl_->max_m(), "GL estimator present and m within its limit");
    const auto t0 = std::chrono::steady_clock::now();
    out = gl_->estimate(boxes, m);
    const double each = boxes.empty() ? 0.0 : seconds_since(t0) / boxes.size();
    seconds->assign(boxes.size(), each);
  }
  if (perturb_)
    for (size_t i = 0; i < boxes.size(); ++i) out[i] = perturb_(out[i], boxes[i], m);
  return out;
}

EstimatorSet::Bounds EstimatorSet::bounds(const Obb& box, int m) const {
  return cubemap_bounds(planner_, box, m);
}

double EstimatorSet::rigorous_bound(const Obb& box, int m) const {
  return bounds(box, m).rigorous();
}

double EstimatorSet::bound(Backend backend, const Obb& box, int m, bool* unresolved) const {
  return cubemap_bound(planner_, backend == Backend::kGl, box, m, unresolved);
}

Status EstimatorSet::check_request(Backend backend, const Obb& box, int m) const {
  if (m < 1)
    return Status::error("cubemap resolution m = " + std::to_string(m) +
                         " refused: m must be at least 1");
  if (backend == Backend::kGl && !gl_)
    return Status::error("GL estimator unavailable: " + gl_status_);
  if (backend == Backend::kGl && m > gl_->max_m())
    return Status::error("cubemap resolution m = " + std::to_string(m) +
                         " refused: beyond the GL limit " + std::to_string(gl_->max_m()) +
                         " of renderer " + gl_->renderer());
  const std::string defect = box_defect(box);
  if (!defect.empty()) return Status::error("box refused: " + defect);
  return Status::ok();
}

Location EstimatorSet::centre_location(const Obb& box) const {
  // Located directly: a flat or unresolved plan does not locate the centre.
  return locate_point(planner_.mesh(), planner_.face_tree(), box.center);
}

}  // namespace vobb::validate
