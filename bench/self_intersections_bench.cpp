// Times the self-intersection search (common/self_intersections.h) against the search it
// replaced, which tests every pair of faces whose bounding boxes overlap, on the same mesh in
// one run. Both must find the same number of intersecting pairs, or the program fails. Median
// of `--repeat` runs; the box-pair search is skipped (its column says so) once one of its runs
// takes longer than `--reference-limit` seconds. With `--stop-at P` it also times the search
// stopped at P pairs (what check_solidity runs, with P = kSelfIntersectionsCounted).
// `--reference-limit 0` skips the box-pair search (its columns say "skipped"), for meshes
// where it is quadratic. "filter steps" is the search's deterministic work besides its exact
// tests (SelfIntersectionSearch::filter_steps).
// Usage: vobb-bench-self-intersections [--repeat N] [--reference-limit S] [--stop-at P] MESH...
#include <algorithm>
#include <chrono>
#include <cstdio>
#include <cstring>
#include <functional>
#include <string>
#include <vector>

#include "common/bvh.h"
#include "common/exact_predicates.h"
#include "common/io/mesh_io.h"
#include "common/self_intersections.h"

namespace {

double seconds(const std::function<void()>& fn) {
  const auto t0 = std::chrono::steady_clock::now();
  fn();
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
}

double median(std::vector<double> t) {
  std::sort(t.begin(), t.end());
  return t[t.size() / 2];
}

// The former search: every pair of faces whose boxes overlap, decided exactly.
size_t box_pairs(const vobb::Mesh& m, const std::vector<char>& skip) {
  const vobb::AabbTree tree = vobb::AabbTree::over_faces(m);
  size_t pairs = 0;
  for (size_t f = 0; f < m.faces.size(); ++f) {
    if (skip[f]) continue;
    tree.for_each_overlap(tree.primitive_bounds(static_cast<int32_t>(f)), [&](int32_t g) {
      if (static_cast<size_t>(g) > f && !skip[g] && vobb::faces_intersect(m, f, g)) ++pairs;
    });
  }
  return pairs;
}

}  // namespace

int main(int argc, char** argv) {
  int repeat = 5;
  double limit = 60.0;
  size_t stop_at = 0;
  std::vector<std::string> meshes;
  for (int i = 1; i < argc; ++i) {
    if (!std::strcmp(argv[i], "--repeat") && i + 1 < argc)
      repeat = std::max(1, std::atoi(argv[++i]));
    else if (!std::strcmp(argv[i], "--reference-limit") && i + 1 < argc)
      limit = std::atof(argv[++i]);
    else if (!std::strcmp(argv[i], "--stop-at") && i + 1 < argc)
      stop_at = std::strtoull(argv[++i], nullptr, 10);
    else
      meshes.push_back(argv[i]);
  }
  std::printf(
      "| mesh | faces | most faces at a vertex | pairs | search s | exact tests | filter steps | "
      "box-pair search s | box-pair / search |%s\n",
      stop_at ? " search stopped at P s | its pairs | search / stopped |" : "");
  std::printf("|---|---|---|---|---|---|---|---|---|%s\n", stop_at ? "---|---|---|" : "");
  for (const std::string& path : meshes) {
    vobb::LoadedMesh lm;
    const vobb::Status s = vobb::load_mesh(path, &lm);
    if (!s) {
      std::fprintf(stderr, "%s\n", s.message().c_str());
      return 2;
    }
    const vobb::Mesh& m = lm.mesh;
    std::vector<char> skip(m.faces.size(), 0);
    std::vector<int> valence(m.vertices.size(), 0);
    for (size_t f = 0; f < m.faces.size(); ++f) {
      const vobb::Face& F = m.faces[f];
      skip[f] = F[0] == F[1] || F[1] == F[2] || F[2] == F[0] ||
                vobb::collinear(m.corner(f, 0), m.corner(f, 1), m.corner(f, 2));
      for (int32_t v : F) ++valence[v];
    }
    vobb::SelfIntersectionSearch found;
    std::vector<double> t_new, t_old;
    for (int r = 0; r < repeat; ++r)
      t_new.push_back(seconds([&] { found = vobb::find_self_intersections(m, skip); }));
    size_t old_pairs = 0;
    for (int r = 0; r < repeat && limit > 0; ++r) {
      t_old.push_back(seconds([&] { old_pairs = box_pairs(m, skip); }));
      if (t_old.back() > limit) break;
    }
    const bool old_done = t_old.size() == static_cast<size_t>(repeat);
    if (old_pairs != found.pairs && old_done) {
      std::fprintf(stderr, "%s: the searches disagree: %zu against %zu pairs\n", path.c_str(),
                   found.pairs, old_pairs);
      return 1;
    }
    const double tn = median(t_new);
    std::printf("| %s | %zu | %d | %zu | %.3f | %zu | %zu |", path.c_str(), m.faces.size(),
                *std::max_element(valence.begin(), valence.end()), found.pairs, tn,
                found.exact_tests, found.filter_steps);
    if (t_old.empty()) {
      std::printf(" skipped | skipped |");
    } else {
      const double to = old_done ? median(t_old) : t_old.back();
      std::printf(" %s%.3f | %s%.1f |", old_done ? "" : "> ", to, old_done ? "" : "> ", to / tn);
    }
    if (stop_at) {
      vobb::SelfIntersectionSearch cut;
      std::vector<double> t_cut;
      for (int r = 0; r < repeat; ++r)
        t_cut.push_back(seconds([&] { cut = vobb::find_self_intersections(m, skip, stop_at); }));
      // Stopped or not, the pairs it found are the full search's first ones: never more.
      if (cut.pairs > found.pairs || (!cut.stopped && cut.pairs != found.pairs)) {
        std::fprintf(stderr, "%s: the stopped search found %zu pairs, the full one %zu\n",
                     path.c_str(), cut.pairs, found.pairs);
        return 1;
      }
      const double tc = median(t_cut);
      std::printf(" %.3f | %s%zu | %.1f |", tc, cut.stopped ? ">= " : "", cut.pairs, tn / tc);
    }
    std::printf("\n");
    std::fflush(stdout);
  }
  return 0;
}
