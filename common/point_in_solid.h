// Exact point classification against a solid: inside, outside, or on its surface.
//
// A segment from the point to a far point is tested against every face whose box it may meet,
// with exact predicates; the parity of proper crossings decides. When the segment touches an
// edge or a vertex, or runs in a face's plane, another far point is tried (a fixed sequence,
// so the answer is deterministic). Precondition: the mesh is a solid.
#pragma once

#include <functional>

#include "common/bvh.h"
#include "common/mesh.h"

namespace vobb {

enum class Location { kOutside, kInside, kOnSurface };

// `faces` must be AabbTree::over_faces(mesh).
Location locate_point(const Mesh& mesh, const AabbTree& faces, const Vec3& p);

// The same against the faces for which `left_out` is false: those must be closed surfaces
// (the other shells of a mesh, say), and the point lies inside where an odd number of them
// enclose it.
Location locate_point(const Mesh& mesh, const AabbTree& faces, const Vec3& p,
                      const std::function<bool(int32_t)>& left_out);

// The same, where every face that `left_out` keeps lies within `region`: the far point is taken
// just beyond the region instead of the whole mesh, so the segment passes only faces near it.
Location locate_point(const Mesh& mesh, const AabbTree& faces, const Vec3& p,
                      const std::function<bool(int32_t)>& left_out, const Aabb& region);

}  // namespace vobb
