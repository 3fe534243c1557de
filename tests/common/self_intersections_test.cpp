#include "common/self_intersections.h"

#include <gtest/gtest.h>

#include <Eigen/Geometry>
#include <cmath>
#include <random>
#include <string>

#include "common/bvh.h"
#include "common/exact_predicates.h"
#include "test_common.h"

namespace vobb {
namespace {

// Pairs of faces: touching along a shared edge or vertex is fine; folding over, piercing or
// touching elsewhere is an intersection.
TEST(FacesIntersect, SharedEdgeAndVertexCases) {
  Mesh m;
  m.vertices = {Vec3(0, 0, 0),      Vec3(1, 0, 0),     Vec3(0, 1, 0),
                Vec3(0, -1, 0),     Vec3(0.5, 0.5, 0), Vec3(0, 0, 1),
                Vec3(0.2, 0.2, -1), Vec3(0.2, 0.2, 1), Vec3(-1, -1, 0)};
  m.faces = {
      {0, 1, 2},  // 0: base
      {1, 0, 3},  // 1: shares edge 0-1, coplanar, other side: fine
      {1, 0, 4},  // 2: shares edge 0-1, coplanar, same side: folds over
      {1, 0, 5},  // 3: shares edge 0-1, not coplanar: fine
      {0, 6, 7},  // 4: shares vertex 0, pierces the base: intersects
      {0, 8, 3},  // 5: shares vertex 0, coplanar, wedges apart: fine
  };
  EXPECT_FALSE(faces_intersect(m, 0, 1));
  EXPECT_TRUE(faces_intersect(m, 0, 2));
  EXPECT_FALSE(faces_intersect(m, 0, 3));
  EXPECT_TRUE(faces_intersect(m, 0, 4));
  EXPECT_FALSE(faces_intersect(m, 0, 5));
}

TEST(FacesIntersect, DisjointAndTouchingWithoutSharedVertices) {
  Mesh m;
  m.vertices = {Vec3(0, 0, 0),
                Vec3(1, 0, 0),
                Vec3(0, 1, 0),
                Vec3(0.25, 0.25, 0),
                Vec3(0.25, 0.25, 1),
                Vec3(1, 1, 1),  // touches at a point
                Vec3(0.25, 0.25, 1e-300),
                Vec3(0.3, 0.25, 1),
                Vec3(1, 1, 1)};  // just above
  m.faces = {{0, 1, 2}, {3, 4, 5}, {6, 7, 8}};
  EXPECT_TRUE(faces_intersect(m, 0, 1));
  EXPECT_FALSE(faces_intersect(m, 0, 2));
}

// Faces a search may take: three distinct, non-collinear vertices (its precondition).
std::vector<char> degenerate_faces(const Mesh& m) {
  std::vector<char> skip(m.faces.size(), 0);
  for (size_t f = 0; f < m.faces.size(); ++f) {
    const Face& F = m.faces[f];
    skip[f] = F[0] == F[1] || F[1] == F[2] || F[2] == F[0] ||
              collinear(m.corner(f, 0), m.corner(f, 1), m.corner(f, 2));
  }
  return skip;
}

// The reference: every pair of faces, decided exactly.
size_t every_pair(const Mesh& m, const std::vector<char>& skip) {
  size_t pairs = 0;
  for (size_t f = 0; f < m.faces.size(); ++f)
    for (size_t g = f + 1; g < m.faces.size(); ++g)
      if (!skip[f] && !skip[g] && faces_intersect(m, f, g)) ++pairs;
  return pairs;
}

// Random faces over a small pool of vertices: shared edges (manifold or not), shared
// vertices, duplicates and both orientations of a face are all common.
Mesh random_soup(std::mt19937& rng, bool on_grid) {
  Mesh m;
  std::uniform_int_distribution<int> pool_size(6, 24), grid(0, 3);
  std::uniform_real_distribution<double> unit(0.0, 1.0);
  const int n = pool_size(rng);
  for (int i = 0; i < n; ++i)
    m.vertices.push_back(on_grid ? Vec3(grid(rng), grid(rng), grid(rng))
                                 : Vec3(unit(rng), unit(rng), unit(rng)));
  std::uniform_int_distribution<int32_t> pick(0, n - 1);
  // 3 to 10 faces per vertex: 9 to 30 faces around a vertex on average, so that fans both
  // below and above the size where the search filters them by direction occur.
  const int faces = std::uniform_int_distribution<int>(3, 10)(rng) * n;
  for (int i = 0; i < faces; ++i) m.faces.push_back({pick(rng), pick(rng), pick(rng)});
  return m;
}

// `count` triangles with random corners in [-1, 1]^2 x [-z, z], sharing no vertex.
void add_random_triangles(Mesh* m, std::mt19937& rng, int count, double z) {
  std::uniform_real_distribution<double> unit(-1.0, 1.0);
  for (int i = 0; i < count; ++i) {
    const int32_t base = static_cast<int32_t>(m->vertices.size());
    for (int k = 0; k < 3; ++k) m->vertices.push_back(Vec3(unit(rng), unit(rng), z * unit(rng)));
    m->faces.push_back({base, base + 1, base + 2});
  }
}

// The search against every pair, on a mesh made to hold intersections (so that the
// comparison is not 0 == 0).
void expect_agrees_with_every_pair(const Mesh& m, const std::string& what, size_t at_least = 1) {
  const std::vector<char> skip = degenerate_faces(m);
  const size_t expected = every_pair(m, skip);
  EXPECT_GE(expected, at_least) << what;
  EXPECT_EQ(find_self_intersections(m, skip).pairs, expected) << what;
}

// On grid points, coplanar and touching pairs (the cases where a filter's rounding would
// matter) are the rule; on random points, crossings in general position. The search must
// agree with deciding every pair, count for count.
TEST(FindSelfIntersections, AgreesWithEveryPairOnRandomSoups) {
  std::mt19937 rng(7);
  size_t total = 0;
  for (int trial = 0; trial < 200; ++trial) {
    const Mesh m = random_soup(rng, trial % 2 == 0);
    const std::vector<char> skip = degenerate_faces(m);
    const size_t expected = every_pair(m, skip);
    EXPECT_EQ(find_self_intersections(m, skip).pairs, expected) << "trial " << trial;
    total += expected;
  }
  EXPECT_GT(total, 1000u);  // the soups do intersect: the comparison is not 0 == 0
}

// Fans around one vertex, coplanar (folded-over wedges meet beyond the apex) and not, plus
// faces through the apex's neighbourhood that do not list it.
TEST(FindSelfIntersections, AgreesWithEveryPairAroundAHighValenceVertex) {
  std::mt19937 rng(11);
  std::uniform_real_distribution<double> angle(0.0, 2 * M_PI), unit(-1.0, 1.0);
  for (int trial = 0; trial < 6; ++trial) {
    Mesh m;
    m.vertices.push_back(Vec3(0, 0, 0));
    const bool flat = trial % 2 == 0;
    for (int i = 0; i < 150; ++i) {
      const double a = angle(rng);
      m.vertices.push_back(Vec3(std::cos(a), std::sin(a), flat ? 0.0 : 0.3 * unit(rng)));
    }
    for (int32_t i = 1; i < 150; i += 2) m.faces.push_back({0, i, i + 1});
    add_random_triangles(&m, rng, 10, 0.2);
    expect_agrees_with_every_pair(m, "trial " + std::to_string(trial));
  }
}

// Many faces on one edge (non-manifold), whose third vertices fall in a few half-planes
// around it (so whole classes of faces fold onto each other), some listed twice, plus faces
// elsewhere that cross them.
TEST(FindSelfIntersections, AgreesWithEveryPairOnACrowdedEdge) {
  std::mt19937 rng(13);
  std::uniform_int_distribution<int> direction(0, 11);
  std::uniform_real_distribution<double> radius(0.2, 1.0), unit(-1.0, 1.0);
  for (int trial = 0; trial < 6; ++trial) {
    Mesh m;
    m.vertices = {Vec3(0, 0, -1), Vec3(0, 0, 1)};
    for (int i = 0; i < 60; ++i) {
      const double a = 2 * M_PI * direction(rng) / 12, r = radius(rng);
      // Directions a multiple of 30 degrees apart: exactly coplanar only where cos and sin
      // round alike, which the exact test decides either way.
      m.vertices.push_back(Vec3(r * std::cos(a), r * std::sin(a), unit(rng)));
      const int32_t w = static_cast<int32_t>(m.vertices.size()) - 1;
      m.faces.push_back({0, 1, w});
      if (i % 10 == 0) m.faces.push_back({1, 0, w});  // the same face, turned round
    }
    for (int32_t i = 2; i < 40; i += 3) m.faces.push_back({0, i, i + 1});  // a fan at vertex 0
    add_random_triangles(&m, rng, 8, 1.0);
    expect_agrees_with_every_pair(m, "trial " + std::to_string(trial));
  }
}

// The same on exactly coplanar classes: third vertices on the axis planes x = 0 and y = 0,
// where every half-plane is exact.
TEST(FindSelfIntersections, AgreesWithEveryPairOnExactlyCoplanarFacesOfAnEdge) {
  std::mt19937 rng(17);
  std::uniform_int_distribution<int> side(0, 3), grid(1, 4);
  Mesh m;
  m.vertices = {Vec3(0, 0, 0), Vec3(0, 0, 4)};
  for (int i = 0; i < 40; ++i) {
    const int s = side(rng), r = grid(rng), z = grid(rng) - 2;
    const Vec3 dir = s == 0   ? Vec3(1, 0, 0)
                     : s == 1 ? Vec3(0, 1, 0)
                     : s == 2 ? Vec3(-1, 0, 0)
                              : Vec3(0, -1, 0);
    m.vertices.push_back(r * dir + Vec3(0, 0, z));
    m.faces.push_back({0, 1, static_cast<int32_t>(m.vertices.size()) - 1});
  }
  m.faces.push_back(m.faces[3]);  // a duplicate
  expect_agrees_with_every_pair(m, "four classes of about ten faces each", 100);
}

// Closed solids whose every face lists one of two vertices: a double cone, k triangles to
// each apex.
Mesh double_cone(int k) {
  Mesh m;
  m.vertices = {Vec3(0, 0, 1), Vec3(0, 0, -1)};
  for (int i = 0; i < k; ++i)
    m.vertices.push_back(Vec3(std::cos(2 * M_PI * i / k), std::sin(2 * M_PI * i / k), 0));
  for (int32_t i = 0; i < k; ++i) {
    const int32_t a = 2 + i, b = 2 + (i + 1) % k;
    m.faces.push_back({0, a, b});
    m.faces.push_back({1, b, a});
  }
  return m;
}

// A closed cylinder whose caps are fans around their centres (a common CAD export): the
// centre vertices have valence k, and each cap's faces are coplanar.
Mesh fan_capped_cylinder(int k) {
  Mesh m;
  m.vertices = {Vec3(0, 0, 1), Vec3(0, 0, -1)};
  for (int i = 0; i < k; ++i) {
    const double a = 2 * M_PI * i / k;
    m.vertices.push_back(Vec3(std::cos(a), std::sin(a), 1));
    m.vertices.push_back(Vec3(std::cos(a), std::sin(a), -1));
  }
  for (int32_t i = 0; i < k; ++i) {
    const int32_t t0 = 2 + 2 * i, b0 = t0 + 1, t1 = 2 + 2 * ((i + 1) % k), b1 = t1 + 1;
    m.faces.push_back({0, t0, t1});
    m.faces.push_back({1, b1, b0});
    m.faces.push_back({t0, b0, b1});
    m.faces.push_back({t0, b1, t1});
  }
  return m;
}

// The same with a star outline, radii alternating 1 and 1/2 (k even; a gear's outline): each
// side face runs nearly radially, so its box holds the cap faces of a wide arc, and the cap
// faces' boxes, from the centre out, hold the side faces of a wide arc too.
Mesh gear_prism(int k) {
  Mesh m = fan_capped_cylinder(k);
  for (int i = 1; i < k; i += 2)
    for (int c = 0; c < 2; ++c) {
      Vec3& v = m.vertices[2 + 2 * i + c];
      v[0] *= 0.5;
      v[1] *= 0.5;
    }
  return m;
}

// The same with the caps' centres lifted 1/4 out of the caps' planes (exactly representable,
// so that midpoints between a centre and a rim vertex are exact): each cap is a shallow cone
// whose faces' directions from the centre run in and out along the star, so the boxes of
// those directions each span an arc of the rim as wide as the star's depth.
Mesh gear_dome(int k) {
  Mesh m = gear_prism(k);
  m.vertices[0].z() = 1.25;
  m.vertices[1].z() = -1.25;
  return m;
}

// A closed cylinder whose caps are fans around a vertex on their rims, as a CAD export or the
// OFF reader's fan triangulation of a k-gon makes them: each cap is k - 2 long thin faces
// (r0, rj, rj+1). Their boxes are as large as the cap, so each holds O(k) of the side faces
// near the rim, which share no vertex with it.
Mesh rim_fan_cylinder(int k) {
  Mesh m;
  for (int i = 0; i < k; ++i) {
    const double a = 2 * M_PI * i / k;
    m.vertices.push_back(Vec3(std::cos(a), std::sin(a), -1));  // bottom: 2 i
    m.vertices.push_back(Vec3(std::cos(a), std::sin(a), 1));   // top: 2 i + 1
  }
  for (int32_t i = 0; i < k; ++i) {
    const int32_t b0 = 2 * i, t0 = b0 + 1, b1 = 2 * ((i + 1) % k), t1 = b1 + 1;
    m.faces.push_back({b0, b1, t1});
    m.faces.push_back({b0, t1, t0});
  }
  for (int32_t j = 1; j + 1 < k; ++j) {
    m.faces.push_back({0, 2 * (j + 1), 2 * j});  // bottom cap, facing down
    m.faces.push_back({1, 2 * j + 1, 2 * (j + 1) + 1});
  }
  return m;
}

// A top rim vertex t moved toward the axis by the factor r and down to the bottom cap (the
// plane z = -1): through it by `depth` (how = 0), onto it (1) or one ulp below it (2).
void sink_to_bottom_cap(Vec3* t, int how, double r, double depth) {
  const double z = how == 0 ? -1.0 - depth : how == 1 ? -1.0 : std::nextafter(-1.0, -2.0);
  *t = Vec3(r * t->x(), r * t->y(), z);
}

// Rim-fan cylinders with some top rim vertices moved: through the bottom cap (the faces around
// them pierce its long thin faces), onto its plane inside it (they touch them), one ulp below
// that plane (they cross them by one ulp, where the slab volumes' rounding decides) or onto a
// bottom vertex (faces touch at a point that neither lists). Besides, small faces outside the
// cylinder touch it at one bottom rim vertex each, a copy of it (so they share no vertex with
// the faces there): the far corners of the cap's long thin faces, which the slab volumes must
// hold. Most pairs that meet share no vertex, so the search's tree with its slab volumes must
// pass them.
TEST(FindSelfIntersections, AgreesWithEveryPairOnRimFanCylinders) {
  std::mt19937 rng(19);
  std::uniform_real_distribution<double> depth(0.0, 1.0), shrink(0.05, 0.95);
  for (int trial = 0; trial < 12; ++trial) {
    const int k = std::uniform_int_distribution<int>(40, 100)(rng);
    Mesh m = rim_fan_cylinder(k);
    std::uniform_int_distribution<int> rim(1, k - 1);
    for (int touching = 0; touching < 8; ++touching) {
      // Its other corners lie strictly below the bottom cap and outside the rim.
      const Vec3 b = m.vertices[2 * rim(rng)];
      const int32_t base = static_cast<int32_t>(m.vertices.size());
      m.vertices.push_back(b);
      m.vertices.push_back(Vec3(1.2 * b.x(), 1.2 * b.y(), -1.1));
      m.vertices.push_back(Vec3(1.2 * b.x() - 0.1 * b.y(), 1.2 * b.y() + 0.1 * b.x(), -1.3));
      m.faces.push_back({base, base + 1, base + 2});
    }
    for (int moved = 0; moved < 3; ++moved) {
      Vec3& t = m.vertices[2 * rim(rng) + 1];
      const double r = shrink(rng);
      const int how = (trial + moved) % 4;
      if (how < 3)
        sink_to_bottom_cap(&t, how, r, how == 0 ? depth(rng) : 0.0);
      else
        t = m.vertices[2 * rim(rng)];
    }
    expect_agrees_with_every_pair(m, "trial " + std::to_string(trial));
  }
}

// The reference for larger meshes: every pair of faces whose boxes overlap (faces whose boxes
// miss each other cannot meet; boxes are exact minima and maxima), decided exactly.
size_t box_pairs(const Mesh& m, const std::vector<char>& skip) {
  const AabbTree tree = AabbTree::over_faces(m);
  size_t pairs = 0;
  for (size_t f = 0; f < m.faces.size(); ++f) {
    if (skip[f]) continue;
    tree.for_each_overlap(tree.primitive_bounds(static_cast<int32_t>(f)), [&](int32_t g) {
      if (static_cast<size_t>(g) > f && !skip[g] && faces_intersect(m, f, g)) ++pairs;
    });
  }
  return pairs;
}

// Gear prisms of 1,500 and 2,000 points, fine enough that the tree's nodes of cap and side
// faces get slab volumes along their least axis, with some top rim vertices moved: through the
// bottom cap, onto its plane inside it, one ulp below that plane, or turned within the top cap
// to another angle (its side faces then cross cap faces, coplanar along their top edges, and
// other side faces). Against every pair of faces whose boxes overlap.
TEST(FindSelfIntersections, AgreesWithEveryPairOnGearPrisms) {
  std::mt19937 rng(29);
  std::uniform_real_distribution<double> depth(0.0, 1.0), shrink(0.05, 0.95), turn(0.05, 0.5);
  for (int trial = 0; trial < 2; ++trial) {
    const int k = trial == 0 ? 1500 : 2000;
    Mesh m = gear_prism(k);
    std::uniform_int_distribution<int> rim(0, k - 1);
    for (int moved = 0; moved < 4; ++moved) {
      Vec3& t = m.vertices[2 + 2 * rim(rng)];  // a top rim vertex
      const double r = shrink(rng);
      if (moved < 3) {
        sink_to_bottom_cap(&t, moved, r, moved == 0 ? depth(rng) : 0.0);
      } else {
        const double a = std::atan2(t.y(), t.x()) + turn(rng), len = std::hypot(t.x(), t.y());
        t = Vec3(len * std::cos(a), len * std::sin(a), 1.0);
      }
    }
    const std::vector<char> skip = degenerate_faces(m);
    const size_t expected = box_pairs(m, skip);
    EXPECT_GE(expected, 1u) << "trial " << trial;
    EXPECT_EQ(find_self_intersections(m, skip).pairs, expected) << "trial " << trial;
  }
}

// Gear domes with some top rim vertices moved, so that faces around the top centre c meet
// beyond it: to the midpoint of c and another top rim vertex (exactly on the edge from c to
// it, so its two faces touch the faces on that edge along a segment from c, the direction
// shared lying exactly at the end of their arcs), to the midpoint of c and the vertex across
// the rim (its faces' arcs then pass close to the axis), onto the axis below c, or turned
// within the cap to another angle (its faces then cover other faces' directions).
TEST(FindSelfIntersections, AgreesWithEveryPairOnGearDomes) {
  std::mt19937 rng(31);
  std::uniform_real_distribution<double> turn(0.05, 0.5);
  for (int trial = 0; trial < 8; ++trial) {
    const int k = 2 * std::uniform_int_distribution<int>(30, 60)(rng);
    Mesh m = gear_dome(k);
    std::uniform_int_distribution<int> rim(0, k - 1);
    auto top = [&](int i) -> Vec3& { return m.vertices[2 + 2 * i]; };
    for (int moved = 0; moved < 4; ++moved) {
      const int i = rim(rng);
      switch ((trial + moved) % 4) {
        case 0:
          top(i) = 0.5 * (m.vertices[0] + top(rim(rng)));
          break;
        case 1:
          top(i) = 0.5 * (m.vertices[0] + top((i + k / 2) % k));
          break;
        case 2:
          top(i) = Vec3(0, 0, 1);
          break;
        default: {
          const Vec3 t = top(i);
          const double a = std::atan2(t.y(), t.x()) + turn(rng), len = std::hypot(t.x(), t.y());
          top(i) = Vec3(len * std::cos(a), len * std::sin(a), 1.0);
        }
      }
    }
    expect_agrees_with_every_pair(m, "trial " + std::to_string(trial));
  }
}

// A fan around the origin whose faces' arcs of directions pass through, or end at, the axis
// of the fan (the direction along its faces' summed normal), where their images across that
// axis pass through or end at 0. The fan's flat faces (in z = 0, most of them turning
// counterclockwise, at random angles, so some fold over others) make the summed normal +z;
// the others come in pairs whose normals cancel exactly, so that the axis is exactly z: two
// arcs through +z (they meet beyond the origin), two ending at +z (sharing that edge), and
// two ending at -z. Faces sharing no vertex cross the fan besides.
TEST(FindSelfIntersections, AgreesWithEveryPairOnFansWithArcsThroughTheirAxis) {
  std::mt19937 rng(37);
  std::uniform_real_distribution<double> angle(0.0, 2 * M_PI), step(0.05, 0.6), radius(0.5, 2);
  for (int trial = 0; trial < 6; ++trial) {
    Mesh m;
    m.vertices = {Vec3(0, 0, 0)};
    auto add = [&](const Vec3& a, const Vec3& b) {
      const int32_t i = static_cast<int32_t>(m.vertices.size());
      m.vertices.push_back(a);
      m.vertices.push_back(b);
      m.faces.push_back({0, i, i + 1});
    };
    for (int i = 0; i < 40; ++i) {
      const double a = angle(rng), b = a + (i % 5 == 0 ? -1 : 1) * step(rng);
      add(radius(rng) * Vec3(std::cos(a), std::sin(a), 0),
          radius(rng) * Vec3(std::cos(b), std::sin(b), 0));
    }
    add(Vec3(1, 0, 1), Vec3(-1, 0, 1));  // normals (0, -1, 0) and (0, 1, 0)
    add(Vec3(-1, 0, 2), Vec3(1, 0, 2));
    const int32_t up = static_cast<int32_t>(m.vertices.size()), down = up + 1;
    m.vertices.push_back(Vec3(0, 0, 3));
    m.vertices.push_back(Vec3(0, 0, -trial - 1.0));
    for (const Vec3& a : {Vec3(0, 3, 0), Vec3(0, -3, 0)}) {  // normals (+-9, 0, 0)
      m.vertices.push_back(a);
      m.faces.push_back({0, static_cast<int32_t>(m.vertices.size()) - 1, up});
    }
    for (const Vec3& a : {Vec3(2, 0, 1), Vec3(-2, 0, 1)}) {  // normals (0, +-2, 0)
      m.vertices.push_back(a);
      m.faces.push_back({0, static_cast<int32_t>(m.vertices.size()) - 1, down});
    }
    add_random_triangles(&m, rng, 10, 1.0);
    expect_agrees_with_every_pair(m, "trial " + std::to_string(trial));
  }
}

// A fan around the origin, tilted (its summed normal along no axis, so that projecting its
// directions rounds), whose consecutive faces share a ray: face i runs from s_i r_i to
// t_i r_(i+1) for integer vectors r_i around the axis (1, 2, 3) and odd scales s_i, t_i <= 7
// (exact: the r_i stay below 2^50), so consecutive faces touch along a segment from the
// origin, and the two computed directions of each shared ray round differently. Half the
// fans are sharp cones (1e-5 wide), around whose axis those directions' angles round 1e5
// times worse, beyond the filters' fixed slack. A search that did not pad the angles as much
// would miss some of those pairs. A few faces turn the other way and fold over their
// neighbours.
TEST(FindSelfIntersections, AgreesWithEveryPairOnFansWithSharedRaysAtOtherScales) {
  std::mt19937 rng(41);
  std::uniform_int_distribution<int> odd(0, 3);
  const Vec3 n = Vec3(1, 2, 3).normalized(), u = n.cross(Vec3::UnitX()).normalized(),
             w = n.cross(u);
  for (int trial = 0; trial < 6; ++trial) {
    const int k = 30 + 5 * trial;
    std::vector<Vec3> r(k + 1);
    for (int i = 0; i <= k; ++i) {
      const double a = 2 * M_PI * i / k;
      const Vec3 around = std::cos(a) * u + std::sin(a) * w;
      const Vec3 x =
          trial % 2 == 0 ? Vec3(1e3 * (around + 0.7 * n)) : Vec3(1e9 * around + 1e14 * n);
      r[i] = x.array().round();
    }
    Mesh m;
    m.vertices = {Vec3(0, 0, 0)};
    for (int i = 0; i < k; ++i) {
      const double s = 1 + 2 * odd(rng), t = 1 + 2 * odd(rng);
      const int32_t v = static_cast<int32_t>(m.vertices.size());
      m.vertices.push_back(s * r[i]);
      m.vertices.push_back(t * r[(i + 1) % k]);
      if (i % 7 == 3)
        m.faces.push_back({0, v + 1, v});
      else
        m.faces.push_back({0, v, v + 1});
    }
    expect_agrees_with_every_pair(m, "trial " + std::to_string(trial), k / 2);
  }
}

// A cone of 30 faces around the origin, plus a face F whose far corners lie near 1.7e308
// (finite, but the 1-norm of their projection across the axis overflows) and a small face
// through F's plane near the origin, sharing a direction with it. A search that took the
// overflowed projections' angles at face value (every quotient 0) would put F's interval far
// from the small face's and miss the pair.
TEST(FindSelfIntersections, AgreesWithEveryPairOnAFanWithCornersNearTheLargestDouble) {
  Mesh m;
  m.vertices = {Vec3(0, 0, 0)};
  const int k = 30;
  for (int i = 0; i < k; ++i) {
    const double a = 2 * M_PI * i / k;
    m.vertices.push_back(Vec3(std::cos(a), std::sin(a), -0.3));
  }
  for (int32_t i = 0; i < k; ++i) m.faces.push_back({0, 1 + i, 1 + (i + 1) % k});
  const Vec3 p(0.7, 0.7, -0.2), q(0.75, 0.65, -0.2);
  const Vec3 n = p.cross(q).normalized(), mid = 0.5 * (p + q);
  m.vertices.push_back(1.7e308 * p);
  m.vertices.push_back(1.7e308 * q);
  m.vertices.push_back(1e-3 * (mid + 0.1 * n));
  m.vertices.push_back(1e-3 * (mid - 0.1 * n));
  m.faces.push_back({0, k + 1, k + 2});
  m.faces.push_back({0, k + 3, k + 4});
  ASSERT_TRUE(std::isfinite(m.vertices[k + 1].x()));
  ASSERT_TRUE(faces_intersect(m, k, k + 1));
  expect_agrees_with_every_pair(m, "corners near 1.7e308");
}

// The axis that the search takes for a fan around the origin, and two rows across it
// (docs/derivations.md, "Fans ordered by angle": the summed unit normals or the summed unit
// directions, whichever is longer per term). Any other axis is as valid; this one lets a test
// put a corner near the axis the search will use.
void fan_frame(const Mesh& m, Vec3* e1, Vec3* e2, Vec3* e3) {
  auto unit = [](const Vec3& x) {
    const double s = x.cwiseAbs().maxCoeff();
    return s > 0 ? Vec3((x / s).normalized()) : Vec3::Zero();
  };
  Vec3 normals = Vec3::Zero(), directions = Vec3::Zero();
  for (const Face& f : m.faces) {
    const int c = f[0] == 0 ? 0 : f[1] == 0 ? 1 : 2;
    const Vec3 p = unit(m.vertices[f[(c + 1) % 3]]), q = unit(m.vertices[f[(c + 2) % 3]]);
    normals += unit(p.cross(q));
    directions += p + q;
  }
  const double k = static_cast<double>(m.faces.size());
  const Vec3 axis = normals.cwiseAbs().maxCoeff() / k >= directions.cwiseAbs().maxCoeff() / (2 * k)
                        ? normals
                        : directions;
  int least = 0;
  for (int i = 1; i < 3; ++i)
    if (std::abs(axis[i]) < std::abs(axis[least])) least = i;
  *e1 = unit(axis.cross(Vec3::Unit(least)));
  *e2 = unit(axis.cross(*e1));
  *e3 = unit(axis);
}

// A tilted cone of 30 faces around the origin, plus a face F from a corner p at angle phi
// (across the axis) to a corner q within 1e-10 of the axis, a little before phi, and a face G
// from near q to a point between them. q's angle rounds by up to about 1e-6 (its projection is
// 1e-10 of its length), so the computed angles of F's ends can come out in the wrong order,
// and the exact arc then runs from before p's computed angle; G's arc ends there and may meet
// F. The corners are placed by iterating on the search's axis, which they move. A search that
// padded only the far end of each interval missed such pairs (75 in 20,000 of these fans).
TEST(FindSelfIntersections, AgreesWithEveryPairWhereAnArcEndsNearTheAxis) {
  std::mt19937_64 rng(47);
  std::uniform_real_distribution<double> unit(0.0, 1.0);
  const Eigen::Matrix3d turn =
      Eigen::AngleAxisd(0.7, Vec3(0.3, -0.5, 0.8).normalized()).toRotationMatrix();
  const int k = 30;
  size_t meeting = 0;
  for (int trial = 0; trial < 3000; ++trial) {
    Mesh m;
    m.vertices = {Vec3::Zero()};
    for (int i = 0; i < k; ++i) {
      const double a = 2 * M_PI * i / k;
      m.vertices.push_back(turn * Vec3(std::cos(a), std::sin(a), -0.3));
    }
    for (int32_t i = 0; i < k; ++i) m.faces.push_back({0, 1 + i, 1 + (i + 1) % k});
    m.vertices.resize(k + 5, Vec3::Zero());
    m.faces.push_back({0, k + 1, k + 2});  // F
    m.faces.push_back({0, k + 3, k + 4});  // G
    const double phi = 2 * M_PI * unit(rng), dr = 1e-6 * (0.2 + unit(rng)),
                 eps = 1e-10 * (0.5 + unit(rng));
    for (int step = 0; step < 40; ++step) {
      Vec3 e1, e2, e3;
      fan_frame(m, &e1, &e2, &e3);
      auto across = [&](double a) { return Vec3(std::cos(a) * e1 + std::sin(a) * e2); };
      const Vec3 p = across(phi) - 0.3 * e3, q = e3 + eps * across(phi - dr);
      const Vec3 x = 0.5 * across(phi - 0.45 * dr) - 0.3 * e3;
      m.vertices[k + 1] = p;
      m.vertices[k + 2] = q;
      m.vertices[k + 3] = q + (eps / 10) * p - (0.2 * eps) * x;
      m.vertices[k + 4] = x;
    }
    const std::vector<char> skip = degenerate_faces(m);
    ASSERT_FALSE(skip[k] || skip[k + 1]) << "trial " << trial;
    const size_t expected = every_pair(m, skip);
    EXPECT_EQ(find_self_intersections(m, skip).pairs, expected) << "trial " << trial;
    meeting += faces_intersect(m, k, k + 1);
  }
  EXPECT_GT(meeting, 1000u);  // F and G meet in about half the trials: not 0 == 0
}

// k faces on one edge, their third vertices on a circle around it: a non-manifold edge
// whose faces pairwise meet only along the edge.
Mesh crowded_edge(int k) {
  Mesh m;
  m.vertices = {Vec3(0, 0, 0), Vec3(0, 0, 1)};
  for (int i = 0; i < k; ++i) {
    m.vertices.push_back(Vec3(std::cos(2 * M_PI * i / k), std::sin(2 * M_PI * i / k), 0.5));
    m.faces.push_back({0, 1, static_cast<int32_t>(m.vertices.size()) - 1});
  }
  return m;
}

// The search's work, not its time (timings belong in bench/): doubling the faces around a
// vertex or on an edge must not quadruple the filter steps and exact tests, as a search whose
// candidates are all pairs of faces around a vertex would (every face's box holds the apex),
// or one that prunes the faces sharing no vertex by their boxes alone would on the rim-fan
// cylinder (each box of a cap's faces holds the side faces along an arc of the rim), or one
// that prunes them by slab volumes' own axes alone would on the gear prism (a cap face holds
// the centre, which lies in the slab of every node of side faces), or one that filters the
// faces around a vertex by boxes of their directions alone would on the gear dome (as many
// exact tests as pairs of those boxes that overlap, about k^2 / 70; few filter steps each).
// Work proportional to n log2 n grows by 2 (log2 n + 1) / log2 n <= 2.2 from n >= 1,024 faces
// to twice as many; k^2 grows by 4. The bound 3 lies between, with room on both sides. The
// exact tests alone, on these meshes where no two faces meet, are the pairs that no filter
// parts: neighbours of a face, whose number grows like n.
TEST(FindSelfIntersections, WorkAroundHighValenceVerticesGrowsLikeNLogN) {
  struct Shape {
    const char* name;
    Mesh (*make)(int);
  };
  for (const Shape& s :
       {Shape{"double cone", double_cone}, Shape{"fan-capped cylinder", fan_capped_cylinder},
        Shape{"rim-fan cylinder", rim_fan_cylinder}, Shape{"gear prism", gear_prism},
        Shape{"gear dome", gear_dome}, Shape{"crowded edge", crowded_edge}}) {
    size_t work[2], exact[2];
    for (int i = 0; i < 2; ++i) {
      const Mesh m = s.make(2048 << i);
      const SelfIntersectionSearch r =
          find_self_intersections(m, std::vector<char>(m.faces.size(), 0));
      EXPECT_EQ(r.pairs, 0u) << s.name;  // no two faces meet beyond their shared vertices
      work[i] = r.exact_tests + r.filter_steps;
      exact[i] = r.exact_tests;
    }
    EXPECT_LT(static_cast<double>(work[1]) / work[0], 3.0)
        << s.name << ": work " << work[0] << " -> " << work[1];
    EXPECT_LE(exact[1], 3 * exact[0])  // 0 <= 0 on the crowded edge: its edge list decides
        << s.name << ": exact tests " << exact[0] << " -> " << exact[1];
  }
}

// k faces around one vertex, all in the plane z = 0 and turning the same way, each from an
// angle in [0, 0.1] to one in [1, 1.1]: every two overlap beyond the vertex they share, and
// the fan's angle intervals all overlap (k (k - 1) / 2 candidates, listed in several batches).
Mesh overlapping_fan(int k) {
  std::mt19937 rng(43);
  std::uniform_real_distribution<double> jitter(0.0, 0.1), radius(0.5, 2.0);
  Mesh m;
  m.vertices = {Vec3(0, 0, 0)};
  for (int32_t i = 0; i < k; ++i) {
    const double a = jitter(rng), b = 1.0 + jitter(rng);
    m.vertices.push_back(radius(rng) * Vec3(std::cos(a), std::sin(a), 0));
    m.vertices.push_back(radius(rng) * Vec3(std::cos(b), std::sin(b), 0));
    m.faces.push_back({0, 2 * i + 1, 2 * i + 2});
  }
  return m;
}

// A caller that only needs "many" stops the search at stop_at pairs. Every pair of the
// pinwheel (sharing no vertex) and of the overlapping fan (sharing one) meets, so a search
// that stops where it should has made exactly stop_at exact tests.
TEST(FindSelfIntersections, StopsAtTheGivenNumberOfPairs) {
  const int k = 200;
  const size_t all = k * (k - 1) / 2;  // 19,900
  for (const Mesh& m : {test::pinwheel(k), overlapping_fan(k)}) {
    const std::vector<char> skip(m.faces.size(), 0);
    const SelfIntersectionSearch full = find_self_intersections(m, skip);
    EXPECT_EQ(full.pairs, all);
    EXPECT_EQ(every_pair(m, skip), all);
    EXPECT_FALSE(full.stopped);
    const SelfIntersectionSearch cut = find_self_intersections(m, skip, 1000);
    EXPECT_TRUE(cut.stopped);
    EXPECT_EQ(cut.pairs, 1000u);
    EXPECT_EQ(cut.exact_tests, 1000u);
    EXPECT_LT(cut.filter_steps, full.filter_steps);
    const SelfIntersectionSearch again = find_self_intersections(m, skip, 1000);  // deterministic
    EXPECT_EQ(again.exact_tests, cut.exact_tests);
    EXPECT_EQ(again.filter_steps, cut.filter_steps);
    // A limit the mesh does not reach changes nothing; one it just reaches stops there.
    const SelfIntersectionSearch above = find_self_intersections(m, skip, all + 1);
    EXPECT_FALSE(above.stopped);
    EXPECT_EQ(above.pairs, all);
    const SelfIntersectionSearch at = find_self_intersections(m, skip, all);
    EXPECT_TRUE(at.stopped);
    EXPECT_EQ(at.pairs, all);
  }
}

}  // namespace
}  // namespace vobb
