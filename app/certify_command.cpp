// vobb certify MESH TREE: the exact certificate (vobb/vobb.h, certify), as text or JSON.
#include <cstdio>
#include <memory>
#include <nlohmann/json.hpp>
#include <string>

#include "app/build_flags.h"
#include "app/cli_support.h"
#include "app/command.h"
#include "common/io/mesh_report.h"
#include "common/tree_io.h"
#include "vobb/vobb.h"

namespace vobb::app {

namespace {

constexpr const char* kThreadsHelp =
    "Threads for the boxes' OBV and for the layers, one layer per thread at a time (default: every "
    "core this process may use); the values are exact, so the same for any number. Each thread "
    "that computes a union holds its own Nef polyhedron of the mesh";

nlohmann::ordered_json enclosure(const MpInterval& x) {
  return nlohmann::ordered_json::array({x.inf(), x.sup()});
}

nlohmann::ordered_json layer_json(const exact::LayerCertificate& l, bool rational) {
  nlohmann::ordered_json j;
  j["level"] = l.level;
  j["boxes"] = l.boxes;
  j["omv"] = l.omv_nearest;
  j["sum_obv"] = l.sum_obv_nearest;
  j["overlap"] = l.overlap_nearest;
  // Outward doubles around the exact values, and what decided the doubles above.
  j["omv_enclosure"] = enclosure(l.omv_enclosure);
  j["sum_obv_enclosure"] = enclosure(l.sum_obv_enclosure);
  j["overlap_enclosure"] = enclosure(l.overlap_enclosure);
  j["omv_rounded_by"] = l.omv_rounded_by;
  j["sum_obv_rounded_by"] = l.sum_obv_rounded_by;
  j["overlap_rounded_by"] = l.overlap_rounded_by;
  j["upper_bound_holds"] = l.upper_bound_holds();
  j["bound_by"] = l.bound_by;
  j["exact_obv"] = l.exact_obv;
  j["exact_overlap"] = l.exact_overlap;
  j["refined_obv"] = l.refined_obv;
  j["refined_overlap"] = l.refined_overlap;
  j["overlapping_boxes"] = l.overlapping_boxes;
  j["omv_path"] = l.omv_path;
  if (l.omv_path == "both") {
    j["paths_agree"] = l.paths_agree;
    j["omv_clip"] = to_double_nearest(l.omv_clip);  // omv is Nef's, the arbiter's
  }
  j["seconds"] = l.seconds;
  if (rational) {
    j["omv_rational"] = l.omv.get_str();
    j["sum_obv_rational"] = l.sum_obv.get_str();
    j["overlap_rational"] = l.overlap().get_str();
    if (l.omv_path == "both") j["omv_clip_rational"] = l.omv_clip.get_str();
  }
  return j;
}

void print_json(const exact::Certificate& c, bool rational, bool single_precision) {
  nlohmann::ordered_json j;
  nlohmann::ordered_json levels = nlohmann::ordered_json::array();
  for (const auto& l : c.layers) levels.push_back(layer_json(l, rational));
  j["levels"] = levels;
  j["mesh_single_precision"] = single_precision;
  j["weighted_error"] = c.weighted_error_nearest;
  j["weighted_error_enclosure"] = enclosure(c.weighted_error_enclosure);
  j["weighted_error_rounded_by"] = c.weighted_error_rounded_by;
  if (rational) j["weighted_error_rational"] = c.weighted_error.get_str();
  j["exact_obv"] = c.exact_obv;
  nlohmann::ordered_json first = nlohmann::ordered_json::array();
  for (const auto& [node, face] : c.containment.first)
    first.push_back({{"node", node}, {"face", face}});
  j["containment"] = {{"ok", c.containment.ok()},
                      {"violations", c.containment.violations},
                      {"checked_pairs", c.containment.checked_pairs},
                      {"first", first}};
  j["seconds"] = c.seconds;
  std::printf("%s\n", report_json(j).c_str());
}

void print_text(const exact::Certificate& c, bool rational) {
  std::printf("%5s %7s %24s %24s %24s %6s\n", "level", "boxes", "OMV", "sum OBV", "overlap",
              "bound");
  for (const auto& l : c.layers)
    std::printf("%5d %7zu %24.17g %24.17g %24.17g %6s\n", l.level, l.boxes, l.omv_nearest,
                l.sum_obv_nearest, l.overlap_nearest, l.upper_bound_holds() ? "holds" : "FAILS");
  std::printf("weighted error e: %.17g\n", c.weighted_error_nearest);
  if (rational) {
    for (const auto& l : c.layers) {
      std::printf("level %d OMV (rational): %s\n", l.level, l.omv.get_str().c_str());
      if (l.omv_path == "both")
        std::printf("level %d OMV by clipping (rational): %s\n", l.level,
                    l.omv_clip.get_str().c_str());
      std::printf("level %d sum OBV (rational): %s\n", l.level, l.sum_obv.get_str().c_str());
      std::printf("level %d overlap (rational): %s\n", l.level, l.overlap().get_str().c_str());
    }
    std::printf("e (rational): %s\n", c.weighted_error.get_str().c_str());
  }
  std::printf("containment: %s (%zu violations in %zu node-face pairs)",
              c.containment.ok() ? "ok" : "FAILED", c.containment.violations,
              c.containment.checked_pairs);
  for (const auto& [node, face] : c.containment.first)
    std::printf(" [node %d face %d]", node, face);
  std::printf("\nseconds: %.3f\n", c.seconds);
}

class CertifyCommand final : public Command {
 public:
  CLI::App* add(CLI::App& app) override {
    CLI::App* c = app.add_subcommand("certify", "Exact OMV, sum of OBV and containment per layer");
    c->add_option("MESH", mesh_, "The solid mesh the tree was built for")->required();
    c->add_option("TREE", tree_path_, "Tree file")->required();
    c->add_flag("--json", json_, "Print JSON");
    c->add_flag(
        "--rational", rational_,
        "Also compute and print the exact values as rationals (OMV by Nef where boxes overlap)");
    c->add_option("--path", path_,
                  "auto: enclosures, rationals only where a sign or a rounding needs them; clip or "
                  "nef: every value "
                  "in rationals by that path; both: auto, and Nef's and clipping's rationals "
                  "compared with it")
        ->capture_default_str()
        ->check(CLI::IsMember({"auto", "clip", "nef", "both"}));
    c->add_flag("--quiet", quiet_, "No per-layer progress on stderr");
    c->add_option("--checkpoint", checkpoint_,
                  "Folder for what is certified so far (obv.json: the boxes' OBV; layers.json: "
                  "each finished "
                  "layer); a run started again with the same folder resumes it and prints the same "
                  "certificate")
        ->check(kPath);
    c->add_option("--threads", threads_, kThreadsHelp)
        ->transform(kCount)
        ->check(CLI::Range(1, 4096));
    return c;
  }

  int threads() const override { return threads_; }

  int run() override {
    LoadedMesh mesh;
    Status s = load_input_solid(mesh_, &mesh);
    if (!s) return refuse(s);
    Tree tree;
    s = read_tree(tree_path_, &tree);
    if (!s) return refuse(s);
    CertifyOptions o;
    o.path = path_ == "clip"   ? exact::OmvPath::kClip
             : path_ == "nef"  ? exact::OmvPath::kNef
             : path_ == "both" ? exact::OmvPath::kBoth
                               : exact::OmvPath::kAuto;
    o.rational = rational_;
    o.checkpoint = checkpoint_;
    o.tree_name = tree_path_;
    if (!quiet_)
      o.progress = [](const std::string& line) {
        std::fprintf(stderr, "certify: %s\n", line.c_str());
      };
    // A resumed state is said even with --quiet: it is what the certificate rests on.
    o.note = o.warning = [](const std::string& line) {
      std::fprintf(stderr, "vobb: %s\n", one_line(line).c_str());
    };
    o.saved = certify_kill_hook();  // build_flags.h
    exact::Certificate c;
    s = certify(mesh.mesh, tree, o, &c);
    if (!s) return refuse(s);
    if (json_)
      print_json(c, rational_, mesh.single_precision);
    else
      print_text(c, rational_);
    if (!c.ok()) {
      std::fprintf(stderr, "vobb: %s: certification failed\n", one_line(tree_path_).c_str());
      return kExitCheckFailed;
    }
    return kExitOk;
  }

 private:
  std::string mesh_, tree_path_, path_ = "auto", checkpoint_;
  bool json_ = false, rational_ = false, quiet_ = false;
  int threads_ = 0;
};

}  // namespace

std::unique_ptr<Command> certify_command() { return std::make_unique<CertifyCommand>(); }

}  // namespace vobb::app
