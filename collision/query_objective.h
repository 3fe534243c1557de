// A collision-specific objective for the variational builder (an extension beyond the paper):
// instead of a box's outer volume, the number of recorded collider queries that may touch it.
//
// Why: in the collision experiment (collision_experiment.h) a node's box is tested exactly when
// a query opened the node's parent, so a tree's collider–box tests are, level by level, the
// arity times the queries that open the level above. The paper's OBV stands in for "queries
// that open the box" under colliders spread evenly through free space; a recorded stream of
// the application's own queries measures it directly. With `hits` as the builder's objective
// (builder/variational_builder.h, in place of the OBV estimate), each node's split minimises the
// queries that open its children, i.e. the tests of the level below on the recorded stream.
// A recorded query "hits" a box when the collider's outward-rounded bounds meet the box's
// outward-padded axis-aligned bounds (an index screen, part of the definition) and
// may_touch_box (contact_predicates.h), the traversal's own pruning test, accepts it. The
// screen's pad is chosen (see the .cpp) so that it drops only colliders that may_touch_box
// rejects: derived for spheres; for boxes with a wide margin over the face-normal case, not
// proven for every edge-edge case. So the count is the traversal's "opens this box" on the
// stream, tested equal to may_touch_box alone on tangent and near-tangent colliders of both
// kinds; a collider it could miss would lie within round-off of touching, one count off in a
// heuristic objective.
// Training on a stream and measuring on the same stream would measure the fit, not the tree:
// record the training stream with other seeds (or other sessions) than the runs reported.
//
// Query files (`vobb collide --record-queries`, `vobb build --queries`): JSON,
//   {"format": "vobb-queries", "version": 1, "mesh_sha256": "<hex>", "colliders": [C, ...]}
// with each collider C in the mesh's own frame, as [x, y, z, r] (a sphere: centre, radius) or
// [x, y, z, h0, h1, h2, a0x, a0y, a0z, a1x, a1y, a1z, a2x, a2y, a2z] (a box: centre, half
// extents, unit axes), doubles in shortest round-trip form. Written atomically.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include "collision/contact_predicates.h"
#include "common/bvh.h"
#include "common/mesh.h"
#include "common/obb.h"
#include "common/status.h"

namespace vobb::collision {

// Most colliders a recording or a build may hold: 5 million, about 1.6 GB of text if all are
// boxes (some 325 bytes each; spheres about 90), 136 bytes each in memory once read.
constexpr size_t kMaxRecordedQueries = 5000000;
// Largest query file read (2 GiB): the file is parsed whole, so reading one takes about
// 2.5 times its size in memory (text, parsed document, colliders) at the peak. A larger file
// is refused before it is read.
constexpr uint64_t kMaxQueryFileBytes = uint64_t(1) << 31;

struct QueryStream {
  std::string mesh_sha256;  // the mesh whose frame the colliders are in
  std::vector<Collider> colliders;
};

// What makes a collider unfit for a query file or the query objective, in words ("" when it is
// fit): a shape that is neither, coordinates not finite or beyond 2^240, a radius or half
// extent that is not a positive normal number up to 2^240, box axes box_defect refuses.
std::string collider_defect(const Collider& c);

Status write_query_stream(const QueryStream& stream, const std::string& path);
// One-line errors naming the file: not a query file, a collider that is not finite, a radius
// or half extent that is not positive and normal, box axes further from orthonormal than
// box_defect allows (common/obb.h), coordinates beyond 2^240, more than kMaxRecordedQueries
// colliders, a file over kMaxQueryFileBytes.
Status read_query_stream(const std::string& path, QueryStream* stream);

class QueryHitObjective {
 public:
  // Keeps copies of the colliders, prepared for `mesh` (its scale sets their round-off
  // margins, as in the experiment).
  QueryHitObjective(const Mesh& mesh, const std::vector<Collider>& colliders);
  size_t size() const { return colliders_.size(); }
  // The recorded queries that hit `box` (see above). `box` must pass box_defect.
  uint64_t hits(const Obb& box) const;
  // hits() of every box, as doubles, in parallel (TBB); may be called from several threads
  // at once. A function of the box alone, as the builder's ObvEstimate must be.
  std::vector<double> operator()(const std::vector<Obb>& boxes) const;

 private:
  std::vector<PreparedCollider> colliders_;
  AabbTree index_;    // over the colliders' bounds
  double reach_ = 0;  // max over colliders of |centre| + extent, plus the mesh's scale
};

}  // namespace vobb::collision
