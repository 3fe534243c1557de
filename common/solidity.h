// Solidity checks: is a Mesh a solid in the sense of DESIGN §1?
//
// A solid is closed, 2-manifold (at edges and at vertices), consistently and outward oriented, free
// of self-intersections and of degenerate faces, with finite coordinates. Every geometric test uses
// exact predicates (exact_predicates.h), so the verdict does not depend on rounding. Nested shells
// are allowed (a solid with cavities) when each shell's orientation matches its nesting depth: an
// outer boundary faces out, a cavity's boundary faces into the cavity.
#pragma once

#include <cstddef>
#include <string>
#include <vector>

#include "common/exact_predicates.h"
#include "common/mesh.h"
#include "common/self_intersections.h"  // faces_intersect, the pair search check_solidity uses

namespace vobb {

enum class Defect {
  kEmpty,            // no faces
  kNonFinite,        // NaN or Inf coordinates (count: vertices)
  kHugeCoordinate,   // |coordinate| > kMaxCoordinate (count: vertices)
  kTinyExtent,       // the vertices span less than kMinExtent on every axis (count: 1)
  kDegenerateFace,   // repeated vertex or zero area (count: faces)
  kDuplicateFace,    // the same three vertices as an earlier face, either way round (count: faces)
  kNotClosed,        // border edges (count: edges)
  kNonManifoldEdge,  // edges with more than two faces (count: edges)
  kNonManifoldVertex,        // vertices whose faces form several fans, e.g. two cones tip to tip
  kInconsistentOrientation,  // edges whose two faces run the same way (count: edges)
  kSelfIntersection,         // pairs of faces that meet beyond their shared vertices (count: pairs)
  kInwardOriented,  // shells whose orientation does not match their nesting (count: shells)
};

const char* defect_name(Defect d);

// Largest accepted |coordinate|, 2^240 (about 1.8e72), and least accepted extent (the
// largest side of the bounding box), 2^-240 (about 5.7e-73). Between them every double
// computed downstream stays finite and normal: differences of coordinates are at most 2^241,
// triple products at most 6 (2^241)^3, box volumes (boxes reach at most 2^242: kMaxBoxReach,
// common/obb.h) at most (2^243)^3, and the baseline's second moments,
// a sum over at most 2^31 faces of area times squared distance, at most 2^31 (2^242)^2 (2^241)^2
// = 2^997 < 2^1024; at the small end extent^4 = 2^-960 is still above the least normal, 2^-1022.
constexpr double kMaxCoordinate = 0x1p240;
constexpr double kMinExtent = 0x1p-240;

// check_solidity stops counting self-intersecting pairs at this many: a mesh of crossing
// sheets can hold n^2 / 2 of them, and knowing that there are a million says as much about the
// mesh as the exact number (the cost of the count with and without the stop:
// docs/history/benchmarks-early.md, "Crossing sheets").
constexpr size_t kSelfIntersectionsCounted = 1'000'000;

struct DefectCount {
  Defect defect;
  size_t count;
  bool at_least = false;         // the count stopped there (self-intersections only)
  std::string describe() const;  // e.g. "not closed: 14 border edges"
};

struct SolidityReport {
  size_t vertices = 0;
  size_t faces = 0;
  size_t edges = 0;                  // distinct undirected edges
  size_t shells = 0;                 // edge-connected components of faces
  std::vector<DefectCount> defects;  // in the order the checks ran
  // The exact enclosed volume; meaningful only when `volume_known`.
  Rational volume;
  bool volume_known = false;

  bool solid() const { return defects.empty(); }
  // "solid", or the defects joined by "; ".
  std::string verdict() const;
};

// Runs every check that the mesh's state allows (geometric checks need finite coordinates,
// orientation checks need a closed, manifold, consistent mesh). Deterministic.
SolidityReport check_solidity(const Mesh& mesh);

// Edge-connected components of the faces (the shells of a solid), each a sorted face list,
// in order of their smallest face id.
std::vector<std::vector<int32_t>> face_components(const Mesh& mesh);

}  // namespace vobb
