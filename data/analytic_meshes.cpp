#include "data/analytic_meshes.h"

#include "common/obb.h"

namespace vobb::analytic {
namespace {

void add_quad(Mesh* m, int a, int b, int c, int d) {
  m->faces.push_back({a, b, c});
  m->faces.push_back({a, c, d});
}

// Appends an axis-aligned box shell [lo, hi]; `inward` flips every face.
void add_box_shell(Mesh* m, const Vec3& lo, const Vec3& hi, bool inward) {
  const int base = static_cast<int>(m->vertices.size());
  for (int i = 0; i < 8; ++i)
    m->vertices.emplace_back(i & 1 ? hi[0] : lo[0], i & 2 ? hi[1] : lo[1], i & 4 ? hi[2] : lo[2]);
  for (const auto& q : kBoxQuads) {
    if (inward)
      add_quad(m, base + q[3], base + q[2], base + q[1], base + q[0]);
    else
      add_quad(m, base + q[0], base + q[1], base + q[2], base + q[3]);
  }
}

Rational cubed(double x) {
  const Rational r(x);
  return r * r * r;
}

}  // namespace

AnalyticMesh cube(double s, const Vec3& o) {
  AnalyticMesh a{"cube", {}, cubed(s)};
  add_box_shell(&a.mesh, o, o + Vec3::Constant(s), false);
  return a;
}

AnalyticMesh tetrahedron(double s) {
  AnalyticMesh a{"tetrahedron", {}, cubed(s) / 6};
  a.mesh.vertices = {Vec3(0, 0, 0), Vec3(s, 0, 0), Vec3(0, s, 0), Vec3(0, 0, s)};
  a.mesh.faces = {{0, 2, 1}, {0, 1, 3}, {0, 3, 2}, {1, 2, 3}};
  return a;
}

AnalyticMesh octahedron(double r) {
  AnalyticMesh a{"octahedron", {}, 4 * cubed(r) / 3};
  a.mesh.vertices = {Vec3(r, 0, 0),  Vec3(-r, 0, 0), Vec3(0, r, 0),
                     Vec3(0, -r, 0), Vec3(0, 0, r),  Vec3(0, 0, -r)};
  // Each face (x, y, z) with signs: orient counter-clockwise seen from outside.
  for (int sx = 0; sx < 2; ++sx)
    for (int sy = 0; sy < 2; ++sy)
      for (int sz = 0; sz < 2; ++sz) {
        const int x = sx, y = 2 + sy, z = 4 + sz;  // vertex ids: +r first, then -r
        const bool flip = (sx + sy + sz) % 2 == 1;
        if (flip)
          a.mesh.faces.push_back({x, z, y});
        else
          a.mesh.faces.push_back({x, y, z});
      }
  return a;
}

AnalyticMesh polygonal_torus(double so, double si, double h) {
  const Rational so_q(so), si_q(si), h_q(h);
  AnalyticMesh a{"polygonal_torus", {}, 28 * (so_q * so_q - si_q * si_q) * h_q};
  static const int kOct[8][2] = {{3, 1},   {1, 3},   {-1, 3}, {-3, 1},
                                 {-3, -1}, {-1, -3}, {1, -3}, {3, -1}};
  // Vertex ids: outer bottom 0..7, inner bottom 8..15, outer top 16..23, inner top 24..31.
  for (int level = 0; level < 2; ++level)
    for (int ring = 0; ring < 2; ++ring) {
      const double s = ring == 0 ? so : si;
      for (const auto& c : kOct) a.mesh.vertices.emplace_back(s * c[0], s * c[1], level * h);
    }
  auto ob = [](int i) { return i % 8; };
  auto ib = [](int i) { return 8 + i % 8; };
  auto ot = [](int i) { return 16 + i % 8; };
  auto it = [](int i) { return 24 + i % 8; };
  for (int i = 0; i < 8; ++i) {
    const int j = i + 1;  // the octagon runs counter-clockwise seen from +z
    add_quad(&a.mesh, ot(i), ot(j), it(j), it(i));  // top, facing +z
    add_quad(&a.mesh, ob(i), ib(i), ib(j), ob(j));  // bottom, facing -z
    add_quad(&a.mesh, ob(i), ob(j), ot(j), ot(i));  // outer wall, facing out
    add_quad(&a.mesh, ib(i), it(i), it(j), ib(j));  // inner wall, facing the hole
  }
  return a;
}

AnalyticMesh cube_with_cavity(double a_len, double b, double c) {
  AnalyticMesh a{"cube_with_cavity", {}, cubed(a_len) - cubed(c - b)};
  add_box_shell(&a.mesh, Vec3::Zero(), Vec3::Constant(a_len), false);
  add_box_shell(&a.mesh, Vec3::Constant(b), Vec3::Constant(c), true);
  return a;
}

std::vector<AnalyticMesh> all() {
  return {cube(), tetrahedron(), octahedron(), polygonal_torus(), cube_with_cavity()};
}

}  // namespace vobb::analytic
