#include "validate/discretization_study.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <limits>

#include "common/stopwatch.h"
#include "exact/outer_volume.h"
#include "fast/poly_solver.h"

namespace vobb::validate {
double StudyEval::abs_error(const StudySample& s) const {
  // Rounded up: one ulp above the nearest double lies above the true difference.
  const double d = std::max(std::abs(estimate - s.lo), std::abs(estimate - s.hi));
  return d == 0 ? 0.0 : std::nextafter(d, INFINITY);
}

double StatedBound::per_volume(int m) const { return c * std::pow(double(m), -p); }

double quantile(std::vector<double> v, double q) {
  VOBB_ASSERT(!v.empty(), "quantile of an empty set");
  std::sort(v.begin(), v.end());
  const double pos = q * (v.size() - 1);
  const size_t lo = static_cast<size_t>(std::floor(pos));
  const size_t hi = std::min(v.size() - 1, lo + 1);
  return v[lo] + (pos - lo) * (v[hi] - v[lo]);
}

double median(std::vector<double> v) { return quantile(std::move(v), 0.5); }

double lsq_slope(const std::vector<double>& x, const std::vector<double>& y) {
  const size_t n = x.size();
  if (n < 2) return std::numeric_limits<double>::quiet_NaN();
  double mx = 0, my = 0;
  for (size_t i = 0; i < n; ++i) mx += x[i], my += y[i];
  mx /= n, my /= n;
  double sxy = 0, sxx = 0;
  for (size_t i = 0; i < n; ++i) sxy += (x[i] - mx) * (y[i] - my), sxx += (x[i] - mx) * (x[i] - mx);
  return sxy / sxx;
}

ErrorStats error_stats(const DiscretizationResult& r,
                       const std::function<bool(const StudyEval&)>& keep) {
  ErrorStats st;
  std::vector<double> rel, ab, norm, rig;
  double secs = 0;
  for (const StudyEval& e : r.evals) {
    if (!keep(e)) continue;
    const StudySample& s = r.samples[e.sample];
    ++st.n;
    secs += e.seconds;
    if (!std::isfinite(e.estimate)) {
      ++st.non_finite;
      st.rigorous_violations += e.has_rigorous();
      continue;
    }
    const double a = e.abs_error(s);
    ab.push_back(a);
    norm.push_back(a / s.box_volume);
    if (s.exact > 0) rel.push_back(a / s.exact);
    if (e.has_rigorous()) {
      rig.push_back(e.rigorous / s.box_volume);
      if (!(a <= e.rigorous)) ++st.rigorous_violations;
    }
  }
  if (st.n) st.seconds_mean = secs / st.n;
  st.n_rel = rel.size();
  if (!rel.empty()) {
    st.rel_median = median(rel);
    st.rel_p95 = quantile(rel, 0.95);
    st.rel_max = *std::max_element(rel.begin(), rel.end());
  }
  if (!ab.empty()) {
    st.abs_median = median(ab);
    st.abs_p95 = quantile(ab, 0.95);
    st.abs_max = *std::max_element(ab.begin(), ab.end());
    st.norm_median = median(norm);
    st.norm_p95 = quantile(norm, 0.95);
    st.norm_max = *std::max_element(norm.begin(), norm.end());
    if (!rig.empty()) st.rigorous_norm_median = median(rig);
  }
  return st;
}

// B(m) = c m^-p vol(O). For each m, q_m is the (1 - alpha/2) quantile of the fit corpus's
// normalised errors (both backends pooled: they share texels and differ by float round-off).
// p is the least-squares slope of log q_m against log m (negated), and c the smallest constant
// with c m^-p >= q_m at every m: the fitted curve lifted to envelope the quantiles. The margin
// between the fitted quantile (1 - alpha/2) and the stated level (alpha) is for the sampling
// error of a quantile from a few dozen boxes per m; it is fixed before the held-out check runs.
StatedBound fit_stated_bound(const DiscretizationResult& r, double alpha) {
  StatedBound b;
  b.alpha = alpha;
  b.quantile = 1 - alpha / 2;
  std::vector<int> ms;
  for (const StudyEval& e : r.evals)
    if (std::find(ms.begin(), ms.end(), e.m) == ms.end()) ms.push_back(e.m);
  std::sort(ms.begin(), ms.end());
  std::vector<double> lx, ly;
  for (int m : ms) {
    std::vector<double> u;
    for (const StudyEval& e : r.evals) {
      const StudySample& s = r.samples[e.sample];
      if (e.m != m || s.held_out || !counts_toward_bound(e)) continue;
      u.push_back(std::isfinite(e.estimate) ? e.abs_error(s) / s.box_volume
                                            : std::numeric_limits<double>::infinity());
    }
    if (u.empty()) continue;
    const double q = quantile(u, b.quantile);
    b.fitted_quantiles.push_back({m, q});
    if (q > 0 && std::isfinite(q)) {
      lx.push_back(std::log(double(m)));
      ly.push_back(std::log(q));
    }
  }
  b.p = lx.size() >= 2 ? -lsq_slope(lx, ly) : 0.0;
  b.c = 0;
  for (const auto& [m, q] : b.fitted_quantiles) b.c = std::max(b.c, q * std::pow(double(m), b.p));
  std::vector<std::pair<size_t, size_t>> per_m(ms.size());  // (n, violations)
  for (const StudyEval& e : r.evals) {
    if (!counts_toward_bound(e)) continue;
    const StudySample& s = r.samples[e.sample];
    const bool violates = !(e.abs_error(s) <= b.per_volume(e.m) * s.box_volume);  // NaN violates
    if (s.held_out) {
      ++b.held_out_n;
      b.held_out_violations += violates;
      const size_t k = std::find(ms.begin(), ms.end(), e.m) - ms.begin();
      ++per_m[k].first;
      per_m[k].second += violates;
    } else {
      ++b.fit_n;
      b.fit_violations += violates;
    }
  }
  for (size_t k = 0; k < ms.size(); ++k)
    if (per_m[k].first)
      b.held_out_rate_per_m.push_back({ms[k], double(per_m[k].second) / per_m[k].first});
  return b;
}

namespace {

// The box sizes of each mesh's corpus, in the order the study draws them.
constexpr BoxSize kSizes[] = {BoxSize::kLeaf, BoxSize::kMid, BoxSize::kRoot};

// Passes one progress line to the configuration's callback, when it has one.
void say(const DiscretizationConfig& config, const std::string& line) {
  if (config.progress) config.progress(line);
}

// Running totals over the meshes: the exact solvers' times, the certified intervals' relative
// widths, and whether GL was tried and whether it ever ran.
struct StudyTotals {
  double clip_seconds = 0, nef_seconds = 0, clip_on_nef_boxes = 0, poly_seconds = 0;
  size_t clip_n = 0, poly_n = 0;
  std::vector<double> poly_rel;
  bool gl_ever = false, gl_tried = false;
};

// One mesh under study and its solvers, which live while the mesh is studied.
struct MeshUnderStudy {
  const NamedMesh& nm;
  bool held_out;
  size_t index;  // among the fit meshes, then the held-out ones: seeds the corpus
  EstimatorSet& est;
  const exact::ClipSolver& clip;
  const PolyObvSolver& poly;
  const exact::NefSolver* nef;  // null except on the mesh on which Nef is timed
};

// Computes the exact rational of sample `i`'s box by clipping, checks that it lies inside the
// sample's certified interval and makes its nearest double the sample's reference; on the Nef
// subsample, also compares it with Nef's rational.
void add_exact_rational(const DiscretizationConfig& config, const MeshUnderStudy& mu,
                        const Obb& box, int i, StudySample* s, StudyTotals* totals,
                        DiscretizationResult* r) {
  const auto te = std::chrono::steady_clock::now();
  const Rational v = mu.clip.obv(box);
  const double t = seconds_since(te);
  totals->clip_seconds += t;
  ++totals->clip_n;
  ++r->rational_checked;
  const bool inside = Rational(s->lo) <= v && v <= Rational(s->hi);
  r->rational_outside += !inside;
  s->rational = inside ? 1 : -1;
  s->exact = to_double_nearest(v);
  if (mu.nef && i < config.nef_boxes_per_size) {
    const auto tn = std::chrono::steady_clock::now();
    const Rational w = mu.nef->obv(box);
    totals->nef_seconds += seconds_since(tn);
    totals->clip_on_nef_boxes += t;
    ++r->nef_compared;
    if (!(w == v)) r->nef_agrees = false;  // exact: equal rationals or a finding
  }
}

// Draws the mesh's corpus, every size in turn, and appends one sample per box to r->samples
// with its certified interval (and the exact rational on the rational subsample); returns the
// boxes in the order of their samples.
std::vector<Obb> add_reference_samples(const DiscretizationConfig& config, const MeshUnderStudy& mu,
                                       StudyTotals* totals, DiscretizationResult* r) {
  const Mesh& mesh = *mu.nm.mesh;
  std::vector<Obb> boxes;
  for (int si = 0; si < 3; ++si) {
    const uint64_t seed =
        (mu.held_out ? config.held_out_seed : config.fit_seed) + 10 * mu.index + si;
    const std::vector<Obb> part = box_corpus(mesh, kSizes[si], config.boxes_per_size, seed);
    // The reference: every box's certified interval, the batch on every core.
    const auto tp = std::chrono::steady_clock::now();
    const std::vector<PolyObv> ref = mu.poly.evaluate(part);
    const double per_box = part.empty() ? 0.0 : seconds_since(tp) / part.size();
    totals->poly_seconds += per_box * part.size();
    totals->poly_n += part.size();
    for (size_t i = 0; i < part.size(); ++i) {
      StudySample s;
      s.mesh = mu.nm.name;
      s.held_out = mu.held_out;
      s.size = kSizes[si];
      s.index = static_cast<int>(i);
      s.box = part[i];
      s.box_volume = volume(part[i]);
      s.centre = mu.est.centre_location(part[i]);
      s.lo = ref[i].lo;
      s.hi = ref[i].hi;
      s.exact = ref[i].estimate;
      s.poly_seconds = per_box;
      if (s.lo > 0) totals->poly_rel.push_back((s.hi - s.lo) / s.lo);
      if (static_cast<int>(i) < config.rational_boxes_per_size)
        add_exact_rational(config, mu, part[i], static_cast<int>(i), &s, totals, r);
      r->samples.push_back(s);
      boxes.push_back(part[i]);
    }
  }
  return boxes;
}

// Appends the estimates of the mesh's boxes (samples first, first + 1, ...) at every m: the CPU
// twin on every box; GL, R(m) and GL's allowed deviation on the detail subsample only.
void add_estimates(const DiscretizationConfig& config, const MeshUnderStudy& mu, size_t first,
                   const std::vector<Obb>& boxes, DiscretizationResult* r) {
  EstimatorSet& est = mu.est;
  // The detail subsample: the first detail_boxes_per_size boxes of each size get R(m) (a texel
  // plan per box and m, the costly part) and GL; the rest, the CPU twin alone.
  std::vector<size_t> detail;
  for (size_t i = 0; i < boxes.size(); ++i)
    if (r->samples[first + i].index < config.detail_boxes_per_size) detail.push_back(i);
  for (Backend backend : {Backend::kCpu, Backend::kGl}) {
    if (backend == Backend::kGl && !est.has_gl()) continue;
    std::vector<size_t> which = detail;
    if (backend == Backend::kCpu) {
      which.resize(boxes.size());
      for (size_t i = 0; i < boxes.size(); ++i) which[i] = i;
    }
    std::vector<Obb> batch;
    for (size_t i : which) batch.push_back(boxes[i]);
    if (batch.empty()) continue;
    if (backend == Backend::kGl) {  // warm-up: shader JIT and the atlas's first pages are not timed
      std::vector<double> ignored;
      est.estimate(backend, {batch[0]}, 8, &ignored);
    }
    for (int m : config.ms) {
      if (backend == Backend::kGl && m > est.gl_max_m()) continue;
      std::vector<double> secs;
      const std::vector<double> v = est.estimate(backend, batch, m, &secs);
      for (size_t k = 0; k < batch.size(); ++k) {
        const size_t i = which[k];
        StudyEval e;
        e.sample = first + i;
        e.backend = backend;
        e.m = m;
        e.estimate = v[k];
        e.seconds = secs[k];
        if (r->samples[first + i].index < config.detail_boxes_per_size) {
          const EstimatorSet::Bounds bd = est.bounds(boxes[i], m);
          e.rigorous = backend == Backend::kCpu ? bd.cpu_rigorous() : bd.rigorous();
          e.deviation = bd.deviation + bd.roundoff;
        }
        r->evals.push_back(e);
      }
    }
    say(config, mu.nm.name + ": " + to_string(backend) + " estimates at every m done");
  }
}

// Studies mesh number `mi`: builds its estimators and exact solvers (timing Nef's build on the
// first mesh), appends its samples with their references, then their estimates.
void study_mesh(const DiscretizationConfig& config, size_t mi, const NamedMesh& nm, bool held_out,
                StudyTotals* totals, DiscretizationResult* r) {
  const Mesh& mesh = *nm.mesh;
  EstimatorSet est(mesh, config.want_gl, config.perturb);
  if (!config.want_gl) {
    r->gl_note = "GL not requested";
  } else if (!totals->gl_tried) {
    totals->gl_tried = true;
    r->gl_note = est.has_gl() ? "GL renderer: " + est.renderer()
                              : "GL estimator unavailable: " + est.gl_status();
  }
  totals->gl_ever |= est.has_gl();
  const exact::ClipSolver clip(mesh);
  const PolyObvSolver poly(mesh);
  const bool time_nef = mi == 0 && config.nef_boxes_per_size > 0;
  std::unique_ptr<exact::NefSolver> nef;
  if (time_nef) {
    const auto tn = std::chrono::steady_clock::now();
    nef = std::make_unique<exact::NefSolver>(mesh);
    r->exact_timings.push_back({"nef (build Nef(X) once)", 1, seconds_since(tn), nm.name});
  }
  const MeshUnderStudy mu{nm, held_out, mi, est, clip, poly, nef.get()};
  const size_t first = r->samples.size();
  const std::vector<Obb> boxes = add_reference_samples(config, mu, totals, r);
  say(config, nm.name + (held_out ? " (held out)" : " (fit)") + ": " +
                  std::to_string(boxes.size()) + " boxes, certified intervals done (" +
                  std::to_string(config.rational_boxes_per_size) +
                  " per size checked against the exact rational)");
  add_estimates(config, mu, first, boxes, r);
}

// Appends the exact solvers' mean times per evaluation, and sets the certified intervals'
// median relative width.
void add_exact_timings(const StudyTotals& totals, DiscretizationResult* r) {
  if (totals.poly_n)
    r->exact_timings.push_back({"poly", totals.poly_n, totals.poly_seconds / totals.poly_n,
                                "every box of the corpus (interval)"});
  if (!totals.poly_rel.empty()) r->poly_certified_rel_median = median(totals.poly_rel);
  if (totals.clip_n)
    r->exact_timings.push_back(
        {"clip", totals.clip_n, totals.clip_seconds / totals.clip_n, "the rational subsample"});
  if (r->nef_compared) {
    r->exact_timings.push_back({"nef", r->nef_compared, totals.nef_seconds / r->nef_compared,
                                "first fit mesh, first boxes of each size"});
    r->exact_timings.push_back({"clip (same boxes as nef)", r->nef_compared,
                                totals.clip_on_nef_boxes / r->nef_compared, ""});
  }
}

// Computes the error statistics per (backend, m), per (backend, box size, centre class) at
// m = 32, and the fitted convergence rates per backend.
void add_error_statistics(const DiscretizationConfig& config, DiscretizationResult* r) {
  for (Backend b : r->backends)
    for (int m : config.ms) {
      PerMStats pm{b, m,
                   error_stats(*r, [&](const StudyEval& e) { return e.backend == b && e.m == m; })};
      if (pm.all.n) r->per_m.push_back(pm);
    }
  if (std::find(config.ms.begin(), config.ms.end(), 32) != config.ms.end())
    for (Backend b : r->backends)
      for (BoxSize sz : kSizes)
        for (Location loc : {Location::kInside, Location::kOutside, Location::kOnSurface}) {
          const ErrorStats st = error_stats(*r, [&](const StudyEval& e) {
            const StudySample& s = r->samples[e.sample];
            return e.backend == b && e.m == 32 && s.size == sz && s.centre == loc;
          });
          if (st.n) r->per_class_m32.push_back({b, sz, loc, st});
        }
  for (Backend b : r->backends) {
    std::vector<double> lx, lmed, lp95, lmax;
    for (const PerMStats& pm : r->per_m)
      if (pm.backend == b && pm.all.rel_median > 0 && pm.all.rel_p95 > 0 && pm.all.rel_max > 0) {
        lx.push_back(std::log(double(pm.m)));
        lmed.push_back(std::log(pm.all.rel_median));
        lp95.push_back(std::log(pm.all.rel_p95));
        lmax.push_back(std::log(pm.all.rel_max));
      }
    r->rates.push_back({b, lsq_slope(lx, lmed), lsq_slope(lx, lp95), lsq_slope(lx, lmax)});
  }
}

// Richardson: per (sample, backend) the estimates at m and 2m, judged at 2m; appends one row
// per (backend, m) that has both.
void add_richardson_rows(const DiscretizationConfig& config, DiscretizationResult* r) {
  for (Backend b : r->backends)
    for (int m : config.ms) {
      if (std::find(config.ms.begin(), config.ms.end(), 2 * m) == config.ms.end()) continue;
      std::vector<const StudyEval*> at_m(r->samples.size(), nullptr),
          at_2m(r->samples.size(), nullptr);
      for (const StudyEval& e : r->evals) {
        if (e.backend != b) continue;
        if (e.m == m) at_m[e.sample] = &e;
        if (e.m == 2 * m) at_2m[e.sample] = &e;
      }
      RichardsonRow row{b, m};
      size_t c3 = 0, c1 = 0, c2 = 0;
      for (size_t i = 0; i < r->samples.size(); ++i) {
        if (!at_m[i] || !at_2m[i]) continue;
        const double d = std::abs(at_m[i]->estimate - at_2m[i]->estimate);
        const double err = at_2m[i]->abs_error(r->samples[i]);
        ++row.n;
        c3 += err <= d / 3;
        c1 += err <= d;
        c2 += err <= 2 * d;
      }
      if (!row.n) continue;
      row.cover_third = double(c3) / row.n;
      row.cover_one = double(c1) / row.n;
      row.cover_two = double(c2) / row.n;
      r->richardson.push_back(row);
    }
}

}  // namespace

DiscretizationResult run_discretization_study(const DiscretizationConfig& config) {
  const auto t0 = std::chrono::steady_clock::now();
  DiscretizationResult r;
  std::vector<std::pair<NamedMesh, bool>> meshes;
  for (const NamedMesh& nm : config.fit_meshes) meshes.push_back({nm, false});
  for (const NamedMesh& nm : config.held_out_meshes) meshes.push_back({nm, true});

  StudyTotals totals;
  for (size_t mi = 0; mi < meshes.size(); ++mi) {
    const auto& [nm, held_out] = meshes[mi];
    study_mesh(config, mi, nm, held_out, &totals, &r);
  }
  r.backends.push_back(Backend::kCpu);
  if (totals.gl_ever) r.backends.push_back(Backend::kGl);
  add_exact_timings(totals, &r);
  add_error_statistics(config, &r);
  r.bound = fit_stated_bound(r, config.alpha);
  add_richardson_rows(config, &r);
  r.seconds = seconds_since(t0);
  return r;
}

}  // namespace vobb::validate
