// The exact comparison the builder's improving steps are tested by.
#pragma once

#include <gtest/gtest.h>

#include "common/mesh.h"
#include "common/tree.h"
#include "exact/certify.h"

namespace vobb::test {

// Certifies both trees in rationals and expects each to certify and `lower`'s exact e to be
// strictly below `higher`'s, decided as rationals.
inline void expect_exact_e_below(const Mesh& mesh, const Tree& lower, const Tree& higher) {
  exact::CertifyOptions co;
  co.rational = true;
  const exact::Certificate a = exact::certify(mesh, lower, co);
  const exact::Certificate b = exact::certify(mesh, higher, co);
  ASSERT_TRUE(a.ok() && b.ok() && a.rational && b.rational);
  EXPECT_TRUE(a.weighted_error < b.weighted_error)
      << a.weighted_error_nearest << " against " << b.weighted_error_nearest;
}

}  // namespace vobb::test
