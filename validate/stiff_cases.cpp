#include "validate/stiff_cases.h"

#include <cmath>
#include <cstdio>
#include <limits>

#include "common/io/mesh_report.h"
#include "common/solidity.h"
#include "data/analytic_meshes.h"
#include "exact/outer_volume.h"
#include "fast/poly_solver.h"

namespace vobb::validate {
namespace {

const char* kWithinR = "finite, within R(m)";
const char* kWithinRB = "finite, within R(m) and B(m)";
const char* kRefused = "refused with a clear message";

// A convex solid from its vertices and faces, each face turned to face away from the
// vertices' centroid (outward for a convex body).
Mesh convex_mesh(std::vector<Vec3> vertices, std::vector<Face> faces) {
  Vec3 c = Vec3::Zero();
  for (const Vec3& v : vertices) c += v;
  c /= double(vertices.size());
  Mesh m;
  m.vertices = std::move(vertices);
  for (Face f : faces) {
    const Vec3 n = (m.vertices[f[1]] - m.vertices[f[0]]).cross(m.vertices[f[2]] - m.vertices[f[0]]);
    if (n.dot(m.vertices[f[0]] - c) < 0) std::swap(f[1], f[2]);
    m.faces.push_back(f);
  }
  return m;
}

// A triangular prism of cross-section w x w (right triangle) and length len along z: its side
// faces are needles of aspect len / w.
Mesh needle_prism(double w, double len) {
  return convex_mesh(
      {{0, 0, 0}, {w, 0, 0}, {0, w, 0}, {0, 0, len}, {w, 0, len}, {0, w, len}},
      {{0, 1, 2}, {3, 4, 5}, {0, 1, 4}, {0, 4, 3}, {1, 2, 5}, {1, 5, 4}, {2, 0, 3}, {2, 3, 5}});
}

// A tetrahedron of height h over a unit right triangle, its apex above the base's interior:
// for small h all four faces are nearly coplanar (slivers).
Mesh sliver_tetrahedron(double h) {
  return convex_mesh({{0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {0.3, 0.3, h}},
                     {{0, 1, 2}, {0, 1, 3}, {1, 2, 3}, {2, 0, 3}});
}

Mesh transformed(const Mesh& mesh, double s, const Vec3& o) {
  Mesh t = mesh;
  for (Vec3& v : t.vertices) v = s * v + o;
  return t;
}

std::string fmt(const char* f, double a, double b = 0) {
  char buf[160];
  std::snprintf(buf, sizeof buf, f, a, b);
  return buf;
}

class Runner {
 public:
  Runner(const StiffConfig& config, const StatedBound& bound) : config_(config), bound_(bound) {}

  // Estimates of every box at every m on both backends, against the exact OBV by clipping.
  // gl_may_refuse: GL may refuse an m beyond its limit (with a message), as expected.
  StiffCaseResult run(const std::string& name, const Mesh& mesh, const std::vector<Obb>& boxes,
                      const std::vector<int>& ms, bool within_b, bool gl_may_refuse = false) {
    StiffCaseResult r;
    r.name = name;
    r.expected = within_b ? kWithinRB : kWithinR;
    const SolidityReport solid = check_solidity(mesh);
    if (!solid.solid()) {
      r.outcome = "the case's mesh is not solid: " + solid.verdict();
      return finish(r);
    }
    EstimatorSet est(mesh, config_.want_gl, config_.perturb);
    const exact::ClipSolver clip(mesh);
    std::vector<double> exact;
    std::vector<Rational> exact_q;
    for (const Obb& b : boxes) {
      exact_q.push_back(clip.obv(b));
      exact.push_back(to_double_nearest(exact_q.back()));
    }
    bool ok = true;
    std::string notes;
    // The polyhedral solver's certified interval holds the exact rational on every box.
    const std::vector<PolyObv> poly = PolyObvSolver(mesh).evaluate(boxes);
    int held = 0, exact_boxes = 0, exact_faces = 0;
    for (size_t i = 0; i < boxes.size(); ++i) {
      held += std::isfinite(poly[i].lo) && std::isfinite(poly[i].hi) &&
              Rational(poly[i].lo) <= exact_q[i] && exact_q[i] <= Rational(poly[i].hi);
      exact_boxes += poly[i].exact_box;
      exact_faces += poly[i].exact_faces;
    }
    r.poly_enclosed = held == static_cast<int>(boxes.size());
    ok = ok && r.poly_enclosed;
    notes += "; poly interval holds the exact value on " + std::to_string(held) + "/" +
             std::to_string(boxes.size()) + " (" + std::to_string(exact_faces) + " faces, " +
             std::to_string(exact_boxes) + " boxes in rationals)";
    size_t n = 0, above_b = 0;
    for (Backend backend : {Backend::kCpu, Backend::kGl}) {
      if (backend == Backend::kGl && !est.has_gl()) {
        notes += "; GL not run (" + est.gl_status() + ")";
        continue;
      }
      for (int m : ms) {
        const Status s = est.check_request(backend, boxes[0], m);
        if (!s) {
          notes += std::string("; ") + to_string(backend) + " refused: " + s.message();
          ok = ok && gl_may_refuse && backend == Backend::kGl;
          continue;
        }
        std::vector<double> secs;
        const std::vector<double> v = est.estimate(backend, boxes, m, &secs);
        for (size_t i = 0; i < boxes.size(); ++i) {
          ++n;
          const double err = std::abs(v[i] - exact[i]);
          const double rb = est.bound(backend, boxes[i], m);
          const double bb = bound_.per_volume(m) * volume(boxes[i]);
          const double rr = rb > 0 ? err / rb : (err > 0 ? INFINITY : 0);
          const double br = bb > 0 ? err / bb : (err > 0 ? INFINITY : 0);
          if (!std::isfinite(v[i])) {
            ok = false;
            notes += "; non-finite estimate";
            r.worst_rigorous_ratio = r.worst_bound_ratio = INFINITY;
            continue;
          }
          r.worst_rigorous_ratio = std::max(r.worst_rigorous_ratio, rr);
          r.worst_bound_ratio = std::max(r.worst_bound_ratio, br);
          r.tightest_rigorous = std::min(r.tightest_rigorous, rb / volume(boxes[i]));
          above_b += !(err <= bb);
          ok = ok && err <= rb && (!within_b || err <= bb);
        }
      }
    }
    r.outcome = std::to_string(n) +
                " estimates finite=" + (r.worst_rigorous_ratio < INFINITY ? "yes" : "no") +
                fmt(", max |E-V|/R(m) %.3g, max |E-V|/B(m) %.3g", r.worst_rigorous_ratio,
                    r.worst_bound_ratio) +
                "; above B(m) on " + std::to_string(above_b) + " of " + std::to_string(n) + notes;
    r.as_expected = ok && n > 0;
    return finish(r);
  }

  StiffCaseResult refusal(const std::string& name, const Status& s) {
    StiffCaseResult r;
    r.name = name;
    r.expected = kRefused;
    r.as_expected = !s && !s.message().empty() && s.message().find('\n') == std::string::npos;
    r.outcome = s ? "accepted (not refused)" : "refused: " + s.message();
    return finish(r);
  }

  StiffCaseResult skipped(const std::string& name, const std::string& expected,
                          const std::string& why) {
    StiffCaseResult r;
    r.name = name;
    r.expected = expected;
    r.outcome = "skipped: " + why;
    r.as_expected = true;  // nothing ran; the table says so
    return finish(r);
  }

 private:
  StiffCaseResult finish(const StiffCaseResult& r) {
    if (config_.progress)
      config_.progress("stiff case " + r.name + ": " +
                       (r.as_expected ? "as expected" : "NOT as expected"));
    return r;
  }
  const StiffConfig& config_;
  const StatedBound& bound_;
};

}  // namespace

std::vector<StiffCaseResult> run_stiff_cases(const StiffConfig& config, const StatedBound& bound) {
  Runner run(config, bound);
  std::vector<StiffCaseResult> out;
  const std::vector<int>& ms = config.ms;

  {  // needles: side faces of aspect 1000
    const double w = 1e-3;
    const Mesh needle = needle_prism(w, 1.0);
    out.push_back(run.run("needle triangles (aspect 1000)", needle,
                          {rotated_box({w / 3, w / 3, 0.5}, {w, w, 0.6}),
                           rotated_box({w / 4, w / 4, 0.5}, {2 * w, 2 * w, 0.1}, 0.2)},
                          ms, false));
  }
  {  // slivers: a tetrahedron of height 1e-3 over a unit triangle
    const Mesh sliver = sliver_tetrahedron(1e-3);
    out.push_back(run.run("sliver triangles (height 1e-3)", sliver,
                          {rotated_box({0.4, 0.4, 0}, {0.7, 0.7, 0.01}),
                           rotated_box({0.3, 0.3, 5e-4}, {0.2, 0.2, 0.2}, 0.3)},
                          ms, false));
  }
  const analytic::AnalyticMesh torus = analytic::polygonal_torus();
  out.push_back(run.run("box aspect ratio 1e-4", torus.mesh,
                        {rotated_box({2.0, 0.1, 0.5}, {1.0, 1.0, 1e-4}, 0.1),
                         rotated_box({0.0, 2.2, 0.3}, {1e-4, 0.8, 0.8}, 0.05)},
                        ms, false));

  if (config.real_mesh) {
    const Mesh& real = *config.real_mesh;
    const std::vector<Obb> mids = box_corpus(real, BoxSize::kMid, 3, 77);
    struct Move {
      const char* name;
      double s;
      Vec3 o;
    };
    for (const Move& mv : {Move{"mesh offset by 1e6", 1.0, Vec3(1e6, -1e6, 1e6)},
                           Move{"mesh scaled by 1e-6", 1e-6, Vec3::Zero()},
                           Move{"mesh scaled by 1e6", 1e6, Vec3::Zero()}}) {
      std::vector<Obb> moved = mids;
      for (Obb& b : moved) {
        b.center = mv.s * b.center + mv.o;
        b.half *= mv.s;
      }
      out.push_back(run.run(std::string(mv.name) + " (" + config.real_mesh_name + ")",
                            transformed(real, mv.s, mv.o), moved, ms, true));
    }
    const Aabb bb = real.bounds();
    const Vec3 mid = 0.5 * (bb.lo + bb.hi), ext = bb.hi - bb.lo;
    out.push_back(run.run(
        "box holding the whole mesh (" + config.real_mesh_name + ")", real,
        {rotated_box(mid, 0.625 * ext), rotated_box(mid, Vec3::Constant(0.9 * ext.norm()), 0.4)},
        ms, true));
    out.push_back(run.run("box disjoint from the mesh (" + config.real_mesh_name + ")", real,
                          {rotated_box(bb.hi + ext, 0.1 * ext, 0.3)}, ms, true));
    const std::vector<Obb> leaves = box_corpus(real, BoxSize::kLeaf, 2, 78);
    out.push_back(
        run.run("m = 1 (" + config.real_mesh_name + " leaf boxes)", real, leaves, {1}, false));
    out.push_back(run.run("m = 1024 (" + config.real_mesh_name + " leaf boxes)", real, leaves,
                          {1024}, false,
                          /*gl_may_refuse=*/true));
  } else {
    for (const char* name : {"mesh offset by 1e6", "mesh scaled by 1e-6", "mesh scaled by 1e6",
                             "box holding the whole mesh", "box disjoint from the mesh"})
      out.push_back(run.skipped(name, kWithinRB, "no real mesh"));
    for (const char* name : {"m = 1", "m = 1024"})
      out.push_back(run.skipped(name, kWithinR, "no real mesh"));
  }

  // Centre on the surface of the unit cube [0, 1]^3 (far-count mode), boxes turned off-axis.
  const analytic::AnalyticMesh cube = analytic::cube();
  out.push_back(run.run("centre on a face", cube.mesh,
                        {rotated_box({0.25, 0.5, 1.0}, {0.3, 0.2, 0.25}, 0.3)}, ms, false));
  out.push_back(run.run("centre on an edge", cube.mesh,
                        {rotated_box({0.5, 1.0, 1.0}, {0.3, 0.2, 0.25}, 0.3)}, ms, false));
  out.push_back(run.run("centre on a vertex", cube.mesh,
                        {rotated_box({1.0, 1.0, 1.0}, {0.3, 0.2, 0.25}, 0.3)}, ms, false));
  // The faces x = 1 seen edge-on: the centre lies in their plane, outside the cube; and an
  // axis-aligned box about the cube, every face parallel to a cubemap face.
  out.push_back(run.run("faces parallel to the view rays", cube.mesh,
                        {rotated_box({1.0, 1.5, 0.5}, {0.5, 0.75, 0.5}),
                         rotated_box({0.5, 0.5, 0.5}, {0.75, 0.75, 0.75})},
                        ms, false));
  const analytic::AnalyticMesh cavity = analytic::cube_with_cavity();
  out.push_back(run.run(
      "nested shells (cube with a cubic cavity)", cavity.mesh,
      {rotated_box({2, 2, 2}, {1.5, 1.2, 1.3}, 0.35), rotated_box({1, 2, 2}, {0.6, 0.6, 0.6}, 0.2)},
      ms, false));

  // Refusals.
  {
    EstimatorSet est(cube.mesh, config.want_gl, config.perturb);
    const Obb ok_box = rotated_box({0.5, 0.5, 0.5}, {0.3, 0.3, 0.3});
    out.push_back(run.refusal("m = 0", est.check_request(Backend::kCpu, ok_box, 0)));
    Obb nan_box = ok_box;
    nan_box.center.x() = std::numeric_limits<double>::quiet_NaN();
    out.push_back(
        run.refusal("box with a NaN centre", est.check_request(Backend::kCpu, nan_box, 8)));
    if (est.has_gl()) {
      const int beyond = est.gl_max_m() + 1;
      out.push_back(run.refusal("GL m beyond its limit (m = " + std::to_string(beyond) + ")",
                                est.check_request(Backend::kGl, ok_box, beyond)));
    } else {
      out.push_back(run.skipped("GL m beyond its limit", kRefused, est.gl_status()));
    }
  }
  if (!config.self_intersecting_mesh.empty()) {
    LoadedMesh lm;
    out.push_back(run.refusal("self-intersecting mesh (" + config.self_intersecting_mesh + ")",
                              load_solid(config.self_intersecting_mesh, &lm)));
  } else {
    out.push_back(run.skipped("self-intersecting mesh", kRefused, "no such mesh given"));
  }
  {
    const analytic::AnalyticMesh huge = analytic::cube(0x1p300);
    const SolidityReport rep = check_solidity(huge.mesh);
    out.push_back(run.refusal("coordinates beyond 2^240",
                              rep.solid() ? Status::ok() : Status::error(rep.verdict())));
  }
  return out;
}

}  // namespace vobb::validate
