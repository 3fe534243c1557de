#include "collision/query_objective.h"

#include <tbb/parallel_for.h>

#include <cmath>
#include <limits>
#include <nlohmann/json.hpp>

#include "common/atomic_file.h"
#include "common/json_parse.h"
#include "common/solidity.h"  // kMaxCoordinate: colliders keep to the meshes' range
#include "common/text_util.h"

namespace vobb::collision {
namespace {

using Json = nlohmann::json;
constexpr double kU = std::numeric_limits<double>::epsilon() / 2;

}  // namespace

std::string collider_defect(const Collider& c) {
  if (c.shape != ColliderShape::kSphere && c.shape != ColliderShape::kBox)
    return "shape neither a sphere nor a box";
  if (!c.center.allFinite()) return "centre not finite";
  if (!(c.center.cwiseAbs().maxCoeff() <= kMaxCoordinate)) return "centre beyond 2^240";
  if (c.shape == ColliderShape::kSphere) {
    if (!std::isnormal(c.radius) || c.radius < 0 || c.radius > kMaxCoordinate)
      return "radius not a positive normal number up to 2^240";
    return "";
  }
  for (int k = 0; k < 3; ++k)
    if (!std::isnormal(c.half[k]) || c.half[k] < 0 || c.half[k] > kMaxCoordinate)
      return "half extent not a positive normal number up to 2^240";
  Obb b;
  b.center = c.center;
  b.axes = c.axes;
  b.half = c.half;
  const std::string bad = box_defect(b);
  return bad.empty() ? "" : "box " + bad;
}

Status write_query_stream(const QueryStream& stream, const std::string& path) {
  std::string out = "{\"format\": \"vobb-queries\", \"version\": 1, \"mesh_sha256\": \"" +
                    stream.mesh_sha256 + "\", \"colliders\": [";
  for (size_t i = 0; i < stream.colliders.size(); ++i) {
    const Collider& c = stream.colliders[i];
    out += i ? ",\n[" : "\n[";
    std::vector<double> v = {c.center[0], c.center[1], c.center[2]};
    if (c.shape == ColliderShape::kSphere) {
      v.push_back(c.radius);
    } else {
      for (int k = 0; k < 3; ++k) v.push_back(c.half[k]);
      for (int k = 0; k < 3; ++k)
        for (int i2 = 0; i2 < 3; ++i2) v.push_back(c.axes[k][i2]);
    }
    for (size_t k = 0; k < v.size(); ++k) {
      if (k) out += ", ";
      // "-0" would read back as the integer 0, that is +0: keep the sign with a fraction.
      if (v[k] == 0 && std::signbit(v[k]))
        out += "-0.0";
      else
        append_double(&out, v[k]);
    }
    out += "]";
  }
  out += "]}\n";
  return write_file_atomic(path, out);
}

Status read_query_stream(const std::string& path, QueryStream* stream) {
  const std::string display = basename_of(path);
  uint64_t size = 0;
  if (Status s = check_regular_file(path, display, "query file", &size); !s) return s;
  if (size > kMaxQueryFileBytes)
    return Status::error(display + ": larger than " + std::to_string(kMaxQueryFileBytes >> 30) +
                         " GiB; record fewer queries (--record-every)");
  std::string text;
  if (Status s = read_regular_file(path, display, "query file", &text, true); !s) return s;
  auto fail = [&](const std::string& why) { return Status::error(display + ": " + why); };
  // The deepest values are at depth 2 (file, colliders, a collider); 4 leaves room.
  Json j;
  bool too_deep = false;
  std::string twice;
  if (!parse_json_within(text, 4, &j, &too_deep, &twice))
    return fail(json_refusal(too_deep, twice, "a query file"));
  if (!j.is_object() || !j.contains("format") || j["format"] != "vobb-queries")
    return fail("not a vobb query file (\"format\" is not \"vobb-queries\")");
  if (!j.contains("version") || !j["version"].is_number_integer() || j["version"] != 1)
    return fail("unsupported version (expected 1)");
  if (!j.contains("mesh_sha256") || !j["mesh_sha256"].is_string())
    return fail("bad or missing 'mesh_sha256'");
  if (!j.contains("colliders") || !j["colliders"].is_array())
    return fail("bad or missing 'colliders'");
  const Json& list = j["colliders"];
  if (list.size() > kMaxRecordedQueries)
    return fail("more than " + std::to_string(kMaxRecordedQueries) + " colliders");
  QueryStream out;
  out.mesh_sha256 = j["mesh_sha256"].get<std::string>();
  out.colliders.reserve(list.size());
  for (size_t i = 0; i < list.size(); ++i) {
    const Json& e = list[i];
    const std::string where = "collider " + std::to_string(i) + ": ";
    if (!e.is_array() || (e.size() != 4 && e.size() != 15))
      return fail(where + "not an array of 4 (sphere) or 15 (box) numbers");
    double v[15];
    for (size_t k = 0; k < e.size(); ++k) {
      if (!e[k].is_number()) return fail(where + "not an array of numbers");
      v[k] = e[k].get<double>();
    }
    Collider c;
    c.center = Vec3(v[0], v[1], v[2]);
    if (e.size() == 4) {
      c.shape = ColliderShape::kSphere;
      c.radius = v[3];
    } else {
      c.shape = ColliderShape::kBox;
      c.half = Vec3(v[3], v[4], v[5]);
      for (int k = 0; k < 3; ++k) c.axes[k] = Vec3(v[6 + 3 * k], v[7 + 3 * k], v[8 + 3 * k]);
    }
    const std::string bad = collider_defect(c);
    if (!bad.empty()) return fail(where + bad);
    out.colliders.push_back(c);
  }
  *stream = std::move(out);
  return Status::ok();
}

QueryHitObjective::QueryHitObjective(const Mesh& mesh, const std::vector<Collider>& colliders) {
  const double scale = mesh_scale(mesh);
  colliders_.reserve(colliders.size());
  std::vector<Aabb> bounds;
  bounds.reserve(colliders.size());
  double reach = 0;
  for (const Collider& c : colliders) {
    colliders_.push_back(prepare_collider(c, scale));
    bounds.push_back(colliders_.back().bounds);
    reach = std::max(reach, c.center.norm() + colliders_.back().extent);
  }
  reach_ = reach + scale;
  index_ = AabbTree(std::move(bounds));
}

uint64_t QueryHitObjective::hits(const Obb& box) const {
  const PreparedBox b = prepare_box(box);
  // The screen's pad. Write S = b.extent + reach_ (reach_ >= |s| + r + the mesh's scale M
  // for every collider), e = b.orth_error and u the unit round-off. (One far collider makes
  // S large for every box; the counts stay right, the screen only prunes less.)
  //  - Sphere (centre s, radius r): may_touch_box accepts only when its computed distance is
  //    at most r + slack + margin, and (its derivation) the true distance to B is at least the
  //    computed one less margin; slack <= 32u(|s| + M + r) <= 32u S and margin <=
  //    3(e + 4u)(|s - c_B| + |h|) + 32u(|s| + extent + r) <= 9(e + 4u) S + 32u S, using
  //    |h| <= 2 sum h_k |a_k| (axes within e of unit, e small). So an accepted sphere's ball
  //    comes within slack + 2 margin <= 18 e S + 200u S of B.
  //  - Box: may_touch_box accepts only when no axis among its 15 separates the two by more
  //    than 32u |L| scale in computed terms, 44u |L| scale in exact terms (its 12u
  //    round-off). That bounds the distance only up to a factor: where the nearest features
  //    are a face and a vertex, the face's normal is among the 15 and shows the whole
  //    distance; at a vertex of the Minkowski difference the best of the 15 shows at least
  //    1/sqrt(3) of it (diagonal offsets); where two edges are nearly parallel the rounded
  //    cross product is off by about u / angle, and no closed bound is derived here. The
  //    pad below is at least 9 times the first two cases' sqrt(3) (46u S + 2e S), and the
  //    test places box colliders tangent and just beyond, at small angles too.
  //  - B lies in the hull of its corners; each computed corner coordinate, c + sum +-h_k a_k,
  //    is off by at most 6u S.
  // Pad (32e + 1024u) S covers the sphere and the corners with room, and the box as said.
  // Tested (HitsAtScale.HitsAreMayTouchBoxOverEveryCollider): colliders at the very edge of
  // may_touch_box's acceptance are all kept; that test fails with 16u S in place of 1024u S
  // and passes with 64u S, so the pad is some 16 times what the probed edge needs.
  const double pad = (32 * b.orth_error + 1024 * kU) * (b.extent + reach_);
  Aabb q;
  for (const Vec3& p : corners(box)) q.extend(p);
  q.lo.array() -= pad;
  q.hi.array() += pad;
  uint64_t n = 0;
  index_.for_each_overlap(q, [&](int32_t i) { n += may_touch_box(colliders_[i], b) ? 1 : 0; });
  return n;
}

std::vector<double> QueryHitObjective::operator()(const std::vector<Obb>& boxes) const {
  std::vector<double> out(boxes.size());
  tbb::parallel_for(size_t(0), boxes.size(),
                    [&](size_t i) { out[i] = static_cast<double>(hits(boxes[i])); });
  return out;
}

}  // namespace vobb::collision
