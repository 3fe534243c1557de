#include "common/solidity.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <numeric>

#include "common/bvh.h"
#include "common/point_in_solid.h"
#include "common/self_intersections.h"
#include "common/status.h"

namespace vobb {

const char* defect_name(Defect d) {
  switch (d) {
    case Defect::kEmpty:
      return "empty";
    case Defect::kNonFinite:
      return "non-finite";
    case Defect::kHugeCoordinate:
      return "huge-coordinate";
    case Defect::kTinyExtent:
      return "tiny-extent";
    case Defect::kDegenerateFace:
      return "degenerate";
    case Defect::kDuplicateFace:
      return "duplicate";
    case Defect::kNotClosed:
      return "not-closed";
    case Defect::kNonManifoldEdge:
      return "non-manifold";
    case Defect::kNonManifoldVertex:
      return "non-manifold-vertex";
    case Defect::kInconsistentOrientation:
      return "inconsistent-orientation";
    case Defect::kSelfIntersection:
      return "self-intersecting";
    case Defect::kInwardOriented:
      return "inward-oriented";
  }
  return "unknown";
}

std::string DefectCount::describe() const {
  const std::string n = std::to_string(count);
  switch (defect) {
    case Defect::kEmpty:
      return "empty: no faces";
    case Defect::kNonFinite:
      return "non-finite coordinates (NaN or Inf): " + n + " vertices";
    case Defect::kHugeCoordinate:
      return "coordinates beyond +-2^240 (about 1.8e72): " + n + " vertices";
    case Defect::kTinyExtent:
      return "too small: the mesh spans less than 2^-240 (about 5.7e-73) on every axis";
    case Defect::kDegenerateFace:
      return "degenerate faces (zero area): " + n + " faces";
    case Defect::kDuplicateFace:
      return "duplicate faces (the same three vertices as another): " + n + " faces";
    case Defect::kNotClosed:
      return "not closed: " + n + " border edges";
    case Defect::kNonManifoldEdge:
      return "non-manifold: " + n + " edges shared by more than two faces";
    case Defect::kNonManifoldVertex:
      return "non-manifold vertices: " + n + " vertices where separate fans of faces meet";
    case Defect::kInconsistentOrientation:
      return "inconsistent orientation (flipped faces): " + n + " edges";
    case Defect::kSelfIntersection:
      return "self-intersecting: " + std::string(at_least ? "at least " : "") + n +
             " pairs of faces";
    case Defect::kInwardOriented:
      return "inward oriented: " + n + " shells face the wrong way";
  }
  return "unknown defect";
}

std::string SolidityReport::verdict() const {
  if (defects.empty()) return "solid";
  std::string out;
  for (const DefectCount& d : defects) {
    if (!out.empty()) out += "; ";
    out += d.describe();
  }
  return out;
}

namespace {

// ---- union-find over faces --------------------------------------------------------------

struct DisjointSets {
  std::vector<int32_t> parent;
  explicit DisjointSets(size_t n) : parent(n) { std::iota(parent.begin(), parent.end(), 0); }
  int32_t find(int32_t x) {
    while (parent[x] != x) x = parent[x] = parent[parent[x]];
    return x;
  }
  void unite(int32_t a, int32_t b) {
    a = find(a);
    b = find(b);
    if (a != b) parent[std::max(a, b)] = std::min(a, b);
  }
};

}  // namespace

std::vector<std::vector<int32_t>> face_components(const Mesh& mesh) {
  const size_t nf = mesh.faces.size();
  std::vector<std::pair<std::pair<int32_t, int32_t>, int32_t>> edges;
  edges.reserve(3 * nf);
  for (size_t f = 0; f < nf; ++f)
    for (int k = 0; k < 3; ++k) {
      const int32_t a = mesh.faces[f][k], b = mesh.faces[f][(k + 1) % 3];
      edges.push_back({{std::min(a, b), std::max(a, b)}, static_cast<int32_t>(f)});
    }
  std::sort(edges.begin(), edges.end());
  DisjointSets sets(nf);
  for (size_t i = 1; i < edges.size(); ++i)
    if (edges[i].first == edges[i - 1].first) sets.unite(edges[i].second, edges[i - 1].second);
  std::vector<int32_t> index(nf, -1);
  std::vector<std::vector<int32_t>> out;
  for (size_t f = 0; f < nf; ++f) {
    const int32_t root = sets.find(static_cast<int32_t>(f));
    if (index[root] < 0) {
      index[root] = static_cast<int32_t>(out.size());
      out.emplace_back();
    }
    out[index[root]].push_back(static_cast<int32_t>(f));
  }
  return out;
}

namespace {

// Faces with a repeated index or, where `geometric` (every coordinate finite and not huge),
// three collinear corners (exactly); `count` is set to their number.
std::vector<char> degenerate_faces(const Mesh& mesh, bool geometric, size_t* count) {
  const size_t nf = mesh.faces.size();
  std::vector<char> degenerate(nf, 0);
  size_t n_degenerate = 0;
  for (size_t f = 0; f < nf; ++f) {
    const Face& F = mesh.faces[f];
    bool deg = F[0] == F[1] || F[1] == F[2] || F[2] == F[0];
    if (!deg && geometric) deg = collinear(mesh.corner(f, 0), mesh.corner(f, 1), mesh.corner(f, 2));
    if (deg) {
      degenerate[f] = 1;
      ++n_degenerate;
    }
  }
  *count = n_degenerate;
  return degenerate;
}

// Non-degenerate faces with the same vertex set as an earlier face; `count` is set to their
// number.
std::vector<char> duplicate_faces(const Mesh& mesh, const std::vector<char>& degenerate,
                                  size_t* count) {
  const size_t nf = mesh.faces.size();
  std::vector<char> duplicate(nf, 0);
  size_t n_duplicate = 0;
  std::vector<std::pair<std::array<int32_t, 3>, int32_t>> keys;
  keys.reserve(nf);
  for (size_t f = 0; f < nf; ++f) {
    if (degenerate[f]) continue;
    std::array<int32_t, 3> k = {mesh.faces[f][0], mesh.faces[f][1], mesh.faces[f][2]};
    std::sort(k.begin(), k.end());
    keys.push_back({k, static_cast<int32_t>(f)});
  }
  std::sort(keys.begin(), keys.end());
  for (size_t i = 1; i < keys.size(); ++i)
    if (keys[i].first == keys[i - 1].first) {
      duplicate[keys[i].second] = 1;
      ++n_duplicate;
    }
  *count = n_duplicate;
  return duplicate;
}

// What the edges of the non-degenerate faces say: counts of distinct, border, non-manifold and
// flipped edges, the faces joined across shared edges (shells), and the corners (face, k)
// joined across the manifold edges around their vertex (fans).
struct EdgeAnalysis {
  explicit EdgeAnalysis(size_t nf) : shells(nf), fans(3 * nf) {}
  size_t edges = 0, border = 0, nonmanifold = 0, inconsistent = 0;
  DisjointSets shells;
  // A vertex whose corners form more than one group sits where separate fans meet.
  DisjointSets fans;
};

// Sorts (lo, hi, face, forward) records of the non-degenerate faces' edges and reads border,
// non-manifold and flipped edges, shells and fans from them.
EdgeAnalysis analyse_edges(const Mesh& mesh, const std::vector<char>& degenerate) {
  const size_t nf = mesh.faces.size();
  struct EdgeRec {
    int32_t lo, hi, face;
    bool forward;
  };
  std::vector<EdgeRec> recs;
  recs.reserve(3 * nf);
  for (size_t f = 0; f < nf; ++f) {
    if (degenerate[f]) continue;
    const Face& F = mesh.faces[f];
    for (int k = 0; k < 3; ++k) {
      const int32_t a = F[k], b = F[(k + 1) % 3];
      recs.push_back({std::min(a, b), std::max(a, b), static_cast<int32_t>(f), a < b});
    }
  }
  std::sort(recs.begin(), recs.end(), [](const EdgeRec& x, const EdgeRec& y) {
    if (x.lo != y.lo) return x.lo < y.lo;
    if (x.hi != y.hi) return x.hi < y.hi;
    return x.face < y.face;
  });
  EdgeAnalysis out(nf);
  auto corner_of = [&](int32_t face, int32_t vertex) {
    const Face& F = mesh.faces[face];
    return 3 * face + (F[0] == vertex ? 0 : F[1] == vertex ? 1 : 2);
  };
  for (size_t i = 0; i < recs.size();) {
    const EdgeRec& first = recs[i];
    size_t j = i + 1;
    while (j < recs.size() && recs[j].lo == first.lo && recs[j].hi == first.hi) {
      out.shells.unite(first.face, recs[j].face);
      ++j;
    }
    const size_t count = j - i;
    ++out.edges;
    if (count == 1)
      ++out.border;
    else if (count > 2)
      ++out.nonmanifold;
    else if (recs[i].forward == recs[i + 1].forward)
      ++out.inconsistent;
    if (count == 2)
      for (int32_t v : {recs[i].lo, recs[i].hi})
        out.fans.unite(corner_of(recs[i].face, v), corner_of(recs[i + 1].face, v));
    i = j;
  }
  return out;
}

// The non-degenerate faces grouped by shell, shells in the order of their first face.
std::vector<std::vector<int32_t>> shell_faces_of(const std::vector<char>& degenerate,
                                                 DisjointSets* shells) {
  const size_t nf = degenerate.size();
  std::vector<int32_t> shell_of(nf, -1);
  std::vector<std::vector<int32_t>> shell_faces;
  for (size_t f = 0; f < nf; ++f) {
    if (degenerate[f]) continue;
    const int32_t root = shells->find(static_cast<int32_t>(f));
    if (shell_of[root] < 0) {
      shell_of[root] = static_cast<int32_t>(shell_faces.size());
      shell_faces.emplace_back();
    }
    shell_faces[shell_of[root]].push_back(static_cast<int32_t>(f));
  }
  return shell_faces;
}

// The vertices where separate fans of non-degenerate faces meet.
size_t pinched_vertices(const Mesh& mesh, const std::vector<char>& degenerate, DisjointSets* fans) {
  const size_t nf = mesh.faces.size();
  std::vector<int32_t> fan_of(mesh.vertices.size(), -1);
  std::vector<char> pinched(mesh.vertices.size(), 0);
  for (size_t f = 0; f < nf; ++f) {
    if (degenerate[f]) continue;
    for (int k = 0; k < 3; ++k) {
      const int32_t v = mesh.faces[f][k];
      const int32_t root = fans->find(static_cast<int32_t>(3 * f + k));
      if (fan_of[v] < 0)
        fan_of[v] = root;
      else if (fan_of[v] != root)
        pinched[v] = 1;
    }
  }
  return static_cast<size_t>(std::count(pinched.begin(), pinched.end(), 1));
}

// The shells that face the wrong way for their nesting depth: a shell that an even number of
// the others enclose must bound its solid from outside (positive volume), one that an odd
// number enclose a cavity (negative), given the shells' exact signed volumes and their sum.
// The shells must be closed, manifold, consistently oriented and disjoint. Decided exactly, a
// vertex of each shell located against the other shells' faces by one axis ray
// (point_in_solid.h): a vertex of one shell lies on no other, and a shell that does not
// enclose it is crossed an even number of times, so every other shell may be kept.
size_t inward_shells(const Mesh& mesh, const std::vector<std::vector<int32_t>>& shell_faces,
                     const std::vector<Rational>& shell_volume, const Rational& total) {
  if (shell_faces.size() == 1) return sgn(total) > 0 ? 0 : 1;
  std::vector<int32_t> shell_of(mesh.faces.size(), -1);
  for (size_t s = 0; s < shell_faces.size(); ++s)
    for (int32_t f : shell_faces[s]) shell_of[f] = static_cast<int32_t>(s);
  const AabbTree faces = AabbTree::over_faces(mesh);
  // A shell whose bounding box does not hold the vertex cannot enclose it: where no other
  // shell's box holds it, it lies outside them all, with no ray.
  std::vector<Aabb> shell_box(shell_faces.size());
  for (size_t s = 0; s < shell_faces.size(); ++s)
    for (int32_t f : shell_faces[s]) shell_box[s].extend(mesh.face_bounds(f));
  const AabbTree shells(shell_box);
  // The search ends at the first such box: many may hold p.
  auto other_box_holds = [&](const Vec3& p, size_t s) {
    return !shells.visit_accepted_until([&](const Aabb& b) { return b.holds(p); },
                                        [&](int32_t t) { return static_cast<size_t>(t) == s; });
  };
  size_t wrong = 0;
  for (size_t s = 0; s < shell_faces.size(); ++s) {
    const Vec3& p = mesh.corner(shell_faces[s][0], 0);
    // Degenerate faces (none here: they are a defect checked before) belong to no shell.
    const Location at = !other_box_holds(p, s)
                            ? Location::kOutside
                            : locate_point_off_surface(mesh, faces, p, [&](int32_t f) {
                                return shell_of[f] < 0 || shell_of[f] == static_cast<int32_t>(s);
                              });
    VOBB_ASSERT(at != Location::kOnSurface, "a shell's vertex lies on no other shell");
    const int sign = sgn(shell_volume[s]);
    const bool ok = at == Location::kOutside ? sign > 0 : sign < 0;
    if (!ok) ++wrong;
  }
  return wrong;
}

}  // namespace

SolidityReport check_solidity(const Mesh& mesh) {
  SolidityReport r;
  r.vertices = mesh.vertices.size();
  r.faces = mesh.faces.size();
  if (mesh.faces.empty()) {
    r.defects.push_back({Defect::kEmpty, 0});
    return r;
  }
  // Finite coordinates first: every predicate below assumes them.
  size_t nonfinite = 0, huge = 0;
  for (const Vec3& v : mesh.vertices) {
    if (!v.allFinite())
      ++nonfinite;
    else if (v.cwiseAbs().maxCoeff() > kMaxCoordinate)
      ++huge;
  }

  // Degenerate faces: a repeated index, or three collinear points (exactly).
  const size_t nf = mesh.faces.size();
  size_t n_degenerate = 0;
  const std::vector<char> degenerate =
      degenerate_faces(mesh, nonfinite == 0 && huge == 0, &n_degenerate);

  // Duplicate faces: the same vertex set as an earlier face. They are reported, and left out
  // of the self-intersection search below, where k copies of a face would cost k^2 / 2 pairs.
  size_t n_duplicate = 0;
  const std::vector<char> duplicate = duplicate_faces(mesh, degenerate, &n_duplicate);

  // Edges: sorted (lo, hi, face, forward) records give border, non-manifold and flipped edges.
  EdgeAnalysis analysis = analyse_edges(mesh, degenerate);
  r.edges = analysis.edges;
  const size_t border = analysis.border, nonmanifold = analysis.nonmanifold;
  const size_t inconsistent = analysis.inconsistent;
  const std::vector<std::vector<int32_t>> shell_faces =
      shell_faces_of(degenerate, &analysis.shells);
  r.shells = shell_faces.size();

  if (nonfinite) r.defects.push_back({Defect::kNonFinite, nonfinite});
  if (huge) r.defects.push_back({Defect::kHugeCoordinate, huge});
  if (nonfinite == 0 && huge == 0) {
    Aabb bounds;
    for (const Vec3& v : mesh.vertices) bounds.extend(v);
    if ((bounds.hi - bounds.lo).maxCoeff() < kMinExtent)
      r.defects.push_back({Defect::kTinyExtent, 1});
  }
  if (n_degenerate) r.defects.push_back({Defect::kDegenerateFace, n_degenerate});
  if (n_duplicate) r.defects.push_back({Defect::kDuplicateFace, n_duplicate});
  if (border) r.defects.push_back({Defect::kNotClosed, border});
  if (nonmanifold) r.defects.push_back({Defect::kNonManifoldEdge, nonmanifold});
  if (border == 0 && nonmanifold == 0) {
    const size_t n_pinched = pinched_vertices(mesh, degenerate, &analysis.fans);
    if (n_pinched) r.defects.push_back({Defect::kNonManifoldVertex, n_pinched});
  }
  if (inconsistent) r.defects.push_back({Defect::kInconsistentOrientation, inconsistent});
  if (nonfinite || huge) return r;  // nothing geometric can be decided on NaN or near overflow

  // Self-intersections among the non-degenerate faces (duplicates are reported above).
  {
    std::vector<char> skip(nf, 0);
    for (size_t f = 0; f < nf; ++f) skip[f] = degenerate[f] || duplicate[f];
    const SelfIntersectionSearch found =
        find_self_intersections(mesh, skip, kSelfIntersectionsCounted);
    if (found.pairs) r.defects.push_back({Defect::kSelfIntersection, found.pairs, found.stopped});
  }
  if (!r.defects.empty()) return r;  // volume and nesting mean nothing on a broken surface

  // Exact volume, and orientation: with closed, manifold, consistent, disjoint shells, each
  // shell must face the way its nesting depth says (inward_shells).
  {
    std::vector<Rational> shell_volume(shell_faces.size());
    Rational total = 0;
    for (size_t s = 0; s < shell_faces.size(); ++s) {
      shell_volume[s] = exact_signed_volume(mesh, shell_faces[s]);
      total += shell_volume[s];
    }
    r.volume = total;
    r.volume_known = true;
    const size_t wrong = inward_shells(mesh, shell_faces, shell_volume, total);
    if (wrong) r.defects.push_back({Defect::kInwardOriented, wrong});
  }
  return r;
}

}  // namespace vobb
