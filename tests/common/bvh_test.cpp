#include "common/bvh.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <random>

namespace vobb {
namespace {

TEST(AabbTree, OverlapQueriesMatchBruteForce) {
  std::mt19937_64 rng(1);
  std::uniform_real_distribution<double> u(0, 10), s(0, 1);
  for (int n : {0, 1, 3, 17, 500}) {
    std::vector<Aabb> boxes(n);
    for (Aabb& b : boxes) {
      const Vec3 lo(u(rng), u(rng), u(rng));
      b.lo = lo;
      b.hi = lo + Vec3(s(rng), s(rng), s(rng));
    }
    AabbTree tree(boxes);
    for (int q = 0; q < 100; ++q) {
      Aabb query;
      query.lo = Vec3(u(rng), u(rng), u(rng));
      query.hi = query.lo + 2 * Vec3(s(rng), s(rng), s(rng));
      std::vector<int32_t> got, want;
      tree.for_each_overlap(query, [&](int32_t i) { got.push_back(i); });
      for (int i = 0; i < n; ++i)
        if (boxes[i].overlaps(query)) want.push_back(i);
      std::sort(got.begin(), got.end());
      ASSERT_EQ(got, want);
    }
  }
}

// visit_accepted_until reports the overlaps in visit_accepted's order and stops at the first
// visit that returns false: the first k of that order, and false; all of them, and true, where
// no visit stops it.
TEST(AabbTree, VisitsUntilTheVisitStops) {
  std::mt19937_64 rng(3);
  std::uniform_real_distribution<double> u(0, 10), s(0, 1);
  std::vector<Aabb> boxes(300);
  for (Aabb& b : boxes) {
    b.lo = Vec3(u(rng), u(rng), u(rng));
    b.hi = b.lo + Vec3(s(rng), s(rng), s(rng));
  }
  const AabbTree tree(boxes);
  for (int q = 0; q < 50; ++q) {
    Aabb query;
    query.lo = Vec3(u(rng), u(rng), u(rng));
    query.hi = query.lo + 4 * Vec3(s(rng), s(rng), s(rng));
    auto overlaps = [&](const Aabb& b) { return b.overlaps(query); };
    std::vector<int32_t> all;
    tree.visit_accepted(overlaps, [&](int32_t i) { all.push_back(i); });
    std::vector<int32_t> got;
    EXPECT_TRUE(tree.visit_accepted_until(overlaps, [&](int32_t i) {
      got.push_back(i);
      return true;
    }));
    ASSERT_EQ(got, all);
    for (size_t k = 1; k <= all.size(); ++k) {
      got.clear();
      EXPECT_FALSE(tree.visit_accepted_until(overlaps, [&](int32_t i) {
        got.push_back(i);
        return got.size() < k;
      }));
      ASSERT_EQ(got, std::vector<int32_t>(all.begin(), all.begin() + k));
    }
  }
}

// Empty boxes among the primitives (the certify path passes the empty cell of a flat box):
// they are never reported, and the others are found as without them.
TEST(AabbTree, EmptyBoxesAmongThePrimitivesAreNeverReported) {
  std::mt19937_64 rng(2);
  std::uniform_real_distribution<double> u(0, 10), s(0, 1);
  std::vector<Aabb> boxes(300);
  for (size_t i = 0; i < boxes.size(); ++i) {
    if (i % 3 == 0) continue;  // left empty: lo = +inf, hi = -inf
    boxes[i].lo = Vec3(u(rng), u(rng), u(rng));
    boxes[i].hi = boxes[i].lo + Vec3(s(rng), s(rng), s(rng));
  }
  const AabbTree tree(boxes);
  Aabb everything;
  everything.lo = Vec3::Constant(-1);
  everything.hi = Vec3::Constant(12);
  for (int q = 0; q < 100; ++q) {
    Aabb query = everything;
    if (q > 0) {
      query.lo = Vec3(u(rng), u(rng), u(rng));
      query.hi = query.lo + 2 * Vec3(s(rng), s(rng), s(rng));
    }
    std::vector<int32_t> got, want;
    tree.for_each_overlap(query, [&](int32_t i) { got.push_back(i); });
    for (size_t i = 0; i < boxes.size(); ++i)
      if (i % 3 != 0 && boxes[i].overlaps(query)) want.push_back(static_cast<int32_t>(i));
    std::sort(got.begin(), got.end());
    ASSERT_EQ(got, want) << "query " << q;
  }
}

TEST(AabbTree, TouchingBoxesOverlap) {
  Aabb a, b;
  a.lo = Vec3(0, 0, 0);
  a.hi = Vec3(1, 1, 1);
  b.lo = Vec3(1, 0, 0);
  b.hi = Vec3(2, 1, 1);
  EXPECT_TRUE(a.overlaps(b));
  AabbTree tree({a});
  int hits = 0;
  tree.for_each_overlap(b, [&](int32_t) { ++hits; });
  EXPECT_EQ(hits, 1);
}

}  // namespace
}  // namespace vobb
