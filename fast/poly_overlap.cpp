#include "fast/poly_overlap.h"

#include <tbb/parallel_for.h>

#include <cmath>

#include "common/cell_clip.h"
#include "common/mp_interval.h"
#include "fast/interval.h"

namespace vobb {

PolyOverlapSolver::PolyOverlapSolver(const Mesh& mesh)
    : mesh_(mesh), faces_(AabbTree::over_faces(mesh)) {}

Rational PolyOverlapSolver::exact(const Obb& box, const std::vector<Obb>& earlier) const {
  return cell_clip::shared_outside_volume<Rational>(mesh_, faces_, box,
                                                    boxes_meeting(box, earlier));
}

PolyOverlap PolyOverlapSolver::evaluate(const Obb& box, const std::vector<Obb>& earlier) const {
  PolyOverlap r;
  const std::vector<Obb> near = boxes_meeting(box, earlier);
  if (near.empty()) return r;  // [0, 0]: nothing shared
  try {
    CGAL::Protect_FPU_rounding<true> upward;
    const Interval v = cell_clip::shared_outside_volume<Interval>(mesh_, faces_, box, near);
    if (CGAL::is_finite(v)) {
      r.lo = std::max(v.inf(), 0.0);  // an outer volume is >= 0
      r.hi = v.sup();
      r.estimate = r.lo + 0.5 * (r.hi - r.lo);  // rounded upward, still within [lo, hi]
      return r;
    }
  } catch (const CGAL::Uncertain_conversion_exception&) {
  }
  // The same arithmetic in wider enclosures: ill-conditioned cuts (a box sheared 1e8 to one)
  // leave double intervals undecided where 128 or 256 bits still decide every sign. Taken
  // where the enclosure also rounds to one double, which is then the rationals' nearest.
  for (const mpfr_prec_t bits : {MpInterval::kPrec, MpInterval::kMaxPrec}) {
    try {
      const MpInterval::Precision precision(bits);
      const MpInterval v = cell_clip::shared_outside_volume<MpInterval>(mesh_, faces_, box, near);
      if (v.nearest(&r.estimate)) {
        r.lo = std::max(v.inf(), 0.0);
        r.hi = v.sup();
        r.enclosure_bits = static_cast<int>(bits);
        return r;
      }
    } catch (const Undecided&) {
    }
  }
  const Rational q = cell_clip::shared_outside_volume<Rational>(mesh_, faces_, box, near);
  enclose(q, &r.lo, &r.hi);
  r.estimate = to_double_nearest(q);
  r.exact = true;
  return r;
}

double PolyOverlapSolver::estimate(const Obb& box, const std::vector<Obb>& earlier) const {
  const std::vector<Obb> near = boxes_meeting(box, earlier);
  if (near.empty()) return 0;
  CGAL::Protect_FPU_rounding<true> nearest(CGAL_FE_TONEAREST);
  // The rounded signs as they are; where they contradict each other (a degenerate contact,
  // as where two tight boxes touch the same mesh vertex), again with values within 1e-10 of
  // their magnitude taken as 0: far above their rounding, and far below what moves the volume
  // by more than the cubemap's error.
  for (double snap : {0.0, 1e-10}) {
    try {
      const double v = cell_clip::shared_outside_volume<double>(mesh_, faces_, box, near, snap);
      if (std::isfinite(v)) return std::max(v, 0.0);
      return evaluate(box, earlier).estimate;  // an overflow: rationals
    } catch (const cell_clip::InconsistentSides&) {
    }
  }
  // Failing that (mesh vertices or faces on the planes of B and of earlier boxes, as where
  // tight boxes of a flat part share its planes), the same with every box grown by kGrow of its
  // half extents, which takes those planes off the mesh. The share only grows with B and with
  // each E, by at most vol(B' \ B) + sum vol(E' \ E) < 3.01 kGrow (V_B + sum V_E): 2.8e-9 of
  // the boxes' volumes, far below the cubemap's error that the search lives with.
  constexpr double kGrow = 0x1p-30;
  auto grown = [](Obb b) {
    b.half *= 1 + kGrow;
    return b;
  };
  std::vector<Obb> near_grown;
  for (const Obb& e : near) near_grown.push_back(grown(e));
  try {
    const double v =
        cell_clip::shared_outside_volume<double>(mesh_, faces_, grown(box), near_grown, 1e-10);
    if (std::isfinite(v)) return std::max(v, 0.0);
  } catch (const cell_clip::InconsistentSides&) {
  }
  return evaluate(box, earlier).estimate;
}

std::vector<double> PolyOverlapSolver::estimate(const std::vector<ShareQuery>& queries) const {
  std::vector<double> out(queries.size());
  tbb::parallel_for(size_t{0}, queries.size(),
                    [&](size_t i) { out[i] = estimate(queries[i].box, queries[i].earlier); });
  return out;
}

}  // namespace vobb
