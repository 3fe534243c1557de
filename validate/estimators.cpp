#include "validate/estimators.h"
#include "common/stopwatch.h"

#include <chrono>
#include <cmath>
#include <limits>

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

namespace {

// The round-off term (header): 32 eps of the volume, plus 2^-1068 for underflow: where the
// volume scale or the products with it are subnormal, each of their roughly 20 operations may
// lose half a subnormal step (2^-1075) instead of a relative eps, and a volume that underflows
// to 0 (a flat plan) was below a few steps.
double roundoff_term(const Obb& box) {
  return 32 * std::numeric_limits<double>::epsilon() * volume(box) + 0x1p-1068;
}

}  // namespace

double range_bound(const Obb& box, double estimate) {
  // U: Hadamard's inequality, |det A| <= ||a0|| ||a1|| ||a2||, in double, carried as a mantissa
  // and a power of two so that no intermediate product underflows (a box may be 2^241 long and
  // 2^-1022 thin). Each norm is within 2 eps of its value (the dot product's roundings, halved
  // by the square root, and the root's own), each h_k ||a_k|| within one more (up to eps where
  // it is subnormal: h_k >= 2^-1022 by box_defect and ||a_k|| >= 1/2), and the 3 mantissa
  // products one eps each: under 12 eps, raised by 32 eps. The one final scaling, U - E and
  // the larger of the two lose at most one rounding each where the result is normal (the
  // factor 1 + 4 eps) and 2^-1075 absolutely where it underflows (2^-1068 covers them).
  constexpr double eps = std::numeric_limits<double>::epsilon();
  double mantissa = 8 * (1 + 32 * eps);
  int exponent = 0;
  for (int k = 0; k < 3; ++k) {
    int e = 0;
    mantissa *= std::frexp(box.half[k] * box.axes[k].norm(), &e);  // in [1/2, 1), or 0
    exponent += e;
  }
  const double u = std::ldexp(mantissa, exponent);
  return std::max(std::abs(estimate), std::abs(u - estimate)) * (1 + 4 * eps) + 0x1p-1068;
}

EstimatorSet::Bounds EstimatorSet::bounds(const Obb& box, int m) const {
  const BoxPlan plan = planner_.plan(box, m);
  return {resolution_bound(plan, m), gl_deviation_bound(plan, m), cpu_rounding_bound(plan, m), roundoff_term(box),
          plan.unresolved};
}

double EstimatorSet::rigorous_bound(const Obb& box, int m) const { return bounds(box, m).rigorous(); }

double EstimatorSet::bound(Backend backend, const Obb& box, int m, bool* unresolved) const {
  const BoxPlan plan = planner_.plan(box, m);
  if (unresolved) *unresolved = plan.unresolved;
  Bounds b;
  b.resolution = resolution_bound(plan, m);
  b.roundoff = roundoff_term(box);
  if (backend == Backend::kCpu) {
    b.cpu_rounding = cpu_rounding_bound(plan, m);
    return b.cpu_rigorous();
  }
  // gl_deviation_bound includes the twin's round-off, except where GL runs the twin's code
  // and it is 0 (Bounds::rigorous).
  b.deviation = gl_deviation_bound(plan, m);
  if (b.deviation == 0) b.cpu_rounding = cpu_rounding_bound(plan, m);
  return b.rigorous();
}

Status EstimatorSet::check_request(Backend backend, const Obb& box, int m) const {
  if (m < 1) return Status::error("cubemap resolution m = " + std::to_string(m) + " refused: m must be at least 1");
  if (backend == Backend::kGl && !gl_) return Status::error("GL estimator unavailable: " + gl_status_);
  if (backend == Backend::kGl && m > gl_->max_m())
    return Status::error("cubemap resolution m = " + std::to_string(m) + " refused: beyond the GL limit " +
                         std::to_string(gl_->max_m()) + " of renderer " + gl_->renderer());
  const std::string defect = box_defect(box);
  if (!defect.empty()) return Status::error("box refused: " + defect);
  return Status::ok();
}

Location EstimatorSet::centre_location(const Obb& box) const {
  // Located directly: a flat or unresolved plan does not locate the centre.
  return locate_point(planner_.mesh(), planner_.face_tree(), box.center);
}

}  // namespace vobb::validate
