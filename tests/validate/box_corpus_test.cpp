#include "validate/box_corpus.h"

#include <gtest/gtest.h>

#include <cmath>
#include <vector>

#include "data/analytic_meshes.h"
#include "fast/obbtree_builder.h"

namespace vobb::validate {
namespace {

// Each box's source: a node box of the baseline at the size's level (or the deepest), from
// which the box is jittered (box_corpus.h): centre within 25 % of each half extent along each
// axis, each axis within 15 degrees of its own, each half extent scaled by [0.8, 1.25]. The
// checks allow 1e-9 relative for the rotation and orthonormalisation's round-off (a few ulps
// of each term, far below 1e-9).
bool jittered_from(const Obb& box, const Obb& source) {
  const double slack = 1e-9;
  for (int k = 0; k < 3; ++k) {
    const double along = (box.center - source.center).dot(source.axes[k]);
    if (std::abs(along) > 0.25 * source.half[k] * (1 + slack) + slack * source.half.norm()) return false;
    if (box.axes[k].dot(source.axes[k]) < std::cos(M_PI / 12) - slack) return false;
    const double ratio = box.half[k] / source.half[k];
    if (ratio < 0.8 * (1 - slack) || ratio > 1.25 * (1 + slack)) return false;
  }
  return true;
}

TEST(BoxCorpus, BoxesAreJitteredNodeBoxesOfTheirLevel) {
  const Mesh mesh = analytic::polygonal_torus().mesh;
  for (BoxSize size : {BoxSize::kLeaf, BoxSize::kMid, BoxSize::kRoot}) {
    SCOPED_TRACE(to_string(size));
    ObbTreeOptions o;
    o.depth = tree_level(size);
    const Tree tree = build_obbtree(mesh, o);
    const std::vector<int32_t> level = layer(tree, std::min(tree_level(size), tree.depth));
    const std::vector<Obb> boxes = box_corpus(mesh, size, 40, 3);
    ASSERT_EQ(boxes.size(), 40u);
    for (size_t i = 0; i < boxes.size(); ++i) {
      const Obb& b = boxes[i];
      for (int k = 0; k < 3; ++k) {
        EXPECT_NEAR(b.axes[k].norm(), 1.0, 1e-12) << i;
        for (int l = k + 1; l < 3; ++l) EXPECT_NEAR(b.axes[k].dot(b.axes[l]), 0.0, 1e-12) << i;
      }
      bool found = false;
      for (int32_t id : level) found = found || jittered_from(b, tree.nodes[id].box);
      EXPECT_TRUE(found) << "box " << i << " is no jittered node box of level " << tree_level(size);
    }
  }
}

// The same (mesh, size, count, seed) gives the same boxes, bit for bit; another seed others;
// a shorter corpus is the start of a longer one.
TEST(BoxCorpus, SeededAndRepeatable) {
  const Mesh mesh = analytic::polygonal_torus().mesh;
  const std::vector<Obb> a = box_corpus(mesh, BoxSize::kMid, 20, 9), b = box_corpus(mesh, BoxSize::kMid, 20, 9);
  const std::vector<Obb> c = box_corpus(mesh, BoxSize::kMid, 20, 10), d = box_corpus(mesh, BoxSize::kMid, 5, 9);
  auto same = [](const Obb& x, const Obb& y) {
    return x.center == y.center && x.half == y.half && x.axes[0] == y.axes[0] && x.axes[1] == y.axes[1] &&
           x.axes[2] == y.axes[2];
  };
  size_t equal_ab = 0, equal_ac = 0;
  for (size_t i = 0; i < a.size(); ++i) {
    equal_ab += same(a[i], b[i]) ? 1 : 0;
    equal_ac += same(a[i], c[i]) ? 1 : 0;
  }
  EXPECT_EQ(equal_ab, a.size());
  EXPECT_EQ(equal_ac, 0u);
  for (size_t i = 0; i < d.size(); ++i) EXPECT_TRUE(same(a[i], d[i])) << i;
}

}  // namespace
}  // namespace vobb::validate
