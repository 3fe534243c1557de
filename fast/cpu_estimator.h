// The CPU twin of the cubemap OBV estimator (cubemap.h): the same texel directions, ray-cast in
// double. It is the reference for the GL estimator and a backend of its own (--backend cpu).
//
// Per box only the faces that can meet the box are cast against (culling by the face AABB
// tree, then by the face's box-normalized bounds); each face is tested only on the texels its
// projection covers. 1_X(centre) comes from an exact point classification; a centre exactly on
// the surface instead counts, per ray, the crossings beyond the box (all faces, no culling),
// which is the inside-ness at the box boundary without reference to the centre.
#pragma once

#include <vector>

#include "common/bvh.h"
#include "common/mesh.h"
#include "common/obb.h"

namespace vobb {

class CpuObvEstimator {
 public:
  explicit CpuObvEstimator(const Mesh& mesh);  // keeps a reference
  // OBV estimate of each box at resolution m >= 1, in world volume units.
  std::vector<double> estimate(const std::vector<Obb>& boxes, int m) const;
  double estimate(const Obb& box, int m) const;
  // For the culling ablation benchmark: cast against every face.
  void set_culling(bool on) { culling_ = on; }
  // Faces cast against in the last estimate() call (the culling statistic).
  size_t faces_used() const { return faces_used_; }

 private:
  const Mesh& mesh_;
  AabbTree faces_;
  bool culling_ = true;
  mutable size_t faces_used_ = 0;
};

}  // namespace vobb
