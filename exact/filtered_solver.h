// Certify's filtered path (DESIGN §3): each box's OBV and each box's share of a layer's overlap
// term, enclosed in MpInterval arithmetic of 128 bits (or 256, asked for where a sum needs
// it); rationals only where the enclosure cannot decide a sign (a vertex exactly on a plane).
//
//   OBV(B)      by the box-frame clip formula (common/box_frame_clip.h) on MpInterval;
//   overlap_j = vol(S_j \ X), S_j = B_j ∩ (B_0 ∪ ... ∪ B_{j-1}), split into convex cells
//               against the earlier boxes that may meet B_j, each cell's vol(cell ∩ X) by the
//               signed prism decomposition over the faces whose column meets it, along the
//               axis direction whose column holds the fewest faces (the clipping path's
//               arithmetic, ClipSolver, on MpInterval; docs/derivations.md, "Certify's filter");
//   OMV(layer) = sum OBV - sum_j overlap_j.
// Only box j's earlier neighbours and the faces in its cells' columns are touched: no Nef
// polyhedron, and memory is one box's cells. Every result's enclosure contains the exact value
// that ClipSolver gives in rationals; `exact` says when a rational was computed instead (it is
// then that rational, enclosed). The same input gives the same enclosure on every thread.
// Precondition: the mesh is a solid and outlives the solver; boxes are finite.
#pragma once

#include <cstdint>
#include <vector>

#include "common/bvh.h"
#include "common/mesh.h"
#include "common/mp_interval.h"
#include "common/obb.h"
#include "exact/outer_volume.h"

namespace vobb::exact {

// A value with its enclosure; `exact`: it was computed in rationals, and `q` is the value.
struct Enclosed {
  MpInterval value;
  bool exact = false;
  Rational q;
  int bits = 128;  // the precision that enclosed it (unless exact)
};

class FilteredSolver {
 public:
  explicit FilteredSolver(const Mesh& mesh);  // keeps a reference
  // Each in `bits` (MpInterval::kPrec or kMaxPrec), or in kMaxPrec where a sign is undecided
  // in fewer, or in rationals where it is undecided there too.
  Enclosed obv(const Obb& box, mpfr_prec_t bits = MpInterval::kPrec) const;
  // Box j's share of the overlap term of `boxes`, with `earlier` its earlier_neighbours entry;
  // [0, 0] exactly when that is empty.
  Enclosed overlap_term(const std::vector<Obb>& boxes, size_t j,
                        const std::vector<int32_t>& earlier,
                        mpfr_prec_t bits = MpInterval::kPrec) const;
  const ClipSolver& rational() const { return clip_; }

  // For the tests: the filter's enclosures are collapsed onto their lower ends before they are
  // returned (a deliberately broken filter must be caught).
  void set_collapse_for_tests(bool on) { collapse_ = on; }

 private:
  const Mesh& mesh_;
  AabbTree faces_;
  ClipSolver clip_;
  bool collapse_ = false;
};

}  // namespace vobb::exact
