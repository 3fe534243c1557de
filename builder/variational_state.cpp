#include "builder/variational_state.h"

#include <cmath>
#include <cstring>
#include <nlohmann/json.hpp>
#include <set>
#include <string>

#include "common/atomic_file.h"
#include "common/json_parse.h"
#include "common/text_util.h"

namespace vobb {

namespace {
constexpr const char* kCheckpointFormat = "vobb-variational-state";

}

Status write_variational_state(const VariationalState& st, const std::string& fingerprint,
                               const std::string& path) {
  nlohmann::json j;
  j["format"] = kCheckpointFormat;
  j["version"] = 1;
  j["fingerprint"] = fingerprint;
  j["split_levels"] = st.split_levels;
  j["sweeps"] = st.sweeps;
  j["sweeping_done"] = st.sweeping_done;
  j["budget_spent"] = st.budget_spent;
  nlohmann::json nodes = nlohmann::json::array();
  for (size_t i = 0; i < st.nodes.size(); ++i) {
    const TreeNode& n = st.nodes[i];
    nlohmann::json axes = nlohmann::json::array();
    for (const Vec3& a : st.axes[i]) axes.push_back({a[0], a[1], a[2]});
    nodes.push_back({{"parent", n.parent},
                     {"level", n.level},
                     {"children", n.children},
                     {"faces", n.faces},
                     {"axes", axes}});
  }
  j["nodes"] = std::move(nodes);
  // nlohmann writes doubles in digits that read back to the same double: a resumed build reads
  // the very axes it saved. The checksum covers everything else, so a damaged digit is refused
  // rather than resumed into another tree.
  j["sha256"] = json_checksum(j);
  return write_file_atomic(path, j.dump() + "\n");
}

Status read_variational_state(const std::string& path, const std::string& fingerprint,
                              size_t mesh_faces, int arity, int depth, VariationalState* state,
                              bool* found) {
  *found = false;
  if (path_absent(path)) return Status::ok();
  *found = true;
  std::string text;
  const Status read = read_regular_file(path, path, "checkpoint file", &text, true);
  if (!read) return read;
  auto bad = [&](const std::string& why) {
    return Status::error(path + ": damaged checkpoint: " + why);
  };
  // A state's deepest values are at depth 4 (file, nodes, node, axes, an axis); 8 leaves room.
  nlohmann::json j;
  bool too_deep = false;
  std::string twice;
  if (!parse_json_within(text, 8, &j, &too_deep, &twice))
    return bad(json_refusal(too_deep, twice, "a checkpoint"));
  if (!j.is_object()) return bad("not a JSON object");
  try {
    if (j.value("format", "") != kCheckpointFormat || j.value("version", 0) != 1)
      return bad("not a vobb checkpoint");
    // Every top-level key must be one this builder writes: a damaged key name (a "sha256"
    // spelled otherwise) would otherwise pass as a state from before checksums.
    const std::set<std::string> known{"format",       "version", "fingerprint",
                                      "split_levels", "sweeps",  "sweeping_done",
                                      "budget_spent", "nodes",   "sha256"};
    for (const auto& item : j.items())
      if (!known.count(item.key())) return bad("unknown field '" + item.key().substr(0, 40) + "'");
    // States saved before checksums were written have none; any other must match.
    if (j.contains("sha256") &&
        (!j["sha256"].is_string() || j["sha256"].get<std::string>() != json_checksum(j)))
      return bad("checksum does not match the contents");
    if (j.at("fingerprint").get<std::string>() != fingerprint)
      return Status::error(path +
                           ": checkpoint of another build (mesh, options or estimator differ); "
                           "use another --checkpoint folder or remove it");
    VariationalState st;
    // Counts are whole numbers as saved: nlohmann's get<int> would truncate 1.5 to 1.
    auto count = [&](const char* key) {
      int64_t x = 0;
      if (!json_integer_in(j.at(key), 0, (int64_t{1} << 31) - 1, &x))
        throw nlohmann::json::type_error::create(302, std::string(key) + " is not a count",
                                                 nullptr);
      return static_cast<int>(x);
    };
    st.split_levels = count("split_levels");
    st.sweeps = count("sweeps");
    st.sweeping_done = j.at("sweeping_done").get<bool>();
    st.budget_spent = j.at("budget_spent").get<bool>();
    const auto& nodes = j.at("nodes");
    if (!nodes.is_array() || nodes.empty()) return bad("no nodes");
    for (size_t i = 0; i < nodes.size(); ++i) {
      const auto& jn = nodes[i];
      TreeNode n;
      n.id = static_cast<int32_t>(i);
      auto integer = [&](const nlohmann::json& v) {
        int64_t x = 0;
        if (!json_integer_in(v, -1, (int64_t{1} << 31) - 1, &x))
          throw nlohmann::json::type_error::create(302, "not an index", nullptr);
        return static_cast<int32_t>(x);
      };
      n.parent = integer(jn.at("parent"));
      n.level = integer(jn.at("level"));
      for (const auto& c : jn.at("children")) integer(c);
      for (const auto& f : jn.at("faces")) integer(f);
      n.children = jn.at("children").get<std::vector<int32_t>>();
      n.faces = jn.at("faces").get<std::vector<int32_t>>();
      std::array<Vec3, 3> axes;
      const auto& ja = jn.at("axes");
      if (!ja.is_array() || ja.size() != 3) return bad("node " + std::to_string(i) + " axes");
      for (int k = 0; k < 3; ++k) {
        const auto v = ja[k].get<std::vector<double>>();
        if (v.size() != 3 || !std::isfinite(v[0]) || !std::isfinite(v[1]) || !std::isfinite(v[2]))
          return bad("node " + std::to_string(i) + " axes");
        axes[k] = Vec3(v[0], v[1], v[2]);
      }
      // Orthonormal as the builder leaves them (orthonormalize: within a few ulps); anything
      // else is not a state this builder saved, and would break the boxes fitted from it.
      for (int a = 0; a < 3; ++a)
        for (int b = 0; b < 3; ++b)
          if (!(std::abs(axes[a].dot(axes[b]) - (a == b ? 1.0 : 0.0)) <= 1e-9))
            return bad("node " + std::to_string(i) + " axes are not orthonormal");
      if (n.faces.empty() || !std::is_sorted(n.faces.begin(), n.faces.end()))
        return bad("node " + std::to_string(i) + " faces");
      for (int32_t f : n.faces)
        if (f < 0 || static_cast<size_t>(f) >= mesh_faces)
          return bad("node " + std::to_string(i) + " faces");
      st.nodes.push_back(std::move(n));
      st.axes.push_back(axes);
    }
    // Links and the face partition, checked as a tree would be.
    Tree t;
    t.arity = arity;
    t.mesh_triangles = mesh_faces;
    t.nodes = st.nodes;
    for (const TreeNode& n : t.nodes) t.depth = std::max(t.depth, static_cast<int>(n.level));
    if (t.depth > depth || st.split_levels > depth)
      return bad("deeper than the build's depth " + std::to_string(depth));
    for (TreeNode& n : t.nodes) std::sort(n.children.begin(), n.children.end());
    const Status s = validate_tree(t, path);
    if (!s) return s;
    if (st.split_levels < 0 || st.sweeps < 0) return bad("counters");
    // The levels made so far are split_levels: no node deeper, and every splittable node
    // above it split (else a resumed build would split it again).
    for (const TreeNode& n : st.nodes)
      if (n.level > st.split_levels ||
          (n.level < st.split_levels && n.faces.size() >= 2 && n.children.empty()))
        return bad("levels do not match split_levels");
    *state = std::move(st);
  } catch (const nlohmann::json::exception&) {
    return bad("missing or mistyped fields");
  }
  return Status::ok();
}

}  // namespace vobb
