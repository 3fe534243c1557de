// The polyhedral OBV solver: vol(B \ X) from the polyhedron itself, in floating point, with a
// certified enclosure (DESIGN §4b).
//
// It evaluates the box-frame clip formula (common/box_frame_clip.h, the one the exact clipping
// path runs in rationals) on the faces whose column meets the box, found through the faces'
// AABB tree. Each box is evaluated with its edge vectors relabelled (the same solid, the same
// exact OBV) for fewer faces: evaluate() takes the order whose column meets the fewest
// (box_clip::fewest_faces_column), estimate() the one whose column leaves the mesh's bounds
// soonest (box_clip::shortest_column), as a count would cost more than its faces' work.
//  - evaluate(): in interval arithmetic (CGAL::Interval_nt, under upward rounding). The result's
//    [lo, hi] provably contains the exact OBV of the box's certified solid. A branch the
//    intervals cannot decide at a mesh vertex (a vertex on a box plane, within round-off, as a
//    tight box's are) is decided exactly; one at a point a clip made sends the whole face to
//    rationals, enclosed; a box whose enclosure cannot be made tight (coordinates beyond
//    the doubles' safe range, a nearly flat box, a width above kMaxRelativeWidth of the box's
//    volume) is evaluated wholly in rationals, and says so. No interval is ever widened.
//  - Both run in units near the box's size (box_clip::frame_exponent), so a mesh and its boxes
//    scaled by 2^k give the results times 2^3k, bit for bit, while those stay normal; the
//    safe range bounds the mesh's reach beyond the box relative to its size, not its size.
//  - estimate(): the same formula in plain double, for the builder's loop (ObvEstimate), with
//    no enclosure: off the exact value by round-off, a median of at most 1e-12 of the box's
//    volume over boxes in general position (measured: about 1e-16, docs/BENCHMARKS.md). What a
//    user is shown comes from evaluate().
// Both are functions of the box alone. Batches run in parallel (TBB, as many threads as the
// caller's arena allows), each box on one thread exactly as alone, so the values do not depend
// on the thread count. Thread-safe: every call keeps its state on its own stack. Sets its own
// rounding mode per box, so it may be called under any floating-point environment.
// Precondition: the mesh is a solid (check_solidity passed) and outlives the solver; boxes
// are finite (box_defect is empty). A flat box (a zero half extent) has OBV 0, exactly.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include "common/bvh.h"
#include "common/exact_predicates.h"
#include "common/mesh.h"
#include "common/obb.h"

namespace vobb {
namespace box_clip {
struct Column;
}

// How one box's OBV was enclosed.
struct PolyObv {
  double lo = 0, hi = 0;    // lo <= exact OBV <= hi, both finite
  double estimate = 0;      // the midpoint of [lo, hi] (the nearest double when exact)
  int32_t faces = 0;        // faces visited (their column met the box's, by the filter)
  int32_t exact_signs = 0;  // signs at mesh vertices the intervals could not decide: rationals
  int32_t exact_faces = 0;  // faces with such a sign at a clipped point: the face in rationals
  bool exact_box = false;   // the whole box in rationals; `why` says what the intervals lacked
  std::string why;
  double rejected_width = 0;  // sent to rationals for its width: the width it had (else 0)
};

// The interval's width, relative to the box's volume, above which a box is evaluated in
// rationals instead. Ordinary boxes come out near 1e-13 (docs/BENCHMARKS.md).
inline constexpr double kMaxRelativeWidth = 1e-9;

class PolyObvSolver {
 public:
  explicit PolyObvSolver(const Mesh& mesh);  // keeps a reference

  PolyObv evaluate(const Obb& box) const;
  std::vector<PolyObv> evaluate(const std::vector<Obb>& boxes) const;

  double estimate(const Obb& box) const;
  std::vector<double> estimate(const std::vector<Obb>& boxes) const;

  // The exact OBV by the same formula in rationals (what evaluate() falls back to).
  Rational exact(const Obb& box) const;

  // For the tests: `damage` runs on every face term of the interval path before it is added
  // (a deliberately broken evaluator must be caught).
  using Damage = void (*)(double* lo, double* hi, int32_t face);
  void set_damage_for_tests(Damage d) { damage_ = d; }

 private:
  // The same, for a box as labelled and the faces of its column (evaluate and estimate first
  // choose its labelling).
  PolyObv evaluate_as(const box_clip::Column& column) const;
  double estimate_as(const Obb& box) const;

  const Mesh& mesh_;
  AabbTree faces_;
  Damage damage_ = nullptr;
};

}  // namespace vobb
