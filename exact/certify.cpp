#include "exact/certify.h"

#include <tbb/parallel_for.h>
#include <tbb/task_arena.h>
#include <tbb/task_group.h>

#include <algorithm>
#include <atomic>
#include <cctype>
#include <exception>
#include <limits>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <memory>
#include <mutex>
#include <map>
#include <set>

#include <nlohmann/json.hpp>

#include "common/atomic_file.h"
#include "common/json_parse.h"
#include "common/stopwatch.h"
#include "common/text_util.h"
#include "exact/outer_volume.h"

// Threads share no CGAL object: each builds its own NefSolver (nef_solver.cpp checks that CGAL
// is built thread-aware). ClipSolver's const members read shared rationals and write nothing.

namespace vobb::exact {

bool Certificate::ok() const {
  if (!containment.ok()) return false;
  for (const LayerCertificate& l : layers)
    if (!l.upper_bound_holds() || !l.paths_agree) return false;
  return true;
}

namespace {

// The path a layer takes: "none" for boxes that overlap nothing (OMV = sum of OBV) unless both
// paths are asked for; auto takes Nef for layers with overlaps (measured on dino,
// docs/BENCHMARKS.md: Nef's union beats the clipping path's overlap cells on every
// overlapping layer of baseline trees).
std::string layer_path(OmvPath path, size_t overlapping_boxes) {
  if (path == OmvPath::kBoth) return "both";
  if (overlapping_boxes == 0) return "none";
  return path == OmvPath::kClip ? "clip" : "nef";
}

}  // namespace

Certificate certify(const Mesh& mesh, const Tree& tree, const CertifyOptions& options) {
  const auto t0 = std::chrono::steady_clock::now();
  Certificate cert;
  std::mutex say_mutex;  // progress lines come from any thread, one at a time
  auto say = [&](const std::string& line) {
    if (!options.progress) return;
    std::lock_guard<std::mutex> lock(say_mutex);
    options.progress(line);
  };
  cert.containment = check_conservative(mesh, tree);
  say("containment: " + std::to_string(cert.containment.violations) + " violations in " +
      std::to_string(cert.containment.checked_pairs) + " (node, face) pairs");

  // What is finished, for the checkpoint callback; saved one call at a time.
  CertifyState done;
  std::mutex done_mutex;
  auto finished = [&](const LayerCertificate* lc) {
    if (!options.checkpoint) return;
    std::lock_guard<std::mutex> lock(done_mutex);
    if (lc) done.layers.push_back(*lc);
    options.checkpoint(done);
  };
  const CertifyState* resume = options.resume;
  VOBB_ASSERT(!resume || resume->obv.empty() || resume->obv.size() == tree.nodes.size(),
              "a resumed state fits the tree (CertifyCheckpoint::load checks it)");

  // OBV once per node (a leaf above level i belongs to every later layer too), by clipping,
  // one node per task: every node belongs to the layer of its own level.
  const ClipSolver clip(mesh);
  std::vector<Rational> obv(tree.nodes.size());
  if (resume && !resume->obv.empty()) {
    obv = resume->obv;
    say("OBV of " + std::to_string(tree.nodes.size()) + " boxes: from the checkpoint");
  } else {
    const auto tobv = std::chrono::steady_clock::now();
    tbb::parallel_for(size_t{0}, tree.nodes.size(), [&](size_t id) { obv[id] = clip.obv(tree.nodes[id].box); });
    char buf[96];
    std::snprintf(buf, sizeof buf, "OBV of %zu boxes in %.2f s", tree.nodes.size(), seconds_since(tobv));
    say(buf);
  }
  if (options.checkpoint) done.obv = obv;

  // One task per layer, the layers with most boxes (the costly unions) first, each taken by
  // the next free thread. A thread builds its own Nef(X) when a layer first needs it. A layer
  // a resumed state finished is taken from it when its boxes, their overlap count (bounds
  // alone: cheap), its sum of OBV and its path are what this run would give; its OMV is taken
  // as saved (the costly part). Any other is certified again.
  const int levels = tree.depth + 1;
  cert.layers.resize(levels);
  std::vector<std::vector<int32_t>> ids(levels);
  for (int level = 0; level < levels; ++level) ids[level] = layer(tree, level);
  auto layer_boxes = [&](int level) {
    std::vector<Obb> boxes;
    for (int32_t id : ids[level]) boxes.push_back(tree.nodes[id].box);
    return boxes;
  };
  auto layer_sum_obv = [&](int level) {
    std::vector<Rational> obvs;
    for (int32_t id : ids[level]) obvs.push_back(obv[id]);
    return sum_pairwise(obvs);
  };
  std::vector<char> resumed(levels, 0);
  size_t taken = 0, again = 0;
  if (resume)
    for (const LayerCertificate& lc : resume->layers) {
      VOBB_ASSERT(lc.level >= 0 && lc.level < levels && !resumed[lc.level],
                  "a resumed state fits the tree (CertifyCheckpoint::load checks it)");
      size_t overlapping = 0;
      for (char o : clip.may_overlap(layer_boxes(lc.level))) overlapping += o ? 1 : 0;
      if (lc.boxes != ids[lc.level].size() || lc.overlapping_boxes != overlapping ||
          lc.omv_path != layer_path(options.path, overlapping) || lc.sum_obv != layer_sum_obv(lc.level) ||
          (lc.omv_path == "none" && lc.omv != lc.sum_obv) ||
          (lc.omv_path == "both" && lc.paths_agree != (lc.omv == lc.omv_clip))) {
        ++again;
        continue;
      }
      cert.layers[lc.level] = lc;
      resumed[lc.level] = 1;
      ++taken;
      if (options.checkpoint) done.layers.push_back(lc);
    }
  if (resume && !resume->layers.empty())
    say(std::to_string(taken) + " of " + std::to_string(levels) + " layers: from the checkpoint" +
        (again > 0 ? "; " + std::to_string(again) + " saved layers do not match this run, certified again" : ""));
  finished(nullptr);
  std::vector<int> order;
  for (int level = 0; level < levels; ++level)
    if (!resumed[level]) order.push_back(level);
  std::stable_sort(order.begin(), order.end(), [&](int a, int b) { return ids[a].size() > ids[b].size(); });
  const int todo = static_cast<int>(order.size());
  std::atomic<int> next{0};
  auto certify_layers = [&]() {
    std::unique_ptr<NefSolver> nef;  // this thread's own
    double nef_build_seconds = 0;    // within the current layer, kept out of its time
    auto need_nef = [&]() -> const NefSolver& {
      if (!nef) {
        const auto tn = std::chrono::steady_clock::now();
        nef = std::make_unique<NefSolver>(mesh);
        nef_build_seconds = seconds_since(tn);
        char buf[96];
        std::snprintf(buf, sizeof buf, "Nef polyhedron of the mesh built in %.2f s (once per thread)",
                      nef_build_seconds);
        say(buf);
      }
      return *nef;
    };
    auto certify_layer = [&](int level) {
      const auto tl = std::chrono::steady_clock::now();
      nef_build_seconds = 0;
      LayerCertificate& lc = cert.layers[level];
      lc.level = level;
      lc.boxes = ids[level].size();
      const std::vector<Obb> boxes = layer_boxes(level);
      lc.sum_obv = layer_sum_obv(level);
      // Which boxes may meet another one (conservative bounds): boxes that overlap nothing
      // skip the union work.
      std::vector<char> overlapped = clip.may_overlap(boxes);
      for (char o : overlapped) lc.overlapping_boxes += o ? 1 : 0;
      lc.omv_path = layer_path(options.path, lc.overlapping_boxes);
      if (lc.omv_path == "none") {
        lc.omv = lc.sum_obv;  // disjoint boxes: the union's outer volume is the sum
      } else if (lc.omv_path == "nef") {
        lc.omv = need_nef().omv(boxes);
      } else if (lc.omv_path == "clip") {
        lc.omv = clip.omv(boxes, lc.sum_obv);
      } else {  // both: Nef is the arbiter, and a disagreement fails the certificate
        lc.omv_clip = clip.omv(boxes, lc.sum_obv);
        lc.omv = need_nef().omv(boxes);
        lc.paths_agree = lc.omv == lc.omv_clip;
      }
      lc.seconds = seconds_since(tl) - nef_build_seconds;
      const std::string disagree =
          lc.paths_agree ? "" : ", PATHS DISAGREE (Nef's OMV above; clipping's " + format_nearest(lc.omv_clip) + ")";
      char buf[300];
      std::snprintf(buf, sizeof buf, "layer %d/%d: %zu boxes (%zu overlapping), OMV %s, sum OBV %s%s, %.2f s",
                    level, tree.depth, lc.boxes, lc.overlapping_boxes, format_nearest(lc.omv).c_str(),
                    format_nearest(lc.sum_obv).c_str(), disagree.c_str(), lc.seconds);
      say(buf);
      finished(&lc);
    };
    try {
      for (int k; (k = next.fetch_add(1)) < todo;) certify_layer(order[k]);
    } catch (...) {
      next = todo;  // a failure: the other threads take no further layer
      throw;        // task_group passes it on to the caller
    }
  };
  const int concurrency = tbb::this_task_arena::max_concurrency();
  const bool uses_nef = options.path != OmvPath::kClip;
  const double available = options.memory_bytes >= 0 ? options.memory_bytes : available_memory_bytes();
  const int workers = layer_workers(todo, concurrency, uses_nef, mesh.faces.size(), available);
  if (workers < std::min(todo, concurrency)) {
    char buf[200];
    std::snprintf(buf, sizeof buf,
                  "layers on %d threads, not %d: a Nef polyhedron of this mesh takes about %.2f GB, and %.2f GB "
                  "is available",
                  workers, std::min(todo, concurrency), kNefBytesPerFace * static_cast<double>(mesh.faces.size()) / 1e9,
                  available / 1e9);
    say(buf);
  }
  tbb::task_group group;
  for (int w = 1; w < workers; ++w) group.run(certify_layers);
  // This thread takes layers too. Its failure is held until the workers have stopped: the
  // group must be waited for before it is destroyed, and its wait rethrows a worker's failure,
  // which during the unwinding of this thread's own would end the process.
  std::exception_ptr failed;
  try {
    certify_layers();
  } catch (...) {
    failed = std::current_exception();
  }
  group.wait();  // a worker's failure, if any, goes on from here
  if (failed) std::rethrow_exception(failed);

  std::vector<Rational> weighted;
  for (const LayerCertificate& lc : cert.layers) weighted.push_back(Rational(tree.depth - lc.level + 1) * lc.omv);
  cert.weighted_error = sum_pairwise(weighted);
  cert.seconds = seconds_since(t0);
  return cert;
}

int layer_workers(int layers, int concurrency, bool uses_nef, size_t faces, double available_bytes) {
  int workers = std::min(layers, concurrency);
  if (uses_nef) {
    const double fit = std::floor(available_bytes / (kNefBytesPerFace * static_cast<double>(std::max<size_t>(faces, 1))));
    if (fit < workers) workers = static_cast<int>(fit);
  }
  return std::max(1, workers);
}

double available_memory_bytes() {
  std::FILE* f = std::fopen("/proc/meminfo", "r");
  if (f == nullptr) return std::numeric_limits<double>::infinity();
  char line[256];
  double kib = -1;
  while (std::fgets(line, sizeof line, f) != nullptr)
    if (std::sscanf(line, "MemAvailable: %lf kB", &kib) == 1) break;
  std::fclose(f);
  return kib >= 0 ? kib * 1024 : std::numeric_limits<double>::infinity();
}

namespace {

constexpr const char* kObvFormat = "vobb-certify-obv";
constexpr const char* kLayersFormat = "vobb-certify-layers";

// "p/q" (or "p") in base 10, q > 0, as mpq_class writes it; false for anything else, and for a
// zero denominator, which mpq would divide by.
bool parse_rational(const nlohmann::json& v, Rational* out) {
  if (!v.is_string()) return false;
  const std::string& text = v.get_ref<const std::string&>();
  const size_t slash = text.find('/');
  mpz_class num, den(1);
  auto whole = [](const std::string& digits, mpz_class* z, bool sign_ok) {
    if (digits.empty()) return false;
    for (size_t i = 0; i < digits.size(); ++i)
      if (!(std::isdigit(static_cast<unsigned char>(digits[i])) || (sign_ok && i == 0 && digits[i] == '-' && digits.size() > 1)))
        return false;
    return z->set_str(digits, 10) == 0;
  };
  if (!whole(text.substr(0, slash), &num, true)) return false;
  if (slash != std::string::npos && !whole(text.substr(slash + 1), &den, false)) return false;
  if (den == 0) return false;
  *out = Rational(num, den);
  out->canonicalize();
  return true;
}

// Reads one of the two files: JSON object, format, known fields, checksum, fingerprint.
// *text gets the file's bytes.
// `fingerprint` null: the file is checked as a file (JSON, format, fields, checksum), not as
// this certification's.
Status read_checkpoint_file(const std::string& path, const char* format, const std::set<std::string>& known,
                            const std::string* fingerprint, nlohmann::json* j, std::string* text) {
  const Status read = read_regular_file(path, path, "checkpoint file", text);
  if (!read) return read;
  auto bad = [&](const std::string& why) { return Status::error(path + ": damaged certify checkpoint: " + why); };
  // The deepest values are at depth 2 (layers.json: file, layers, a layer); 8 leaves room.
  bool too_deep = false;
  if (!parse_json_within(*text, 8, j, &too_deep) || !j->is_object())
    return bad(too_deep ? "nested deeper than a checkpoint can be" : "not JSON");
  // Types first: value() throws on a field of another type ("format": 5).
  const bool format_ok = j->contains("format") && (*j)["format"].is_string() && (*j)["format"].get<std::string>() == format;
  const bool version_ok = j->contains("version") && (*j)["version"].is_number_integer() && (*j)["version"].get<int64_t>() == 1;
  if (!format_ok || !version_ok) return bad("not a vobb certify checkpoint");
  for (const auto& item : j->items())
    if (!known.count(item.key())) return bad("unknown field '" + item.key().substr(0, 40) + "'");
  if (!j->contains("sha256") || !(*j)["sha256"].is_string() || (*j)["sha256"].get<std::string>() != json_checksum(*j))
    return bad("checksum does not match the contents");
  if (!j->contains("fingerprint") || !(*j)["fingerprint"].is_string()) return bad("no fingerprint");
  if (fingerprint == nullptr) return Status::ok();
  if ((*j)["fingerprint"].get<std::string>() != *fingerprint)
    return Status::error(path + ": checkpoint of another certification (mesh, tree, path or certify version differ); "
                         "use another --checkpoint folder or remove it");
  return Status::ok();
}

const std::set<std::string> kObvFields = {"format", "version", "fingerprint", "obv", "sha256"};
const std::set<std::string> kLayersFields = {"format", "version", "fingerprint", "obv_sha256", "layers", "sha256"};

// Both files of a checkpoint, each checked as read_checkpoint_file checks it. An absent file
// leaves its JSON null; layers.json without obv.json is damage.
Status read_checkpoint_files(const std::string& obv_file, const std::string& layers_file, const std::string* fingerprint,
                             nlohmann::json* obv, nlohmann::json* layers) {
  *obv = nlohmann::json();
  *layers = nlohmann::json();
  const bool has_obv = !path_absent(obv_file), has_layers = !path_absent(layers_file);
  if (has_layers && !has_obv)
    return Status::error(layers_file + ": damaged certify checkpoint: layers without the boxes' OBV (" + obv_file + ")");
  std::string text;
  if (has_obv) {
    Status s = read_checkpoint_file(obv_file, kObvFormat, kObvFields, fingerprint, obv, &text);
    if (!s) return s;
  }
  if (has_layers) {
    Status s = read_checkpoint_file(layers_file, kLayersFormat, kLayersFields, fingerprint, layers, &text);
    if (!s) return s;
  }
  return Status::ok();
}

// Whether layers.json (read, not null) names obv.json (read) by its checksum: it was written
// after that obv.json, not another.
bool layers_name_obv(const nlohmann::json& obv, const nlohmann::json& layers) {
  return layers.contains("obv_sha256") && layers["obv_sha256"].is_string() && layers["obv_sha256"] == obv["sha256"];
}
constexpr const char* kLayersOfAnotherObv = "its layers belong to another obv.json";

}  // namespace

Status CertifyCheckpoint::check_files(const std::string& folder) {
  nlohmann::json obv, layers;
  const std::string layers_file = folder + "/layers.json";
  Status s = read_checkpoint_files(folder + "/obv.json", layers_file, nullptr, &obv, &layers);
  if (s && !layers.is_null() && !layers_name_obv(obv, layers))
    return Status::error(layers_file + ": damaged certify checkpoint: " + kLayersOfAnotherObv);
  return s;
}

struct CertifyCheckpoint::Written {
  std::map<int, nlohmann::json> layers;
};

CertifyCheckpoint::CertifyCheckpoint(std::string folder, std::string fingerprint)
    : folder_(std::move(folder)), fingerprint_(std::move(fingerprint)), written_(new Written) {}

CertifyCheckpoint::~CertifyCheckpoint() = default;

std::string CertifyCheckpoint::obv_path() const { return folder_ + "/obv.json"; }
std::string CertifyCheckpoint::layers_path() const { return folder_ + "/layers.json"; }

Status CertifyCheckpoint::save(const CertifyState& state) {
  if (!state.obv.empty() && obv_sha256_.empty()) {
    nlohmann::json j;
    j["format"] = kObvFormat;
    j["version"] = 1;
    j["fingerprint"] = fingerprint_;
    nlohmann::json obv = nlohmann::json::array();
    for (const Rational& q : state.obv) obv.push_back(q.get_str());
    j["obv"] = std::move(obv);
    j["sha256"] = json_checksum(j);
    const std::string text = j.dump() + "\n";
    const Status w = write_file_atomic(obv_path(), text);
    if (!w) return w;
    obv_sha256_ = j["sha256"].get<std::string>();
  }
  if (obv_sha256_.empty()) return Status::ok();  // nothing finished yet
  nlohmann::json j;
  j["format"] = kLayersFormat;
  j["version"] = 1;
  j["fingerprint"] = fingerprint_;
  j["obv_sha256"] = obv_sha256_;
  nlohmann::json layers = nlohmann::json::array();
  for (const LayerCertificate& l : state.layers) {
    // A finished layer does not change: its decimal strings (up to some 10^5 digits each) are
    // made once, not at every save.
    auto cached = written_->layers.find(l.level);
    if (cached != written_->layers.end()) {
      layers.push_back(cached->second);
      continue;
    }
    nlohmann::json jl = {{"level", l.level},
                         {"boxes", l.boxes},
                         {"overlapping_boxes", l.overlapping_boxes},
                         {"omv", l.omv.get_str()},
                         {"sum_obv", l.sum_obv.get_str()},
                         {"omv_path", l.omv_path},
                         {"seconds", l.seconds}};
    if (l.omv_path == "both") {
      jl["paths_agree"] = l.paths_agree;
      jl["omv_clip"] = l.omv_clip.get_str();
    }
    layers.push_back(jl);
    written_->layers.emplace(l.level, std::move(jl));
  }
  j["layers"] = std::move(layers);
  j["sha256"] = json_checksum(j);
  return write_file_atomic(layers_path(), j.dump() + "\n");
}

Status CertifyCheckpoint::load(const Tree& tree, CertifyState* state, bool* found) {
  *found = false;
  const std::string obv_file = obv_path(), layers_file = layers_path();
  if (path_absent(obv_file) && path_absent(layers_file)) return Status::ok();
  *found = true;
  CertifyState s;
  std::string current;  // the file being read, for the messages
  auto bad = [&](const std::string& why) { return Status::error(current + ": damaged certify checkpoint: " + why); };
  try {
    nlohmann::json jo, j;
    Status r = read_checkpoint_files(obv_file, layers_file, &fingerprint_, &jo, &j);
    if (!r) return r;
    current = obv_file;
    const std::string obv_sha = jo["sha256"].get<std::string>();  // checked: the checksum of its contents
    const nlohmann::json& obv = jo.at("obv");
    if (!obv.is_array() || obv.size() != tree.nodes.size())
      return bad("OBV of " + std::to_string(obv.size()) + " boxes for a tree of " + std::to_string(tree.nodes.size()));
    for (size_t i = 0; i < obv.size(); ++i) {
      Rational q;
      if (!parse_rational(obv[i], &q)) return bad("OBV of node " + std::to_string(i) + " is not a rational");
      s.obv.push_back(q);
    }
    if (!j.is_null()) {
      current = layers_file;
      if (!layers_name_obv(jo, j)) return bad(kLayersOfAnotherObv);
      const nlohmann::json& layers = j.at("layers");
      if (!layers.is_array()) return bad("layers is not a list");
      std::vector<char> seen(tree.depth + 1, 0);
      for (const nlohmann::json& jl : layers) {
        LayerCertificate l;
        if (!jl.is_object()) return bad("a layer is not an object");
        const nlohmann::json& level = jl.at("level");
        if (!level.is_number_integer() || level.get<int64_t>() < 0 || level.get<int64_t>() > tree.depth)
          return bad("a layer's level is not an integer in 0.." + std::to_string(tree.depth));
        l.level = static_cast<int>(level.get<int64_t>());
        const std::string at = "layer " + std::to_string(l.level) + ": ";
        if (seen[l.level]) return bad(at + "given twice");
        seen[l.level] = 1;
        // Every field must be one the writer puts there for the layer's path.
        const bool both = jl.contains("omv_path") && jl["omv_path"] == "both";
        for (const auto& item : jl.items()) {
          static const std::set<std::string> kLayerFields{"level", "boxes",    "overlapping_boxes", "omv",
                                                          "sum_obv", "omv_path", "seconds"};
          if (!kLayerFields.count(item.key()) && !(both && (item.key() == "paths_agree" || item.key() == "omv_clip")))
            return bad(at + "unknown field '" + item.key().substr(0, 40) + "'");
        }
        const std::vector<int32_t> ids = layer(tree, l.level);
        const nlohmann::json& boxes = jl.at("boxes");
        const nlohmann::json& overlapping = jl.at("overlapping_boxes");
        if (!boxes.is_number_unsigned() || boxes.get<uint64_t>() != ids.size())
          return bad(at + "box count is not the tree's");
        if (!overlapping.is_number_unsigned() || overlapping.get<uint64_t>() > ids.size())
          return bad(at + "overlapping boxes are not a count up to its boxes");
        l.boxes = ids.size();
        l.overlapping_boxes = overlapping.get<uint64_t>();
        if (!parse_rational(jl.at("omv"), &l.omv) || !parse_rational(jl.at("sum_obv"), &l.sum_obv))
          return bad(at + "OMV or sum of OBV is not a rational");
        std::vector<Rational> obvs;
        for (int32_t id : ids) obvs.push_back(s.obv[id]);
        if (sum_pairwise(obvs) != l.sum_obv) return bad(at + "sum of OBV is not the sum of its boxes' OBV");
        l.omv_path = jl.at("omv_path").get<std::string>();
        if (l.omv_path == "none") {
          if (l.omv != l.sum_obv || l.overlapping_boxes != 0)
            return bad(at + "path none, but OMV is not the sum of OBV or boxes overlap");
        } else if (l.omv_path == "both") {
          if (!parse_rational(jl.at("omv_clip"), &l.omv_clip)) return bad(at + "clipping's OMV is not a rational");
          l.paths_agree = jl.at("paths_agree").get<bool>();
          if (l.paths_agree != (l.omv == l.omv_clip)) return bad(at + "paths_agree contradicts the two OMV");
        } else if (l.omv_path != "nef" && l.omv_path != "clip") {
          return bad(at + "unknown path '" + l.omv_path.substr(0, 20) + "'");
        }
        const nlohmann::json& seconds = jl.at("seconds");
        if (!seconds.is_number() || !(seconds.get<double>() >= 0)) return bad(at + "seconds is not a time");
        l.seconds = seconds.get<double>();
        s.layers.push_back(std::move(l));
      }
    }
    obv_sha256_ = obv_sha;
  } catch (const nlohmann::json::exception& e) {
    // A field missing or of another type: nlohmann's one-line reason ("key 'x' not found",
    // "type must be boolean, but is string") without its "[json.exception.type_error.302] ".
    const std::string what = e.what();
    const size_t tag = what.rfind("[json.exception.", 0) == 0 ? what.find("] ") : std::string::npos;
    return bad(tag == std::string::npos ? what : what.substr(tag + 2));
  }
  *state = std::move(s);
  return Status::ok();
}

}  // namespace vobb::exact
