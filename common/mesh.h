// vobb::Mesh — an indexed triangle mesh in double precision.
//
// Vertices are stored exactly as read; faces index into `vertices`, counter-clockwise seen
// from outside for a solid. A Mesh makes no promise of solidity: see solidity.h.
#pragma once

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <array>
#include <cstdint>
#include <limits>
#include <string>
#include <vector>

namespace vobb {

using Vec3 = Eigen::Vector3d;
using Face = std::array<int32_t, 3>;

struct Aabb {
  Vec3 lo = Vec3::Constant(std::numeric_limits<double>::infinity());
  Vec3 hi = Vec3::Constant(-std::numeric_limits<double>::infinity());
  void extend(const Vec3& p) {
    lo = lo.cwiseMin(p);
    hi = hi.cwiseMax(p);
  }
  void extend(const Aabb& b) {
    lo = lo.cwiseMin(b.lo);
    hi = hi.cwiseMax(b.hi);
  }
  bool empty() const { return !(lo.array() <= hi.array()).all(); }
  // Closed: a point on the boundary is held.
  bool holds(const Vec3& p) const {
    return (lo.array() <= p.array()).all() && (p.array() <= hi.array()).all();
  }
  // Closed-interval overlap: boxes that only touch do overlap.
  bool overlaps(const Aabb& b) const {
    return (lo.array() <= b.hi.array()).all() && (b.lo.array() <= hi.array()).all();
  }
};

struct Mesh {
  std::vector<Vec3> vertices;
  std::vector<Face> faces;

  const Vec3& corner(size_t face, int k) const { return vertices[faces[face][k]]; }
  Aabb face_bounds(size_t face) const;
  Aabb bounds() const;
  // Twice the area, as the norm of the double cross product (not exact).
  double double_area(size_t face) const;
};

}  // namespace vobb
