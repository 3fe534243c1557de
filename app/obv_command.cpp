// vobb obv MESH --boxes B: OBV of boxes by the chosen backends (vobb/vobb.h, estimate_obv).
#include <cmath>
#include <cstdio>
#include <memory>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "app/cli_support.h"
#include "app/command.h"
#include "common/exact_predicates.h"
#include "common/io/mesh_report.h"
#include "common/obb.h"
#include "common/tree_io.h"
#include "vobb/vobb.h"

namespace vobb::app {

namespace {

class ObvCommand final : public Command {
 public:
  CLI::App* add(CLI::App& app) override {
    CLI::App* c = app.add_subcommand(
        "obv",
        "OBV of boxes by --backend: cubemap estimates at several m (gl, cpu), the polyhedral "
        "solver's interval (poly), the exact value (exact), or all of them (all)");
    c->add_option("MESH", mesh_, "Solid mesh")->required();
    c->add_option("--boxes", boxes_path_, "Box file {\"boxes\":[{center, axes, half_extents}]}")
        ->required();
    m_option_ = c->add_option("--m", ms_text_, "Cubemap resolutions in [1, 4096], comma-separated")
                    ->capture_default_str()
                    ->check(count_list(1, 4096));
    c->add_option("--backend", backend_,
                  "gl (EGL: a GPU, else llvmpipe), cpu (the double-precision twin), poly (the "
                  "polyhedral solver: "
                  "an estimate and its certified interval), exact, all, or auto (gl, else cpu with "
                  "a warning)")
        ->capture_default_str()
        ->check(CLI::IsMember({"auto", "gl", "cpu", "poly", "exact", "all"}));
    c->add_flag("--r-bound", r_bound_,
                "Also print R(m), the cubemap's rigorous texel bound, beside each cubemap "
                "estimate's certified error");
    c->add_flag("--json", json_, "Print JSON");
    c->add_flag("--rational", rational_,
                "With the exact backend, also print each exact OBV as a rational");
    return c;
  }

  int run() override {
    EstimateOptions o;
    const bool all = backend_ == "all";
    o.exact = backend_ == "exact" || all;
    o.poly = backend_ == "poly" || all;
    o.cpu = backend_ == "cpu" || all;
    // A GL context only where GL is asked for; auto and all fall back to the CPU twin.
    o.gl = backend_ == "gl" || backend_ == "auto" || all;
    o.gl_fallback = backend_ != "gl";
    o.ms = split_counts(ms_text_);
    o.r_bound = r_bound_;
    o.rational = rational_;
    // Flags that would change nothing for the backends asked for are refused, not ignored.
    const bool cubemap = o.cpu || o.gl;
    if (m_option_->count() > 0 && !cubemap)
      return refuse(Status::error("--m: the " + backend_ +
                                  " backend has no resolution; it is for gl, cpu, auto and all"));
    if (r_bound_ && !cubemap)
      return refuse(Status::error("--r-bound: the " + backend_ +
                                  " backend has no R(m); it is for gl, cpu, auto and all"));
    if (rational_ && !o.exact)
      return refuse(Status::error("--rational: the exact values come with --backend exact or all"));
    LoadedMesh mesh;
    Status s = load_input_solid(mesh_, &mesh);
    if (!s) return refuse(s);
    std::vector<Obb> boxes;
    s = read_boxes(boxes_path_, &boxes);
    if (!s) return refuse(s);
    o.note = [](const std::string& line) {
      std::fprintf(stderr, "vobb: %s\n", one_line(line).c_str());
    };
    ObvReport r;
    s = estimate_obv(mesh.mesh, boxes, o, &r);
    if (!s) return refuse(s);
    print(boxes, r, mesh.single_precision);
    return kExitOk;
  }

 private:
  void print(const std::vector<Obb>& boxes, const ObvReport& r, bool single_precision) const {
    const size_t n = boxes.size();
    const bool want_exact = backend_ == "exact" || backend_ == "all";
    const bool want_poly = backend_ == "poly" || backend_ == "all";
    nlohmann::ordered_json out = nlohmann::ordered_json::array();
    if (!json_)
      std::printf("%5s %8s %5s %24s %24s %12s %12s %10s%s%s\n", "box", "backend", "m", "OBV",
                  "exact", "rel.error", "bound", "seconds", r_bound_ ? "         R(m)" : "",
                  want_poly ? "  certified interval" : "");
    for (size_t i = 0; i < n; ++i) {
      nlohmann::ordered_json jb;
      jb["index"] = i;
      jb["box_volume"] = to_double_nearest(exact_volume(boxes[i]));
      if (r.unresolved[i]) jb["unresolved"] = true;
      if (!r.poly.empty()) {
        const PolyObv& p = r.poly[i];
        jb["interval"] = {p.lo, p.hi};
        jb["interval_faces"] = p.faces;              // faces visited
        jb["interval_exact_signs"] = p.exact_signs;  // vertex signs decided in rationals
        jb["interval_exact_faces"] = p.exact_faces;  // faces evaluated in rationals
        if (p.exact_box) jb["interval_from_exact"] = p.why;
      }
      if (want_exact) {
        jb["exact"] = r.exact[i];
        if (rational_) jb["exact_rational"] = r.exact_rational[i].get_str();
        jb["exact_seconds"] = r.exact_seconds[i];
      }
      nlohmann::ordered_json est = nlohmann::ordered_json::array();
      for (const ObvRun& run : r.runs) {
        nlohmann::ordered_json e = {{"backend", run.backend}};
        e["m"] = run.m > 0 ? nlohmann::ordered_json(run.m) : nlohmann::ordered_json(nullptr);
        e["obv"] = run.obv[i];
        e["bound"] = run.bound[i];
        if (r_bound_ && run.m > 0) e["r_bound"] = run.r_bound[i];
        e["seconds"] = run.seconds[i];
        est.push_back(e);
        if (!json_)
          print_row(i, run, want_exact ? &r.exact[i] : nullptr,
                    r.poly.empty() ? nullptr : &r.poly[i], want_poly);
      }
      if (!json_ && r.runs.empty())
        std::printf("%5zu %8s %5s %24.17g %24s %12s %12s %10.6f\n", i, "exact", "-", r.exact[i],
                    "-", "-", "-", r.exact_seconds[i]);
      jb["estimates"] = est;
      out.push_back(jb);
    }
    if (json_) {
      nlohmann::ordered_json doc;
      if (!r.renderer.empty()) doc["renderer"] = r.renderer;
      doc["mesh_single_precision"] = single_precision;
      doc["boxes"] = out;
      std::printf("%s\n", report_json(doc).c_str());
    } else if (rational_ && want_exact) {
      for (size_t i = 0; i < n; ++i)
        std::printf("box %zu exact (rational): %s\n", i, r.exact_rational[i].get_str().c_str());
    }
  }

  // One row of the table; with `exact`, the box's exact OBV and the estimate's relative error
  // from it, each correctly rounded (estimate_obv).
  void print_row(size_t i, const ObvRun& run, const double* exact, const PolyObv* poly,
                 bool want_poly) const {
    char rel[32] = "-", ex[40] = "-", mm[16] = "-", rb[24] = "", iv[64] = "";
    if (exact && !std::isnan(run.rel_error[i]))
      std::snprintf(rel, sizeof rel, "%.3e", run.rel_error[i]);
    if (exact) std::snprintf(ex, sizeof ex, "%.17g", *exact);
    if (run.m > 0) std::snprintf(mm, sizeof mm, "%d", run.m);
    if (r_bound_ && run.m > 0) std::snprintf(rb, sizeof rb, " %12.3e", run.r_bound[i]);
    if (r_bound_ && run.m == 0) std::snprintf(rb, sizeof rb, " %12s", "-");
    if (want_poly && run.m == 0 && poly)
      std::snprintf(iv, sizeof iv, "  [%.17g, %.17g]", poly->lo, poly->hi);
    std::printf("%5zu %8s %5s %24.17g %24s %12s %12.3e %10.6f%s%s\n", i, run.backend.c_str(), mm,
                run.obv[i], ex, rel, run.bound[i], run.seconds[i], rb, iv);
  }

  CLI::Option* m_option_ = nullptr;
  std::string mesh_, boxes_path_, backend_ = "auto";
  std::string ms_text_ = "8,16,32";
  bool r_bound_ = false, json_ = false, rational_ = false;
};

}  // namespace

std::unique_ptr<Command> obv_command() { return std::make_unique<ObvCommand>(); }

}  // namespace vobb::app
