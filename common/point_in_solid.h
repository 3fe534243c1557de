// Exact point classification against a solid: inside, outside, or on its surface.
//
// A ray from the point along an axis is tested against the faces whose boxes it meets, with
// exact predicates, and the parity of its crossings decides. The ray starts at the point moved
// by an infinitesimal amount across its axis (simulation of simplicity), so that it never passes
// through an edge or a vertex nor runs in a face: every point, at any scale, is decided by one
// ray, with no retry. The faces through the point itself are found by a separate exact test.
// The ray along +x is cast where it meets at most 16 faces' boxes; otherwise the faces of 24
// rays (six directions, each start moved four ways) are counted in rounds with a doubling cap
// and the ray that meets the fewest is cast, so the cost is within a constant factor of the
// best of them. The derivation is in docs/derivations.md, "Locating a point".
// Precondition: the mesh is a solid (or, with `left_out`, the faces kept are closed surfaces).
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

// The same for a point known to lie on none of the faces kept (a vertex of one shell against
// the others, which are disjoint from it): the faces through p are not searched for, so only the
// ray's faces are visited. kInside or kOutside; kOnSurface only where the precondition fails
// and the ray shows it (it starts on a face it would cross).
Location locate_point_off_surface(const Mesh& mesh, const AabbTree& faces, const Vec3& p,
                                  const std::function<bool(int32_t)>& left_out);

// The number of rays locate_point chooses from.
constexpr int kLocateRays = 24;

// The same as locate_point by ray `ray` of them, 0 <= ray < kLocateRays, whatever faces it
// meets: every ray gives the same answer, which tests check ray by ray.
Location locate_point_by_ray(const Mesh& mesh, const AabbTree& faces, const Vec3& p, int ray);

}  // namespace vobb
