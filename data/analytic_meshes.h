// Small solids whose volumes are known in closed form. Every coordinate is a small dyadic
// rational, so the closed-form volume is exact and a test can compare with `==`.
#pragma once

#include <string>
#include <vector>

#include "common/exact_predicates.h"
#include "common/mesh.h"

namespace vobb::analytic {

struct AnalyticMesh {
  std::string name;
  Mesh mesh;
  Rational volume;  // closed form
};

// Axis-aligned cube [o, o + s]^3: volume s^3.
AnalyticMesh cube(double s = 1.0, const Vec3& o = Vec3::Zero());
// Corner tetrahedron 0, s e_x, s e_y, s e_z: volume s^3 / 6.
AnalyticMesh tetrahedron(double s = 1.0);
// Octahedron with vertices +-r on the axes: volume 4 r^3 / 3.
AnalyticMesh octahedron(double r = 1.0);
// Ring of octagonal plan and rectangular cross-section (genus 1). The octagons have corners
// s(3,1), s(1,3), ... (area 28 s^2), outer scale so > inner scale si, height h:
// volume 28 (so^2 - si^2) h.
AnalyticMesh polygonal_torus(double so = 1.0, double si = 0.5, double h = 1.0);
// Cube [0, a]^3 with the cubic cavity [b, c]^3 (0 < b < c < a): volume a^3 - (c - b)^3.
// The cavity's faces point into the cavity.
AnalyticMesh cube_with_cavity(double a = 4.0, double b = 1.0, double c = 3.0);

std::vector<AnalyticMesh> all();

}  // namespace vobb::analytic
