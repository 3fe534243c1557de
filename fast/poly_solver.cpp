#include "fast/poly_solver.h"

#include <CGAL/Interval_nt.h>
#include <tbb/parallel_for.h>

#include <cmath>
#include <optional>

#include "common/box_frame_clip.h"
#include "common/text_util.h"
#include "fast/interval.h"

namespace vobb {

namespace {

using box_clip::ColumnFilter;
using box_clip::Frame;
using box_clip::Point;

// Magnitudes of T-space coordinates and of R up to which no product or sum in face_term6 can
// overflow: a clipped vertex stays within 2^301, a doubled shadow area within 2^605, a term
// within 2^908 and a mesh's sum of terms far below 2^1023 (docs/derivations.md, "Interval
// range").
constexpr double kSafe = 0x1p300;

bool in_range(const Interval& x) { return x.inf() >= -kSafe && x.sup() <= kSafe; }

// The box's frame in rationals, made at the first question: the signs and faces that the
// intervals cannot decide are settled here.
class ExactBox {
 public:
  // In the units of the interval frame (scaled by 2^-e), so that its terms add to that sum.
  ExactBox(const Mesh& mesh, const Obb& box, int e) : mesh_(mesh), box_(box), e_(e) {}
  // sign(side T_axis(v) - bound R) for mesh vertex v, exactly.
  int sign(int32_t v, int axis, int side, int bound) {
    make();
    ++signs_;
    const Point<Rational> p = box_clip::to_frame(*frame_, mesh_.vertices[v], v);
    return sgn(Rational(side * p.x[axis] - bound * R_));
  }
  bool face_term6(const Face& face, Rational* term) {
    make();
    const Point<Rational> q[3] = {box_clip::to_frame(*frame_, mesh_.vertices[face[0]], face[0]),
                                  box_clip::to_frame(*frame_, mesh_.vertices[face[1]], face[1]),
                                  box_clip::to_frame(*frame_, mesh_.vertices[face[2]], face[2])};
    return box_clip::face_term6(q, R_, term);
  }
  int32_t signs() const { return signs_; }

 private:
  void make() {
    if (frame_) return;
    frame_ = box_clip::make_frame<Rational>(box_, e_);
    R_ = abs(frame_->det);
  }
  const Mesh& mesh_;
  const Obb& box_;
  int e_;
  std::optional<Frame<Rational>> frame_;
  Rational R_;
  int32_t signs_ = 0;
};

// The interval path's decider: the interval's sign where it decides; at a mesh vertex, the
// exact sign from the box's exact frame; at a point a clip made, an exception (the caller then
// evaluates the whole face exactly). The exact signs keep every branch the exact one, and the
// arithmetic stays in intervals, which then enclose the exact values.
struct ExactVertexSigns {
  ExactBox* exact;
  int operator()(const Point<Interval>& p, int axis, int side, int bound,
                 const Interval& val) const {
    int s;
    return decided_sign(val, &s) ? s : undecided(p, axis, side, bound);
  }
  int undecided(const Point<Interval>& p, int axis, int side, int bound) const {
    if (p.origin < 0) throw CGAL::Uncertain_conversion_exception("a clipped point on a box plane");
    return exact->sign(p.origin, axis, side, bound);
  }
};

// x * 2^(3e), the OBV in the box's own units from its value in units of 2^e, enclosed.
Interval unscaled(Interval x, int e) {
  const Interval p(std::ldexp(1.0, e));  // exact: e lies within [-1022, 242]
  return x * p * p * p;
}

PolyObv exact_result(const Rational& q, int32_t faces, std::string why) {
  PolyObv r;
  enclose(q, &r.lo, &r.hi);
  r.estimate = to_double_nearest(q);
  r.faces = faces;
  r.exact_box = true;
  r.why = std::move(why);
  return r;
}

}  // namespace

PolyObvSolver::PolyObvSolver(const Mesh& mesh) : mesh_(mesh), faces_(AabbTree::over_faces(mesh)) {}

PolyObv PolyObvSolver::evaluate(const Obb& box) const {
  return evaluate_as(box_clip::fewest_faces_column(box, mesh_, faces_));
}

double PolyObvSolver::estimate(const Obb& box) const {
  return estimate_as(box_clip::shortest_column(box, faces_.bounds()));
}

Rational PolyObvSolver::exact(const Obb& box) const {
  return box_clip::box_obv_rational(mesh_, faces_, box);
}

PolyObv PolyObvSolver::evaluate_as(const box_clip::Column& column) const {
  const Obb& box = column.box;
  const ColumnFilter filter(box);
  if (filter.flat()) return PolyObv{};  // no volume: [0, 0]
  Interval::Protector upward;
  const int e = box_clip::frame_exponent(box);
  const Frame<Interval> frame = box_clip::make_frame<Interval>(box, e);
  const Interval R = CGAL::abs(frame.det);  // in units of 2^e, as every value below
  if (!(R.inf() > 0) || !in_range(R)) {
    const double vol = volume(box);
    return exact_result(exact(box), 0,
                        R.inf() > 0 ? "coordinates beyond the intervals' safe range"
                                    : "a nearly flat box: its volume's enclosure holds 0 (volume " +
                                          format_double(vol) + ")");
  }
  ExactBox exact_box(mesh_, box, e);
  const ExactVertexSigns decide{&exact_box};
  Interval sum(0);
  int32_t visited = 0, exact_faces = 0;
  bool range_ok = true;
  for (const int32_t f : column.faces) {
    ++visited;
    if (!range_ok) continue;
    const Face& face = mesh_.faces[f];
    Point<Interval> tri[3];
    for (int i = 0; i < 3; ++i) {
      tri[i] = box_clip::to_frame(frame, mesh_.vertices[face[i]], face[i]);
      for (const Interval& x : tri[i].x) range_ok &= in_range(x);
    }
    if (!range_ok) continue;
    Interval term(0);
    try {
      if (!box_clip::face_term6(tri, R, &term, decide)) continue;
    } catch (const CGAL::Uncertain_conversion_exception&) {
      // A sign at a point that a clip made: the whole face in the box's exact frame.
      ++exact_faces;
      Rational t;
      if (!exact_box.face_term6(face, &t)) continue;
      double lo, hi;
      enclose(t, &lo, &hi);
      term = Interval(lo, hi);
    }
    if (damage_ != nullptr) {
      double lo = term.inf(), hi = term.sup();
      damage_(&lo, &hi, f);
      term = Interval(lo, hi);
    }
    sum += term;
  }
  if (!range_ok)
    return exact_result(exact(box), visited, "coordinates beyond the intervals' safe range");
  const Interval scaled_obv = box_clip::obv_from_sum6(sum, R);
  // The box's volume in the same units: 8 times the scaled half extents, in [8, 256).
  const double scaled_vol =
      8 * std::ldexp(box.half[0], -e) * std::ldexp(box.half[1], -e) * std::ldexp(box.half[2], -e);
  const double width = scaled_obv.sup() - scaled_obv.inf();
  if (!CGAL::is_finite(scaled_obv) || !(width <= kMaxRelativeWidth * scaled_vol)) {
    PolyObv r = exact_result(exact(box), visited,
                             "an ill-conditioned box: the interval is wider than " +
                                 format_double(kMaxRelativeWidth) + " of its volume");
    r.rejected_width = CGAL::is_finite(scaled_obv) ? std::ldexp(width, 3 * e) : INFINITY;
    return r;
  }
  const Interval obv = unscaled(scaled_obv, e);
  PolyObv r;
  // The exact OBV lies in [0, vol(B)] too; vol(B)'s double is not an enclosure, so only 0 clips.
  r.lo = std::max(obv.inf(), 0.0);
  r.hi = obv.sup();
  r.faces = visited;
  r.exact_faces = exact_faces;
  r.exact_signs = exact_box.signs();
  // Rounded upward, lo + (hi - lo) / 2 still lies in [lo, hi].
  r.estimate = r.lo + 0.5 * (r.hi - r.lo);
  return r;
}

double PolyObvSolver::estimate_as(const Obb& box) const {
  const ColumnFilter filter(box);
  if (filter.flat()) return 0;
  CGAL::Protect_FPU_rounding<true> nearest(CGAL_FE_TONEAREST);
  const int e = box_clip::frame_exponent(box);
  const Frame<double> frame = box_clip::make_frame<double>(box, e);  // in units of 2^e
  const double R = std::abs(frame.det);
  double sum = 0;
  if (R > 0) {
    try {
      faces_.visit_accepted(filter, [&](int32_t f) {
        const Point<double> tri[3] = {box_clip::to_frame(frame, mesh_.corner(f, 0)),
                                      box_clip::to_frame(frame, mesh_.corner(f, 1)),
                                      box_clip::to_frame(frame, mesh_.corner(f, 2))};
        double term;
        if (box_clip::face_term6(tri, R, &term)) sum += term;
      });
    } catch (const box_clip::PolygonOverflow&) {  // rounded signs contradicted each other
      return evaluate_as(box_clip::column_of(box, mesh_, faces_)).estimate;
    }
  }
  const double obv = R > 0 ? box_clip::obv_from_sum6(sum, R) : 0.0;
  // Beyond double's range (or a nearly flat box): the certified evaluation's midpoint.
  if (!std::isfinite(obv)) return evaluate_as(box_clip::column_of(box, mesh_, faces_)).estimate;
  return std::ldexp(obv, 3 * e);
}

std::vector<PolyObv> PolyObvSolver::evaluate(const std::vector<Obb>& boxes) const {
  std::vector<PolyObv> out(boxes.size());
  tbb::parallel_for(size_t{0}, boxes.size(), [&](size_t i) { out[i] = evaluate(boxes[i]); });
  return out;
}

std::vector<double> PolyObvSolver::estimate(const std::vector<Obb>& boxes) const {
  std::vector<double> out(boxes.size());
  tbb::parallel_for(size_t{0}, boxes.size(), [&](size_t i) { out[i] = estimate(boxes[i]); });
  return out;
}

}  // namespace vobb
