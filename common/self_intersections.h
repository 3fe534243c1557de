// Self-intersections of a triangle mesh: which pairs of faces meet beyond the vertices they
// share.
//
// Two faces intersect when their closed triangles have a point in common that is not a vertex
// both of them list (by index). Exact predicates (exact_predicates.h) decide every pair that is
// tested. Floating-point filters only choose which pairs to test. Each filter is conservative:
// it may pass a pair that does not meet, never drop one that does, with its rounding bounded in
// self_intersections.cpp. So the count equals that of testing every pair.
//
// Cost. Pairs are found in three disjoint groups, by how many vertices they share, so that a
// vertex shared by k faces (the apex of a finely divided cone, the centre of a fan-triangulated
// disc) costs about k log k tests, not the k^2 / 2 a box-overlap search gives, where every box
// holds that vertex; and an edge shared by c faces (non-manifold when c > 2) costs c log c:
//   - two (an edge): the faces listed on that edge, sorted exactly by the half-plane of their
//     third vertex around it (two meet exactly when those half-planes are the same);
//   - one (a vertex v): faces around v whose cones of directions from v may share a
//     direction: where no edge at v is non-manifold, those whose arcs' angles around the fan's
//     axis overlap (sorted intervals, so a cone's or dome's apex costs k log k even where its
//     rim zigzags); otherwise, or where more than a few arcs pass near that axis, through a
//     tree of boxes around each cone's arc on the unit sphere, skipping subtrees of faces that
//     share an edge with the query as well; each candidate pair's boxes are compared too;
//   - none: a tree over the faces, descended only into boxes that the query triangle may meet
//     (a separating-axis test) and, where a node's box is much looser than its faces (long
//     thin faces running diagonally), into a parallelepiped along their covariance axes that
//     it may meet; pruned at subtrees whose faces all list one of the query's vertices; each
//     pair left is tested in floating point (separating axes) before the exact test. (The
//     parallelepipeds are skipped where the largest coordinate lies outside [2^-500, 2^500],
//     the pair test where it exceeds 2^300.)
//     So a cylinder whose caps are fans around a vertex on their rims (a CAD export, or the
//     OFF reader's triangulation of a k-gon), where the box of each long thin cap face holds
//     the side faces along an arc of the rim, costs about k log k, not k^2.
// Meshes can still be made where the pairs that meet, or nearly meet, number n^2 (crossing
// sheets, close parallel sheets); then the count costs that much. Nor is the last group's
// cost bounded below n^2 in general: its boxes and parallelepipeds can both be loose, as
// around a node that mixes long thin faces of many directions. A caller that only needs to
// know that there are many can stop the search once it has found `stop_at` pairs: the pairs
// that meet then cost no more than that, while pairs that nearly meet (the filters pass them,
// the exact test says no) cannot be cut short.
#pragma once

#include <cstddef>
#include <vector>

#include "common/mesh.h"

namespace vobb {

struct SelfIntersectionSearch {
  size_t pairs = 0;         // pairs of faces that intersect
  size_t exact_tests = 0;   // pairs decided by exact predicates
  size_t filter_steps = 0;  // boxes, tree nodes, parallelepipeds, cones and triangle pairs
                            // looked at by the filters
  bool stopped = false;     // stop_at was reached: `pairs` (>= stop_at) is a lower bound
};

// Counts the intersecting pairs among the faces f with skip[f] == 0 (skip has one entry per
// face). Preconditions: every coordinate is finite, and every face not skipped has three
// distinct, non-collinear vertices (check_solidity skips degenerate faces). Faces listing the
// same three vertices count once as a pair. Deterministic, also where it stops early (the same
// pairs are found in the same order). stop_at = 0: count every pair.
SelfIntersectionSearch find_self_intersections(const Mesh& mesh, const std::vector<char>& skip,
                                               size_t stop_at = 0);

// Exact test of whether two non-degenerate faces of `mesh` meet anywhere other than at the
// vertices they share (by index). Faces listing the same three vertices meet.
bool faces_intersect(const Mesh& mesh, size_t f, size_t g);

}  // namespace vobb
