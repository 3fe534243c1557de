#include "validate/box_corpus.h"

#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>
#include <random>

#include "builder/obbtree_builder.h"

namespace vobb::validate {

const char* to_string(BoxSize s) {
  switch (s) {
    case BoxSize::kLeaf:
      return "leaf";
    case BoxSize::kMid:
      return "mid";
    case BoxSize::kRoot:
      return "root";
  }
  return "?";
}

int tree_level(BoxSize s) { return s == BoxSize::kLeaf ? 8 : s == BoxSize::kMid ? 4 : 0; }

std::vector<Obb> box_corpus(const Mesh& mesh, BoxSize size, int count, uint64_t seed) {
  ObbTreeOptions options;
  options.depth = tree_level(size);
  const Tree tree = build_obbtree(mesh, options);
  const std::vector<int32_t> nodes = layer(tree, std::min(tree_level(size), tree.depth));
  std::mt19937_64 rng(seed);
  auto uniform = [&] { return static_cast<double>(rng() >> 11) * 0x1.0p-53; };  // [0, 1)
  auto symmetric = [&] { return 2 * uniform() - 1; };                           // [-1, 1)
  std::vector<Obb> out;
  out.reserve(count);
  for (int i = 0; i < count; ++i) {
    const Obb& source =
        tree.nodes[nodes[std::min<size_t>(nodes.size() - 1, uniform() * nodes.size())]].box;
    Obb b = source;
    for (int k = 0; k < 3; ++k) b.center += 0.25 * symmetric() * source.half[k] * source.axes[k];
    Vec3 axis(symmetric(), symmetric(), symmetric());
    if (axis.norm() < 1e-3) axis = Vec3(0, 0, 1);
    const double angle = symmetric() * M_PI / 12;  // up to 15 degrees
    const Eigen::Matrix3d r = Eigen::AngleAxisd(angle, axis.normalized()).toRotationMatrix();
    b.axes = orthonormalize({r * source.axes[0], r * source.axes[1], r * source.axes[2]});
    for (int k = 0; k < 3; ++k) b.half[k] = source.half[k] * std::exp(std::log(1.25) * symmetric());
    out.push_back(b);
  }
  return out;
}

}  // namespace vobb::validate
