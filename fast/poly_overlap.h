// What a box shares with earlier boxes outside the solid, vol((B ∩ (E_0 ∪ ... ∪ E_{k-1})) \ X),
// from the polyhedron itself, in floating point: the builder's overlap-aware objective (DESIGN
// §5; derivation in docs/derivations.md, "Shared outer volume"). With one earlier box it is the
// pair's overlap term vol((B ∩ E) \ X); a layer's OMV is
//   OMV = sum_j OBV(B_j) - sum_j share(B_j; B_0 .. B_{j-1}),
// exactly, with no inclusion-exclusion truncated.
//
// B is split against the earlier boxes into disjoint convex cells, and each cell's outer volume
// taken by the signed prism decomposition over the faces in its column (common/cell_clip.h,
// the arithmetic that the exact clipping path runs in rationals).
//  - evaluate(): in interval arithmetic (CGAL::Interval_nt, under upward rounding); [lo, hi]
//    provably contains the exact value. Where the intervals cannot decide a sign or a value
//    comes out non-finite, the same in MPFR intervals of 128, then 256 bits (common/
//    mp_interval.h), taken where one decides every sign and rounds to one double; where neither
//    does (a mesh vertex or a box corner on a plane), in rationals. It says which.
//  - estimate(): in plain double, for the builder's loop: no enclosure. Where the rounded signs
//    agree, off the exact value by round-off of the cells' volumes alone, within 1e-9 of B's
//    volume (about 1e-15 on the tests' boxes; the cubemap's error, which the search lives with,
//    is about 1e-4 of a box's volume). Where rounded signs contradict each other it takes
//    values within 1e-10 of their magnitude as 0; failing that (mesh vertices and faces on the
//    planes of B and of earlier boxes, as on a flat part), the same with every box grown by
//    2^-30 of its half extents, at most 3.01 2^-30 of the boxes' volumes above the exact value;
//    and failing that, or where a value overflows, the certified evaluation's estimate.
// 0 exactly where no earlier box meets B by a separating-axis test in double with a margin
// that round-off cannot cross, or where B is flat. Functions of their arguments alone (the
// earlier boxes in the order given); batches run in parallel (TBB), each as alone. Thread-safe.
// Precondition: the mesh is a solid (check_solidity passed) and outlives the solver; boxes are
// finite (box_defect is empty).
#pragma once

#include <utility>
#include <vector>

#include "common/bvh.h"
#include "common/exact_predicates.h"
#include "common/mesh.h"
#include "common/obb.h"

namespace vobb {

struct PolyOverlap {
  double lo = 0, hi = 0;   // lo <= the exact value <= hi
  double estimate = 0;     // the midpoint of [lo, hi]; the exact value's nearest double when
                           // enclosure_bits or exact is set
  int enclosure_bits = 0;  // 128 or 256: an MPFR enclosure decided it (double intervals did not)
  bool exact = false;      // computed in rationals: no enclosure decided it (see evaluate())
};

class PolyOverlapSolver {
 public:
  explicit PolyOverlapSolver(const Mesh& mesh);  // keeps a reference

  PolyOverlap evaluate(const Obb& box, const std::vector<Obb>& earlier) const;
  double estimate(const Obb& box, const std::vector<Obb>& earlier) const;
  std::vector<double> estimate(const std::vector<ShareQuery>& queries) const;
  // The exact value by the same arithmetic in rationals.
  Rational exact(const Obb& box, const std::vector<Obb>& earlier) const;

 private:
  const Mesh& mesh_;
  AabbTree faces_;
};

}  // namespace vobb
