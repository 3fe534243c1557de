#include "validate/box_corpus.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <vector>

#include "builder/obbtree_builder.h"
#include "data/analytic_meshes.h"
#include "test_common.h"

namespace vobb::validate {
namespace {

// How far a box is from its source node box, per bound of box_corpus.h: the centre's offset
// along each source axis over 25 % of that half extent, the largest angle between an axis and
// its own (degrees), and each half extent over the source's.
struct Jitter {
  double offset = 0, angle = 0, ratio_lo = 1e300, ratio_hi = 0;
};
Jitter jitter(const Obb& box, const Obb& source) {
  Jitter j;
  for (int k = 0; k < 3; ++k) {
    j.offset = std::max(j.offset, std::abs((box.center - source.center).dot(source.axes[k])) /
                                      (0.25 * source.half[k]));
    j.angle =
        std::max(j.angle, std::acos(std::min(1.0, box.axes[k].dot(source.axes[k]))) * 180 / M_PI);
    j.ratio_lo = std::min(j.ratio_lo, box.half[k] / source.half[k]);
    j.ratio_hi = std::max(j.ratio_hi, box.half[k] / source.half[k]);
  }
  return j;
}

// Within the bounds: centre within 25 % of each half extent along each axis, each axis within
// 15 degrees of its own, each half extent scaled by [0.8, 1.25]. The slack, 1e-9 relative, is
// far above the round-off of these few operations on numbers of the mesh's size (some 1e-15
// relative) and far below any real excess, so it decides nothing but round-off.
bool jittered_from(const Obb& box, const Obb& source) {
  const double slack = 1e-9;
  const Jitter j = jitter(box, source);
  return j.offset <= 1 + slack && j.angle <= 15 * (1 + slack) && j.ratio_lo >= 0.8 * (1 - slack) &&
         j.ratio_hi <= 1.25 * (1 + slack);
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
    Jitter most;
    for (size_t i = 0; i < boxes.size(); ++i) {
      const Obb& b = boxes[i];
      for (int k = 0; k < 3; ++k) {
        // The axes come from orthonormalize() (common/obb.cpp).
        const double tol = test::kOrthonormalTol;
        EXPECT_NEAR(b.axes[k].norm(), 1.0, tol) << i;
        for (int l = k + 1; l < 3; ++l) EXPECT_NEAR(b.axes[k].dot(b.axes[l]), 0.0, tol) << i;
      }
      bool found = false;
      for (int32_t id : level)
        if (!found && jittered_from(b, tree.nodes[id].box)) {
          found = true;
          const Jitter j = jitter(b, tree.nodes[id].box);
          most.offset = std::max(most.offset, j.offset);
          most.angle = std::max(most.angle, j.angle);
          most.ratio_lo = std::min(most.ratio_lo, j.ratio_lo);
          most.ratio_hi = std::max(most.ratio_hi, j.ratio_hi);
        }
      EXPECT_TRUE(found) << "box " << i << " is no jittered node box of level " << tree_level(size);
    }
    // And the jitter is there: over 40 seeded boxes (120 draws of each kind, uniform over the
    // bounds) the largest offset, angle and scalings reach past half their bounds; a jitter
    // shrunk tenfold, or none, fails here.
    EXPECT_GT(most.offset, 0.5);
    EXPECT_GT(most.angle, 7.5);
    EXPECT_LT(most.ratio_lo, 0.9);
    EXPECT_GT(most.ratio_hi, 1.1);
  }
}

// The same (mesh, size, count, seed) gives the same boxes, bit for bit; another seed others;
// a shorter corpus is the start of a longer one.
TEST(BoxCorpus, SeededAndRepeatable) {
  const Mesh mesh = analytic::polygonal_torus().mesh;
  const std::vector<Obb> a = box_corpus(mesh, BoxSize::kMid, 20, 9),
                         b = box_corpus(mesh, BoxSize::kMid, 20, 9);
  const std::vector<Obb> c = box_corpus(mesh, BoxSize::kMid, 20, 10),
                         d = box_corpus(mesh, BoxSize::kMid, 5, 9);
  auto same = [](const Obb& x, const Obb& y) {
    return x.center == y.center && x.half == y.half && x.axes[0] == y.axes[0] &&
           x.axes[1] == y.axes[1] && x.axes[2] == y.axes[2];
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
