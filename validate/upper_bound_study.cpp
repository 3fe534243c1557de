#include "validate/upper_bound_study.h"

#include <chrono>
#include <cstdio>

#include "common/stopwatch.h"
#include "exact/certify.h"
#include "vobb/vobb.h"

namespace vobb::validate {
bool UpperBoundResult::all_exact_hold() const {
  for (const LayerBoundRow& l : layers)
    if (!l.exact_holds || !l.paths_agree) return false;
  for (const TreeCheck& t : trees)
    if (!t.containment_ok) return false;
  return true;
}

bool UpperBoundResult::all_estimated_hold_with_bound() const {
  for (const LayerBoundRow& l : layers)
    for (const auto& e : l.estimated)
      if (!e.above_with_bound) return false;
  return true;
}

UpperBoundResult run_upper_bound_study(const UpperBoundConfig& config, const StatedBound& bound) {
  const auto t0 = std::chrono::steady_clock::now();
  UpperBoundResult r;
  auto say = [&](const std::string& line) {
    if (config.progress) config.progress(line);
  };
  for (const NamedMesh& nm : config.meshes) {
    const Mesh& mesh = *nm.mesh;
    EstimatorSet est(mesh, config.want_gl, config.perturb);
    for (const char* builder : {"obbtree", "variational"}) {
      const auto tb = std::chrono::steady_clock::now();
      // The variational builder's estimator is the unperturbed CPU twin: the trees are the
      // object under test here, and the perturbation reaches the estimated sums below.
      BuildOptions o;
      o.method = std::string(builder) == "obbtree" ? Method::kObbTree : Method::kVariational;
      o.depth = config.depth;
      o.lloyd = config.lloyd_iterations;
      o.sweeps = config.max_sweeps;
      o.m = config.variational_m;
      o.backend = vobb::Backend::kCpu;
      // build_tree's default objective, named here as the report names it.
      if (o.method == Method::kVariational) o.objective = Objective::kOmv;
      Tree tree;
      const Status built = build_tree(mesh, o, &tree);
      VOBB_ASSERT(built, built.message().c_str());  // the options are the study's own
      TreeCheck tc{nm.name, builder};
      tc.build_seconds = seconds_since(tb);
      exact::CertifyOptions co;
      co.path = exact::OmvPath::kAuto;
      co.rational = true;  // the study decides estimates against the exact OMV, as rationals
      const exact::Certificate cert = exact::certify(mesh, tree, co);
      tc.certify_seconds = cert.seconds;
      tc.containment_ok = cert.containment.ok();
      tc.weighted_error = to_double_nearest(cert.weighted_error);
      r.trees.push_back(tc);
      for (const exact::LayerCertificate& lc : cert.layers) {
        LayerBoundRow row;
        row.mesh = nm.name;
        row.builder = builder;
        row.level = lc.level;
        row.boxes = lc.boxes;
        row.overlapping_boxes = lc.overlapping_boxes;
        row.omv = lc.omv;
        row.sum_obv = lc.sum_obv;
        row.exact_holds = lc.upper_bound_holds();  // sum_obv >= omv, rationals
        row.paths_agree = lc.paths_agree;
        row.gap = to_double_nearest(lc.overlap());
        row.gap_relative = lc.omv > 0 ? to_double_nearest(Rational(lc.overlap() / lc.omv)) : 0.0;
        row.omv_path = lc.omv_path;
        std::vector<Obb> boxes;
        for (int32_t id : layer(tree, lc.level)) boxes.push_back(tree.nodes[id].box);
        for (int m : config.ms) {
          std::vector<double> secs;
          const std::vector<double> v = est.estimate(Backend::kCpu, boxes, m, &secs);
          LayerBoundRow::Estimated e;
          e.m = m;
          for (size_t j = 0; j < boxes.size(); ++j) {
            e.sum += v[j];
            e.allowance += bound.per_volume(m) * volume(boxes[j]);
          }
          // Exact comparisons of the computed doubles (a double is an exact rational); a NaN
          // sum fails both.
          e.above = std::isfinite(e.sum) && Rational(e.sum) >= lc.omv;
          const double with = e.sum + e.allowance;
          e.above_with_bound = std::isfinite(with) && Rational(with) >= lc.omv;
          row.estimated.push_back(e);
        }
        r.layers.push_back(row);
      }
      char buf[160];
      std::snprintf(buf, sizeof buf, "%s %s depth %d: built in %.1f s, certified in %.1f s",
                    nm.name.c_str(), builder, tree.depth, tc.build_seconds, tc.certify_seconds);
      say(buf);
    }
  }
  r.seconds = seconds_since(t0);
  return r;
}

}  // namespace vobb::validate
