#include "common/mesh.h"

namespace vobb {

Aabb Mesh::face_bounds(size_t face) const {
  Aabb b;
  for (int k = 0; k < 3; ++k) b.extend(corner(face, k));
  return b;
}

Aabb Mesh::bounds() const {
  Aabb b;
  for (const Vec3& v : vertices) b.extend(v);
  return b;
}

double Mesh::double_area(size_t face) const {
  const Vec3& a = corner(face, 0);
  return (corner(face, 1) - a).cross(corner(face, 2) - a).norm();
}

}  // namespace vobb
