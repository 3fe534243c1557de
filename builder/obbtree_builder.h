// The OBB-Tree baseline builder (Gottschalk, Lin and Manocha 1996, as RAPID 2.01 builds it).
//
// For each node: axes are the eigenvectors of the area-weighted covariance of its triangles
// (the second moments of the uniform distribution over each triangle, not over the hull),
// major axis first; the box is the tight fit of the node's vertices along those axes
// (fit_obb: exactly conservative). A node is split by triangle centroid at the area-weighted
// mean along its major axis; when one side would be empty, at the median instead.
// For arity k > 2, the node's group with the most faces is split that way until there are k
// groups or none can be split. Splitting stops at `depth` or at single-face nodes.
// Deterministic: ties are broken by face id.
#pragma once

#include <array>
#include <vector>

#include "common/mesh.h"
#include "common/tree.h"

namespace vobb {

struct ObbTreeOptions {
  int depth = 8;  // >= 0: the root alone is depth 0
  int arity = 2;  // >= 2
};

// Precondition: the mesh is a solid (check_solidity passed) or at least has finite
// coordinates and no degenerate faces. Fills every field but mesh_sha256.
Tree build_obbtree(const Mesh& mesh, const ObbTreeOptions& options);

// The baseline's split of one node's faces into at most `arity` groups (the rule above), each
// sorted by face id. Fewer groups when the faces run out.
std::vector<std::vector<int32_t>> split_into_groups(const Mesh& mesh,
                                                    const std::vector<int32_t>& faces, int arity);

// Area-weighted covariance axes of the given faces: major axis first, right-handed, each
// with its largest-magnitude component positive (axes 0 and 1) so that the result is unique.
std::array<Vec3, 3> covariance_axes(const Mesh& mesh, const std::vector<int32_t>& faces);

}  // namespace vobb
