// The outer volume of two boxes' intersection, vol((A ∩ B) \ X), from the polyhedron itself,
// in floating point: the pairwise term of the builder's overlap-aware objective (DESIGN §5;
// derivation in docs/derivations.md, "The overlap of two boxes").
//
// A ∩ B (the boxes' certified solids) is clipped as a convex cell and its outer volume taken
// by the signed prism decomposition over the faces in its column (common/cell_clip.h, the
// arithmetic that the exact clipping path runs in rationals).
//  - evaluate(): in interval arithmetic (CGAL::Interval_nt, under upward rounding); [lo, hi]
//    provably contains the exact value. Where the intervals cannot decide a sign (a mesh vertex
//    or a corner of one box on the other's plane), or a value comes out non-finite, the pair is
//    evaluated in rationals, and says so.
//  - estimate(): the same arithmetic in plain double, for the builder's loop: no enclosure, off
//    the exact value by round-off of the cell's volume (tested against rationals). Where
//    rounded signs contradict each other it returns the certified evaluation's midpoint.
// 0 exactly where the boxes are apart by a separating axis (tested in double with a margin
// that round-off cannot cross), or where either is flat. Functions of the pair alone, in
// either order; batches run in parallel (TBB), each pair as alone. Thread-safe.
// Precondition: the mesh is a solid (check_solidity passed) and outlives the solver; boxes are
// finite (box_defect is empty).
#pragma once

#include <string>
#include <utility>
#include <vector>

#include "common/bvh.h"
#include "common/exact_predicates.h"
#include "common/mesh.h"
#include "common/obb.h"

namespace vobb {

struct PolyOverlap {
  double lo = 0, hi = 0;   // lo <= vol((A ∩ B) \ X) <= hi
  double estimate = 0;     // the midpoint of [lo, hi] (the nearest double when exact)
  bool exact = false;      // computed in rationals: the intervals could not decide a sign
};

class PolyOverlapSolver {
 public:
  explicit PolyOverlapSolver(const Mesh& mesh);  // keeps a reference

  PolyOverlap evaluate(const Obb& a, const Obb& b) const;
  double estimate(const Obb& a, const Obb& b) const;
  std::vector<double> estimate(const std::vector<std::pair<Obb, Obb>>& pairs) const;
  // The exact value by the same arithmetic in rationals.
  Rational exact(const Obb& a, const Obb& b) const;

  // Whether the boxes are surely apart: some separating axis (of the 15) splits them with a
  // gap larger than round-off can close. False where they may meet.
  static bool apart(const Obb& a, const Obb& b);

 private:
  const Mesh& mesh_;
  AabbTree faces_;
};

}  // namespace vobb
