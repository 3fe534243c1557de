// Exact outer volumes (DESIGN §1, §3).
//
//   OBV(X, O) = vol(O \ X)             for one box;
//   OMV(X, Z) = vol((U_j O_j) \ X)     for a set of boxes, overlaps counted once.
//
// Boxes are their certified solids: the parallelepipeds of the stored doubles, exactly.
// Two independent paths compute the same rationals:
//  - ClipSolver (path b): everything rests on the signed prism decomposition of X along a
//    direction d: 1_X = sum_T sign(n_T . -d) 1[prism of T swept along d], so for a convex C,
//    vol(C ∩ X) = sum_T sign vol(C ∩ prism_T). OBV works in the box's own frame, where most
//    faces are closed forms (common/box_frame_clip.h, shared with fast/). OMV = sum OBV - sum vol(S
//    \ X) over convex cells S that split each box's part inside earlier boxes (half-space splits,
//    disjoint within one box; d = -z there, each prism a convex clip). Only faces whose column
//    meets a cell are visited; a layer whose boxes overlap nothing does no union work.
//  - NefSolver (path a): CGAL Nef polyhedra, (U_j O_j) - X, then the volume.
// Precondition for both: the mesh is a solid (check_solidity passed). Neither creates a GL
// context nor reads a file.
#pragma once

#include <memory>
#include <mutex>
#include <vector>

#include "common/bvh.h"
#include "common/exact_predicates.h"
#include "common/mesh.h"
#include "common/obb.h"

namespace vobb::exact {

class ConvexCell;

class ClipSolver {
 public:
  explicit ClipSolver(const Mesh& mesh);  // keeps a reference: the mesh must outlive it
  ~ClipSolver();
  Rational obv(const Obb& box) const;
  Rational omv(const std::vector<Obb>& boxes) const;
  // The same, given the exact sum of the boxes' OBV (certify has it already).
  Rational omv(const std::vector<Obb>& boxes, const Rational& sum_obv) const;
  // Per box: may it meet another box? By exact-conservative bounds: false means surely not.
  std::vector<char> may_overlap(const std::vector<Obb>& boxes) const;
  // vol(cell ∩ X).
  Rational inside_volume(const ConvexCell& cell) const;
  // Convex cells that make up, for each box j, S_j = B_j ∩ (B_1 ∪ ... ∪ B_{j-1}), its part
  // inside earlier boxes: the cells of one S_j are disjoint, while cells of different j may
  // overlap (a point in three boxes lies in S_2 and S_3). So their volumes sum to
  // sum_j vol(B_j) - vol(U_j B_j), the overlap term, not to the volume of the points covered
  // twice. Empty when no two boxes overlap.
  std::vector<ConvexCell> overlap_cells(const std::vector<Obb>& boxes) const;
  // Per box j, the boxes i < j (ascending) whose conservative bounds meet box j's; flat boxes
  // meet nothing.
  std::vector<std::vector<int32_t>> earlier_neighbours(const std::vector<Obb>& boxes) const;
  // The cells of S_j alone, splitting box j against `earlier` (its earlier_neighbours entry).
  std::vector<ConvexCell> shared_cells(const std::vector<Obb>& boxes, size_t j,
                                       const std::vector<int32_t>& earlier) const;
  // vol(S_j \ X): box j's share of the overlap term, over those cells.
  Rational overlap_term(const std::vector<Obb>& boxes, size_t j,
                        const std::vector<int32_t>& earlier) const;

 private:
  struct Prism;
  // Face f's prism, made at its first need (thread-safe): only inside_volume needs prisms, and
  // only where certify's filter falls back to rationals or a path asks for them.
  const Prism& prism(int32_t f) const;
  Prism make_prism(int32_t f) const;
  const Mesh& mesh_;
  AabbTree faces_;
  mutable std::vector<std::unique_ptr<Prism>> prisms_;  // per face; vertical faces: sign 0
  std::unique_ptr<std::once_flag[]> made_;
};

class NefSolver {
 public:
  explicit NefSolver(const Mesh& mesh);  // builds Nef(X) once (the costly part)
  ~NefSolver();
  Rational obv(const Obb& box) const;
  Rational omv(const std::vector<Obb>& boxes) const;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace vobb::exact
