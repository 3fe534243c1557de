// vobb compare MESH: both builders, both trees certified (vobb/vobb.h, compare): OMV per layer,
// its change, and each tree's e; with --figure, both trees drawn (vobb/gl.h); with --tree, the
// variational tree written as `build -o` writes it.
#include <cstdio>
#include <memory>
#include <nlohmann/json.hpp>
#include <string>

#include "app/build_flags.h"
#include "app/cli_support.h"
#include "app/command.h"
#include "common/io/mesh_report.h"
#include "common/tree_io.h"
#include "vobb/gl.h"
#include "vobb/vobb.h"

namespace vobb::app {

namespace {

double change(double a, double b) { return a == 0 ? 0.0 : 100.0 * (b - a) / a; }

void print_json(const CompareResult& r, bool rational, bool single_precision) {
  nlohmann::ordered_json doc, rows = nlohmann::ordered_json::array();
  for (size_t l = 0; l < r.levels; ++l) {
    const double a = r.layer(0, l).omv_nearest, b = r.layer(1, l).omv_nearest;
    nlohmann::ordered_json row = {
        {"level", l}, {"omv_baseline", a}, {"omv_variational", b}, {"change_pct", change(a, b)}};
    if (rational) {
      row["omv_baseline_rational"] = r.layer(0, l).omv.get_str();
      row["omv_variational_rational"] = r.layer(1, l).omv.get_str();
    }
    rows.push_back(row);
  }
  doc["levels"] = rows;
  doc["mesh_single_precision"] = single_precision;
  doc["depth_baseline"] = r.trees[0].depth;
  doc["depth_variational"] = r.trees[1].depth;
  doc["e_baseline"] = r.e[0];
  doc["e_variational"] = r.e[1];
  if (rational) {
    doc["e_baseline_rational"] = r.e_exact[0].get_str();
    doc["e_variational_rational"] = r.e_exact[1].get_str();
  }
  doc["seconds_baseline"] = r.build_seconds[0];
  doc["seconds_variational"] = r.build_seconds[1];
  doc["certified"] = r.certified();
  std::printf("%s\n", report_json(doc).c_str());
}

void print_text(const CompareResult& r, bool rational) {
  std::printf("%5s %24s %24s %10s\n", "layer", "OMV obbtree", "OMV variational", "change %");
  for (size_t l = 0; l < r.levels; ++l) {
    const double a = r.layer(0, l).omv_nearest, b = r.layer(1, l).omv_nearest;
    std::printf("%5zu %24.17g %24.17g %+10.2f\n", l, a, b, change(a, b));
  }
  if (r.trees[0].depth != r.trees[1].depth)
    std::printf(
        "\nthe obbtree tree has depth %d and the variational one %d: the shallower one's leaf "
        "layer is repeated "
        "below its last, and both e are over layers 0..%zu\n",
        r.trees[0].depth, r.trees[1].depth, r.levels - 1);
  std::printf("\ne obbtree %.17g, e variational %.17g, change %+.2f %%\n", r.e[0], r.e[1],
              change(r.e[0], r.e[1]));
  if (rational) {
    for (size_t l = 0; l < r.levels; ++l)
      std::printf(
          "layer %zu OMV obbtree (rational): %s\nlayer %zu OMV variational (rational): %s\n", l,
          r.layer(0, l).omv.get_str().c_str(), l, r.layer(1, l).omv.get_str().c_str());
    std::printf("e obbtree (rational): %s\ne variational (rational): %s\n",
                r.e_exact[0].get_str().c_str(), r.e_exact[1].get_str().c_str());
  }
  std::printf("build seconds: obbtree %.3f, variational %.3f; both certified: %s\n",
              r.build_seconds[0], r.build_seconds[1], r.certified() ? "yes" : "NO");
}

class CompareCommand final : public Command {
 public:
  CLI::App* add(CLI::App& app) override {
    cmd_ = app.add_subcommand("compare",
                              "Both builders, both trees certified exactly: OMV per layer and e");
    cmd_->add_option("MESH", mesh_, "Solid mesh")->required();
    add_build_flags(cmd_, &flags_, /*compare=*/true);
    cmd_->add_flag("--json", json_, "Print JSON (DESIGN §7)");
    cmd_->add_flag("--rational", rational_,
                   "Also print each exact value (OMV per layer, e) as a rational");
    cmd_->add_option("--figure", figure_,
                     "Also draw both trees' boxes at levels 1..8 over the mesh to this PNG")
        ->check(kPath);
    cmd_->add_option("--tree", tree_,
                     "Also write the variational tree it built and certified (as build -o does)")
        ->check(kPath);
    cmd_->add_option("--figure-up", figure_up_,
                     "The mesh's up axis in the figure: x, y, z, -x, -y or -z")
        ->capture_default_str()
        ->check(CLI::IsMember({"x", "y", "z", "-x", "-y", "-z"}))
        ->needs(cmd_->get_option("--figure"));
    return cmd_;
  }

  Status check_outputs() const override {
    Status s = check_build_flags(cmd_, flags_);
    if (s) s = check_output_is_not_input("--figure", figure_, {mesh_});
    if (s)
      s = check_output_is_not_checkpoint("--figure", figure_, flags_.options.checkpoint,
                                         compare_checkpoint_files());
    if (s) s = check_output_is_writable("--figure", figure_);
    if (s) s = check_output_is_not_input("--tree", tree_, {mesh_});
    if (s)
      s = check_output_is_not_checkpoint("--tree", tree_, flags_.options.checkpoint,
                                         compare_checkpoint_files());
    if (s) s = check_outputs_differ("--tree", tree_, "--figure", figure_);
    if (s) s = check_output_is_writable("--tree", tree_);
    // A file the figure makes is named .png; a device or pipe (/dev/stdout) takes it as it is.
    std::error_code ec;
    const auto st = std::filesystem::status(figure_, ec);
    if (s && !figure_.empty() && extension_of(figure_) != "png" &&
        !(std::filesystem::exists(st) && !std::filesystem::is_regular_file(st)))
      s = Status::error("--figure " + figure_ + ": the figure is a PNG; name a .png file");
    return s;
  }

  int threads() const override { return flags_.threads; }

  int run() override {
    LoadedMesh loaded;
    Status s = load_input_solid(mesh_, &loaded);
    if (!s) return refuse(s);
    std::unique_ptr<FigureContext> figure_context;
    if (!figure_.empty()) {  // before the run, not after it
      s = FigureContext::create(&figure_context);
      if (!s) return refuse(Status::error(figure_ + ": " + s.message()));
    }
    CompareOptions o;
    o.build = build_options(flags_);
    o.rational = rational_;
    o.certify_saved = certify_kill_hook();
    if (!flags_.quiet)
      o.progress = [](const std::string& line) {
        std::fprintf(stderr, "vobb: %s\n", line.c_str());
      };
    CompareResult r;
    s = compare(loaded.mesh, o, &r);
    if (!s) return refuse(s);
    if (!tree_.empty()) {
      s = write_tree(r.trees[1], tree_);
      if (!s) return could_not_finish(s);  // its folder took a file when the run started
    }
    if (json_)
      print_json(r, rational_, loaded.single_precision);
    else
      print_text(r, rational_);
    if (!figure_.empty()) {
      CompareFigure fig;
      RgbaImage image;
      s = draw_compare_figure(loaded.mesh, r, figure_up_, o.build.note, &image, &fig,
                              figure_context.get());
      if (!s) return could_not_finish(Status::error(figure_ + ": " + s.message()));
      s = write_png(figure_, image);
      if (!s) return could_not_finish(s);  // its folder took a file when the run started
      std::fprintf(stderr,
                   "vobb: figure %s: %dx%d px; row 1 obbtree (baseline), row 2 variational; "
                   "columns levels %d..%d\n",
                   figure_.c_str(), fig.width, fig.height, fig.first_level, fig.last_level);
    }
    return r.certified() ? kExitOk : kExitCheckFailed;
  }

 private:
  CLI::App* cmd_ = nullptr;
  std::string mesh_, figure_, tree_, figure_up_ = "y";
  bool json_ = false, rational_ = false;
  BuildFlags flags_;
};

}  // namespace

std::unique_ptr<Command> compare_command() { return std::make_unique<CompareCommand>(); }

}  // namespace vobb::app
