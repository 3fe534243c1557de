#include "common/tree_io.h"

#include <cmath>
#include <functional>
#include <nlohmann/json.hpp>

#include "common/atomic_file.h"
#include "common/json_parse.h"
#include "common/solidity.h"
#include "common/text_util.h"

namespace vobb {
namespace {

using Json = nlohmann::ordered_json;

Json vec_json(const Vec3& v) { return Json::array({v[0], v[1], v[2]}); }

void put_box(Json* j, const Obb& b) {
  (*j)["center"] = vec_json(b.center);
  (*j)["axes"] = Json::array({vec_json(b.axes[0]), vec_json(b.axes[1]), vec_json(b.axes[2])});
  (*j)["half_extents"] = vec_json(b.half);
}

bool get_vec(const Json& j, Vec3* out) {
  if (!j.is_array() || j.size() != 3) return false;
  for (int k = 0; k < 3; ++k) {
    if (!j[k].is_number()) return false;
    (*out)[k] = j[k].get<double>();
  }
  return true;
}

// Reads center/axes/half_extents; returns the name of the first bad field, or "" if fine.
std::string get_box(const Json& j, Obb* b) {
  if (!j.is_object()) return "box is not an object";
  if (!j.contains("center") || !get_vec(j["center"], &b->center)) return "bad or missing 'center'";
  if (!j.contains("half_extents") || !get_vec(j["half_extents"], &b->half))
    return "bad or missing 'half_extents'";
  if (!j.contains("axes") || !j["axes"].is_array() || j["axes"].size() != 3)
    return "bad or missing 'axes'";
  for (int k = 0; k < 3; ++k)
    if (!get_vec(j["axes"][k], &b->axes[k])) return "bad or missing 'axes'";
  return box_defect(*b);
}

bool get_int(const Json& j, const char* key, long long* out) {
  int64_t x = 0;
  if (!j.contains(key) || !json_integer_in(j[key], std::numeric_limits<int64_t>::min(),
                                           std::numeric_limits<int64_t>::max(), &x))
    return false;
  *out = x;
  return true;
}

bool get_int_list(const Json& j, std::vector<int32_t>* out) {
  if (!j.is_array()) return false;
  out->clear();
  out->reserve(j.size());
  for (const Json& v : j) {
    int64_t x = 0;
    if (!json_integer_in(v, INT32_MIN, INT32_MAX, &x)) return false;
    out->push_back(static_cast<int32_t>(x));
  }
  return true;
}

}  // namespace

std::string tree_to_json(const Tree& tree) {
  Json j;
  j["format"] = "vobb-tree";
  j["version"] = 1;
  j["mesh"] = {{"triangles", tree.mesh_triangles}, {"sha256", tree.mesh_sha256}};
  j["method"] = tree.method;
  j["arity"] = tree.arity;
  j["depth"] = tree.depth;
  Json nodes = Json::array();
  for (const TreeNode& n : tree.nodes) {
    Json jn;
    jn["id"] = n.id;
    jn["parent"] = n.parent;
    jn["level"] = n.level;
    put_box(&jn, n.box);
    jn["children"] = n.children;
    jn["faces"] = n.faces;
    nodes.push_back(std::move(jn));
  }
  j["nodes"] = std::move(nodes);
  return j.dump() + "\n";
}

Status write_tree(const Tree& tree, const std::string& path) {
  // No file its reader would refuse: the structure, and each box as read_tree takes boxes.
  if (Status s = validate_tree(tree, basename_of(path)); !s) return s;
  for (const TreeNode& n : tree.nodes)
    if (const std::string bad = box_defect(n.box); !bad.empty())
      return Status::error(basename_of(path) + ": node " + std::to_string(n.id) + ": " + bad);
  return write_file_atomic(path, tree_to_json(tree));
}

Status parse_tree(const std::string& text, const std::string& display, Tree* tree) {
  auto fail = [&](const std::string& why) { return Status::error(display + ": " + why); };
  // A tree's deepest values are at depth 4 (file, nodes, node, axes, a row); 8 leaves room.
  Json j;
  bool too_deep = false;
  std::string twice;
  if (!parse_json_within(text, 8, &j, &too_deep, &twice))
    return fail(json_refusal(too_deep, twice, "a tree file"));
  if (!j.is_object() || !j.contains("format") || j["format"] != "vobb-tree")
    return fail("not a vobb tree file (\"format\" is not \"vobb-tree\")");
  long long version, arity, depth, triangles;
  if (!get_int(j, "version", &version) || version != 1)
    return fail("unsupported version (expected 1)");
  if (!get_int(j, "arity", &arity) || arity < 2 || arity > 1 << 20)
    return fail("bad or missing 'arity'");
  if (!get_int(j, "depth", &depth)) return fail("bad or missing 'depth'");
  if (const std::string bad = depth_defect(depth); !bad.empty()) return fail(bad);
  if (!j.contains("mesh") || !j["mesh"].is_object() ||
      !get_int(j["mesh"], "triangles", &triangles) || triangles < 0)
    return fail("bad or missing 'mesh.triangles'");
  if (triangles > INT32_MAX) return fail("too many triangles");
  Tree t;
  t.arity = static_cast<int>(arity);
  t.depth = static_cast<int>(depth);
  t.mesh_triangles = static_cast<size_t>(triangles);
  // Both may be absent (a hand-made tree: the mesh check is then skipped), but one that is
  // there must be a string: a damaged sha256 must not switch the mesh check off.
  if (j["mesh"].contains("sha256")) {
    if (!j["mesh"]["sha256"].is_string()) return fail("bad 'mesh.sha256' (not a string)");
    t.mesh_sha256 = j["mesh"]["sha256"];
  }
  if (j.contains("method")) {
    if (!j["method"].is_string()) return fail("bad 'method' (not a string)");
    t.method = j["method"];
  }
  if (!j.contains("nodes") || !j["nodes"].is_array()) return fail("bad or missing 'nodes'");
  const Json& nodes = j["nodes"];
  t.nodes.resize(nodes.size());
  std::vector<char> has_faces(nodes.size(), 0);
  for (size_t i = 0; i < nodes.size(); ++i) {
    const Json& jn = nodes[i];
    const std::string at = "node " + std::to_string(i) + ": ";
    if (!jn.is_object()) return fail(at + "not an object");
    TreeNode& n = t.nodes[i];
    long long id, parent, level;
    if (!get_int(jn, "id", &id) || !get_int(jn, "parent", &parent) || !get_int(jn, "level", &level))
      return fail(at + "bad or missing 'id', 'parent' or 'level'");
    if (id != static_cast<long long>(i))
      return fail(at + "id " + std::to_string(id) + " out of order");
    if (parent < -1 || parent > INT32_MAX || level < 0 || level > depth)
      return fail(at + "bad 'parent' or 'level'");
    n.id = static_cast<int32_t>(id);
    n.parent = static_cast<int32_t>(parent);
    n.level = static_cast<int32_t>(level);
    const std::string bad = get_box(jn, &n.box);
    if (!bad.empty()) return fail(at + bad);
    if (jn.contains("children") && !get_int_list(jn["children"], &n.children))
      return fail(at + "bad 'children'");
    if (jn.contains("faces")) {
      if (!get_int_list(jn["faces"], &n.faces)) return fail(at + "bad 'faces'");
      has_faces[i] = 1;
    }
  }
  // Fill in inner nodes that left out their faces, children first. Each child is taken only
  // by the parent it names, once, one level below it: the nodes form a tree of at most
  // kMaxTreeDepth levels, so the faces filled in are at most that many times those listed.
  const int32_t count = static_cast<int32_t>(t.nodes.size());
  std::vector<char> taken(t.nodes.size(), 0);
  for (int32_t i = count - 1; i >= 0; --i) {
    TreeNode& n = t.nodes[i];
    for (int32_t c : n.children) {
      if (c <= i || c >= count || t.nodes[c].parent != i || t.nodes[c].level != n.level + 1 ||
          taken[c])
        return fail("node " + std::to_string(i) + ": bad child " + std::to_string(c));
      taken[c] = 1;
    }
    if (has_faces[i] || n.is_leaf()) continue;
    for (int32_t c : n.children)
      n.faces.insert(n.faces.end(), t.nodes[c].faces.begin(), t.nodes[c].faces.end());
    std::sort(n.faces.begin(), n.faces.end());
  }
  Status s = validate_tree(t, display);
  if (!s) return s;
  *tree = std::move(t);
  return Status::ok();
}

Status read_tree(const std::string& path, Tree* tree) {
  std::string text;
  Status s = read_regular_file(path, basename_of(path), "tree file", &text, true);
  if (!s) return s;
  return parse_tree(text, basename_of(path), tree);
}

Status write_boxes(const std::vector<Obb>& boxes, const std::string& path) {
  for (size_t i = 0; i < boxes.size(); ++i)  // no file its reader would refuse
    if (const std::string bad = box_defect(boxes[i]); !bad.empty())
      return Status::error(basename_of(path) + ": box " + std::to_string(i) + ": " + bad);
  Json arr = Json::array();
  for (const Obb& b : boxes) {
    Json jb;
    put_box(&jb, b);
    arr.push_back(std::move(jb));
  }
  Json j;
  j["boxes"] = std::move(arr);
  return write_file_atomic(path, j.dump() + "\n");
}

Status read_boxes(const std::string& path, std::vector<Obb>* boxes) {
  std::string text;
  Status s = read_regular_file(path, basename_of(path), "box file", &text, true);
  if (!s) return s;
  const std::string display = basename_of(path);
  // A box file's deepest values are at depth 4 (file, boxes, box, axes, a row); 8 leaves room.
  Json j;
  bool too_deep = false;
  std::string twice;
  if (!parse_json_within(text, 8, &j, &too_deep, &twice))
    return Status::error(display + ": " + json_refusal(too_deep, twice, "a box file"));
  if (!j.is_object() || !j.contains("boxes") || !j["boxes"].is_array())
    return Status::error(display + ": no \"boxes\" array");
  boxes->clear();
  for (size_t i = 0; i < j["boxes"].size(); ++i) {
    Obb b;
    const std::string bad = get_box(j["boxes"][i], &b);
    if (!bad.empty()) return Status::error(display + ": box " + std::to_string(i) + ": " + bad);
    boxes->push_back(b);
  }
  return Status::ok();
}

}  // namespace vobb
