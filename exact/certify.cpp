#include "exact/certify.h"

#include <chrono>
#include <cstdio>
#include <memory>

#include "exact/outer_volume.h"
#include "common/stopwatch.h"

namespace vobb::exact {

bool Certificate::ok() const {
  if (!containment.ok()) return false;
  for (const LayerCertificate& l : layers)
    if (!l.upper_bound_holds() || !l.paths_agree) return false;
  return true;
}

Certificate certify(const Mesh& mesh, const Tree& tree, const CertifyOptions& options) {
  const auto t0 = std::chrono::steady_clock::now();
  Certificate cert;
  auto say = [&](const std::string& line) {
    if (options.progress) options.progress(line);
  };
  cert.containment = check_conservative(mesh, tree);
  say("containment: " + std::to_string(cert.containment.violations) + " violations in " +
      std::to_string(cert.containment.checked_pairs) + " (node, face) pairs");

  ClipSolver clip(mesh);
  std::unique_ptr<NefSolver> nef;  // built only when a layer needs it
  auto need_nef = [&]() -> const NefSolver& {
    if (!nef) {
      const auto tn = std::chrono::steady_clock::now();
      nef = std::make_unique<NefSolver>(mesh);
      char buf[64];
      std::snprintf(buf, sizeof buf, "%.2f s", seconds_since(tn));
      say(std::string("Nef polyhedron of the mesh built in ") + buf);
    }
    return *nef;
  };

  // OBV once per node: a leaf above level i belongs to every later layer too.
  std::vector<Rational> obv(tree.nodes.size());
  std::vector<char> have_obv(tree.nodes.size(), 0);
  std::vector<Rational> weighted;
  for (int level = 0; level <= tree.depth; ++level) {
    const auto tl = std::chrono::steady_clock::now();
    LayerCertificate lc;
    lc.level = level;
    const std::vector<int32_t> ids = layer(tree, level);
    lc.boxes = ids.size();
    std::vector<Obb> boxes;
    std::vector<Rational> obvs;
    for (int32_t id : ids) {
      if (!have_obv[id]) {
        obv[id] = clip.obv(tree.nodes[id].box);
        have_obv[id] = 1;
      }
      boxes.push_back(tree.nodes[id].box);
      obvs.push_back(obv[id]);
    }
    lc.sum_obv = sum_pairwise(obvs);
    // Which boxes may meet another one (conservative bounds): boxes that overlap nothing skip
    // the union work.
    std::vector<char> overlapped = clip.may_overlap(boxes);
    for (char o : overlapped) lc.overlapping_boxes += o ? 1 : 0;
    OmvPath path = options.path;
    // Auto: Nef for layers with overlaps. Measured on dino (docs/BENCHMARKS.md), Nef's union
    // beats the clipping path's overlap cells on every overlapping layer of baseline trees.
    if (path == OmvPath::kAuto) path = OmvPath::kNef;
    if (lc.overlapping_boxes == 0 && path != OmvPath::kBoth) {
      lc.omv = lc.sum_obv;  // disjoint boxes: the union's outer volume is the sum
      lc.omv_path = "none";
    } else if (path == OmvPath::kNef) {
      lc.omv = need_nef().omv(boxes);
      lc.omv_path = "nef";
    } else {
      lc.omv = clip.omv(boxes, lc.sum_obv);
      lc.omv_path = "clip";
      if (path == OmvPath::kBoth) {
        lc.paths_agree = need_nef().omv(boxes) == lc.omv;
        lc.omv_path = "both";
      }
    }
    lc.seconds = seconds_since(tl);
    weighted.push_back(Rational(tree.depth - level + 1) * lc.omv);
    char buf[200];
    std::snprintf(buf, sizeof buf, "layer %d/%d: %zu boxes (%zu overlapping), OMV %s, sum OBV %s%s, %.2f s",
                  level, tree.depth, lc.boxes, lc.overlapping_boxes, format_nearest(lc.omv).c_str(),
                  format_nearest(lc.sum_obv).c_str(), lc.paths_agree ? "" : ", PATHS DISAGREE", lc.seconds);
    say(buf);
    cert.layers.push_back(std::move(lc));
  }
  cert.weighted_error = sum_pairwise(weighted);
  cert.seconds = seconds_since(t0);
  return cert;
}

}  // namespace vobb::exact
