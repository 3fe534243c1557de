#include "common/solidity.h"

#include <gtest/gtest.h>

#include <cmath>
#include <fstream>
#include <set>
#include <sstream>

#include "common/io/mesh_io.h"
#include "data/analytic_meshes.h"
#include "test_common.h"

namespace vobb {
namespace {

using analytic::cube;

// The single defect of a report, for meshes made to show exactly one.
DefectCount only_defect(const Mesh& m) {
  const SolidityReport r = check_solidity(m);
  EXPECT_EQ(r.defects.size(), 1u) << r.verdict();
  return r.defects.empty() ? DefectCount{Defect::kEmpty, 0} : r.defects[0];
}

Mesh append(Mesh a, const Mesh& b) {
  const int32_t base = static_cast<int32_t>(a.vertices.size());
  a.vertices.insert(a.vertices.end(), b.vertices.begin(), b.vertices.end());
  for (Face f : b.faces) a.faces.push_back({f[0] + base, f[1] + base, f[2] + base});
  return a;
}

// Joins exactly equal vertices, as the loader does.
Mesh welded(Mesh m) {
  size_t w, u;
  weld_vertices(&m, &w, &u);
  return m;
}

TEST(Solidity, EmptyMesh) { EXPECT_EQ(only_defect(Mesh()).defect, Defect::kEmpty); }

TEST(Solidity, OpenMeshCountsBorderEdges) {
  Mesh m = cube().mesh;
  m.faces.pop_back();
  const DefectCount d = only_defect(m);
  EXPECT_EQ(d.defect, Defect::kNotClosed);
  EXPECT_EQ(d.count, 3u);
  EXPECT_EQ(d.describe(), "not closed: 3 border edges");
}

TEST(Solidity, NonManifoldEdge) {
  const Mesh m = welded(append(cube().mesh, cube(1, Vec3(1, 1, 0)).mesh));  // share one edge
  const DefectCount d = only_defect(m);
  EXPECT_EQ(d.defect, Defect::kNonManifoldEdge);
  EXPECT_EQ(d.count, 1u);
}

TEST(Solidity, NonManifoldVertex) {
  const Mesh m = welded(append(cube().mesh, cube(1, Vec3(1, 1, 1)).mesh));  // share one corner
  const DefectCount d = only_defect(m);
  EXPECT_EQ(d.defect, Defect::kNonManifoldVertex);
  EXPECT_EQ(d.count, 1u);
}

TEST(Solidity, FlippedFace) {
  Mesh m = cube().mesh;
  std::swap(m.faces[4][1], m.faces[4][2]);
  const DefectCount d = only_defect(m);
  EXPECT_EQ(d.defect, Defect::kInconsistentOrientation);
  EXPECT_EQ(d.count, 3u);
}

TEST(Solidity, InwardOrientedMesh) {
  Mesh m = cube().mesh;
  for (Face& f : m.faces) std::swap(f[1], f[2]);
  const DefectCount d = only_defect(m);
  EXPECT_EQ(d.defect, Defect::kInwardOriented);
  EXPECT_EQ(d.count, 1u);
}

TEST(Solidity, CavityFacingTheWrongWay) {
  Mesh m = analytic::cube_with_cavity().mesh;
  for (size_t f = 12; f < 24; ++f) std::swap(m.faces[f][1], m.faces[f][2]);
  const DefectCount d = only_defect(m);
  EXPECT_EQ(d.defect, Defect::kInwardOriented);
  EXPECT_EQ(d.count, 1u);
}

// A cube with a cavity holding an island: three shells, each facing the way its nesting depth
// says (0 and 2 shells around: out; 1: into the cavity). Flipping one shell makes that one
// shell wrong, whatever the others enclose.
TEST(Solidity, NestedShellsEachFaceTheWayTheirDepthSays) {
  const Mesh nested =
      append(analytic::cube_with_cavity(4, 1, 3).mesh, cube(1, Vec3(1.5, 1.5, 1.5)).mesh);
  const SolidityReport r = check_solidity(nested);
  EXPECT_TRUE(r.solid()) << r.verdict();
  EXPECT_EQ(r.shells, 3u);
  EXPECT_EQ(r.volume, Rational(64 - 8 + 1));
  // Faces 0-11 the outer cube, 12-23 the cavity, 24-35 the island.
  for (size_t first : {0, 12, 24}) {
    Mesh m = nested;
    for (size_t f = first; f < first + 12; ++f) std::swap(m.faces[f][1], m.faces[f][2]);
    const DefectCount d = only_defect(m);
    EXPECT_EQ(d.defect, Defect::kInwardOriented) << first;
    EXPECT_EQ(d.count, 1u) << first;
  }
}

// The same three shells moved to 2^52, where a unit apart is all the doubles there have: the
// nesting is decided without forming any point off the shells' vertices.
TEST(Solidity, NestedShellsAtTheCoordinatesLastUnit) {
  Mesh nested = append(analytic::cube_with_cavity(4, 1, 3).mesh, cube(1, Vec3(1.5, 1.5, 1.5)).mesh);
  for (Vec3& v : nested.vertices) v = Vec3::Constant(0x1p52) + 2.0 * v;
  const SolidityReport r = check_solidity(nested);
  EXPECT_TRUE(r.solid()) << r.verdict();
  EXPECT_EQ(r.shells, 3u);
  EXPECT_EQ(r.volume, Rational(8 * (64 - 8 + 1)));
  for (size_t f = 24; f < 36; ++f) std::swap(nested.faces[f][1], nested.faces[f][2]);
  const DefectCount d = only_defect(nested);
  EXPECT_EQ(d.defect, Defect::kInwardOriented);
  EXPECT_EQ(d.count, 1u);
}

// Thin parallel tetrahedra stacked along z on the plane z = c - x, each shell's first vertex on
// the boundary of every other's bounding box, so that most axis rays from it meet the shells
// above or below. Each is wound outward (its apex lies 2 d above its base's plane, on the side
// the base's normal points away from). One turned inside out is the one found.
TEST(Solidity, ThinShellsStackedSoThatRaysMeetTheOthers) {
  Mesh m;
  const int n = 300;
  for (int k = 0; k < n; ++k) {
    const double c = k * 0x1p-10, d = 0x1p-12;
    const int32_t b = static_cast<int32_t>(m.vertices.size());
    for (const Vec3& v : {Vec3(0, 0, c), Vec3(1, 0, c - 1), Vec3(0.5, 1, c - 0.5),
                          Vec3(0.5 + d, 1.0 / 3, c - 0.5 + d)})
      m.vertices.push_back(v);
    for (const Face& f : {Face{b, b + 2, b + 1}, Face{b, b + 1, b + 3}, Face{b, b + 3, b + 2},
                          Face{b + 1, b + 2, b + 3}})
      m.faces.push_back(f);
  }
  const SolidityReport r = check_solidity(m);
  EXPECT_TRUE(r.solid()) << r.verdict();
  EXPECT_EQ(r.shells, static_cast<size_t>(n));
  for (size_t f = 4 * 123; f < 4 * 124; ++f) std::swap(m.faces[f][1], m.faces[f][2]);
  const DefectCount d = only_defect(m);
  EXPECT_EQ(d.defect, Defect::kInwardOriented);
  EXPECT_EQ(d.count, 1u);
}

// Many shells: 1,000 disjoint tetrahedra on a grid, one of them turned inside out.
TEST(Solidity, ManyDisjointShellsAreLocatedEachAgainstTheOthers) {
  Mesh m;
  for (int k = 0; k < 1000; ++k) {
    const Vec3 o(3.0 * (k % 10), 3.0 * (k / 10 % 10), 3.0 * (k / 100));
    const int32_t b = static_cast<int32_t>(m.vertices.size());
    for (const Vec3& v : {Vec3(0, 0, 0), Vec3(1, 0, 0), Vec3(0, 1, 0), Vec3(0, 0, 1)})
      m.vertices.push_back(o + v);
    for (const Face& f : {Face{b, b + 2, b + 1}, Face{b, b + 1, b + 3}, Face{b, b + 3, b + 2},
                          Face{b + 1, b + 2, b + 3}})
      m.faces.push_back(f);
  }
  const SolidityReport r = check_solidity(m);
  EXPECT_TRUE(r.solid()) << r.verdict();
  EXPECT_EQ(r.shells, 1000u);
  EXPECT_EQ(r.volume, Rational(1000) / Rational(6));
  for (size_t f = 4 * 537; f < 4 * 538; ++f) std::swap(m.faces[f][1], m.faces[f][2]);
  const DefectCount d = only_defect(m);
  EXPECT_EQ(d.defect, Defect::kInwardOriented);
  EXPECT_EQ(d.count, 1u);
}

TEST(Solidity, DisjointShellsAreASolid) {
  const Mesh m = append(cube().mesh, cube(1, Vec3(3, 0, 0)).mesh);
  const SolidityReport r = check_solidity(m);
  EXPECT_TRUE(r.solid()) << r.verdict();
  EXPECT_EQ(r.volume, Rational(2));
  EXPECT_EQ(r.shells, 2u);
}

TEST(Solidity, OverlappingShellsSelfIntersect) {
  const Mesh m = append(cube().mesh, cube(1, Vec3(0.5, 0.5, 0.5)).mesh);
  const SolidityReport r = check_solidity(m);
  ASSERT_FALSE(r.defects.empty());
  EXPECT_EQ(r.defects[0].defect, Defect::kSelfIntersection);
  EXPECT_GT(r.defects[0].count, 0u);
}

// Crossing sheets: 1,500 triangles through one segment, 1,124,250 meeting pairs. The count
// stops at kSelfIntersectionsCounted, and the verdict says it is a lower bound.
TEST(Solidity, CountOfSelfIntersectionsStopsAtItsLimit) {
  const Mesh m = test::pinwheel(1500);
  const SolidityReport r = check_solidity(m);
  const DefectCount* found = nullptr;
  for (const DefectCount& d : r.defects)
    if (d.defect == Defect::kSelfIntersection) found = &d;
  ASSERT_NE(found, nullptr) << r.verdict();
  EXPECT_TRUE(found->at_least);
  EXPECT_EQ(found->count, kSelfIntersectionsCounted);
  EXPECT_NE(r.verdict().find("self-intersecting: at least 1000000 pairs of faces"),
            std::string::npos)
      << r.verdict();
  // Below the limit the count is exact and says so.
  const SolidityReport two = check_solidity(append(cube().mesh, cube(1, Vec3(0.5, 0.5, 0.5)).mesh));
  ASSERT_FALSE(two.defects.empty());
  EXPECT_FALSE(two.defects[0].at_least);
  EXPECT_EQ(two.verdict().find("at least"), std::string::npos) << two.verdict();
}

TEST(Solidity, NestedShellTouchingTheOuterOneSelfIntersects) {
  // A cavity whose face lies on the outer surface: faces touch without sharing vertices.
  Mesh m = analytic::cube_with_cavity(4, 0, 2).mesh;  // cavity [0, 2]^3 touches 3 outer faces
  const SolidityReport r = check_solidity(m);
  ASSERT_FALSE(r.solid());
  EXPECT_EQ(r.defects[0].defect, Defect::kSelfIntersection);
}

TEST(Solidity, DegenerateFaces) {
  Mesh m = cube().mesh;
  m.faces.push_back({0, 0, 1});  // repeated index
  EXPECT_EQ(only_defect(m).defect, Defect::kDegenerateFace);
  Mesh c = cube().mesh;
  c.vertices.emplace_back(0.5, 0, 0);  // on the edge from vertex 0 to vertex 1
  c.faces.push_back({0, 1, 8});
  const DefectCount d = only_defect(c);
  EXPECT_EQ(d.defect, Defect::kDegenerateFace);
  EXPECT_EQ(d.count, 1u);
}

TEST(Solidity, NonFiniteCoordinates) {
  for (double bad : {NAN, INFINITY, -INFINITY}) {
    Mesh m = cube().mesh;
    m.vertices[2][1] = bad;
    const DefectCount d = only_defect(m);
    EXPECT_EQ(d.defect, Defect::kNonFinite);
    EXPECT_EQ(d.count, 1u);
  }
}

TEST(Solidity, HugeCoordinatesAreRefusedBeforeTheyOverflow) {
  Mesh m = analytic::tetrahedron(1e308).mesh;
  const DefectCount d = only_defect(m);
  EXPECT_EQ(d.defect, Defect::kHugeCoordinate);
  EXPECT_EQ(d.count, 3u);
  EXPECT_TRUE(check_solidity(analytic::tetrahedron(1e72).mesh).solid());
}

TEST(Solidity, TinyMeshesAreRefusedBeforeTheyUnderflow) {
  const DefectCount d = only_defect(analytic::tetrahedron(1e-73).mesh);
  EXPECT_EQ(d.defect, Defect::kTinyExtent);
  EXPECT_TRUE(check_solidity(analytic::tetrahedron(1e-72).mesh).solid());
}

// The committed verdict list (data/real_meshes.tsv) against what the checker says now, and
// the DESIGN's classification of the same meshes: clean ones solid, the rest not.
// "not closed: 6 border edges; self-intersecting: 38 pairs" -> {"not closed", "self-intersecting"}.
std::set<std::string> defect_kinds(const std::string& verdict) {
  std::set<std::string> out;
  std::istringstream in(verdict);
  std::string part;
  while (std::getline(in, part, ';')) {
    const size_t start = part.find_first_not_of(' ');
    out.insert(part.substr(start, part.find(':') - start));
  }
  return out;
}

TEST(Solidity, RealMeshVerdictsMatchTheCommittedList) {
  std::ifstream list(std::string(VOBB_REAL_MESH_DIR) + "/../real_meshes.tsv");
  ASSERT_TRUE(list) << "data/real_meshes.tsv missing";
  std::string line;
  int checked = 0;
  while (std::getline(list, line)) {
    if (line.empty() || line[0] == '#') continue;
    std::istringstream in(line);
    std::string name, faces, verdict;
    std::getline(in, name, '\t');
    std::getline(in, faces, '\t');
    std::getline(in, verdict);
    if (!test::exists(test::real_mesh(name))) {
      if (test::real_meshes_required())
        ADD_FAILURE() << name << " is absent (VOBB_REQUIRE_REAL_MESHES=1)";
      continue;
    }
    LoadedMesh lm;
    ASSERT_TRUE(load_mesh(test::real_mesh(name), &lm));
    const SolidityReport r = check_solidity(lm.mesh);
    // The face count from the file itself, counted without vobb's reader (the list's column is
    // what `vobb info` printed, so it documents, and is not the expectation).
    EXPECT_EQ(static_cast<long>(r.faces), test::off_triangle_count(test::real_mesh(name))) << name;
    // The kinds of defect, not their counts: the counts in the list are what `vobb info`
    // printed, so comparing them would test the code against itself. The counts are checked
    // against CGAL instead (tests/exact/solidity_referee_test.cpp).
    EXPECT_EQ(defect_kinds(r.verdict()), defect_kinds(verdict)) << name;
    const auto& clean = test::clean_real_meshes();
    EXPECT_EQ(r.solid(), std::find(clean.begin(), clean.end(), name) != clean.end()) << name;
    ++checked;
  }
  if (checked == 0) VOBB_SKIP_WITHOUT_REAL_MESHES("no real meshes present");
}

}  // namespace
}  // namespace vobb
