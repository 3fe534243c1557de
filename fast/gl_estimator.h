// The GL cubemap OBV estimator (DESIGN §4, paper §4.1): the CPU twin's texel rays, evaluated in
// float by OpenGL through a headless EGL context (gl_context.h), many boxes per round trip.
//
// Per box the CPU makes the shared plan (texel_plan.h: box frame in double, exact centre class,
// culled faces in box-normalized coordinates, texel spans); the boxes of a call are planned in
// parallel (TBB, as many threads as the caller's arena allows). Each span becomes one instanced
// quad in an R32F atlas, one 3m x 2m tile per box; the fragment shader runs the ray test of
// texel_hit() in float and blends the hit's value additively; a compute pass sums each tile in
// slices (cubemap_bound.h), and the host adds a box's slices in double. Boxes whose plan draws
// nothing take no GPU work.
// Calls may come from several threads at once (the variational builder searches nodes in
// parallel). Each plans its boxes on its own thread and gathers their span records into
// requests of up to an atlas of boxes (or 64 MiB of records); the estimator's own drawing
// thread draws the requests waiting at that moment together, holding the context only while
// it draws (the only one of the estimator's threads that binds it after create()). A box's value
// does not depend on which tile it gets or what else shares its batch (its spans are blended in
// their order within its own tile, and its tile is summed alone), so the values are a function of
// the box alone, as ObvEstimate requires, whatever the number of threads. Shaders:
// shaders/texel_spans.{vert,frag}, shaders/reduce_tiles.comp, embedded at build time.
//
// Agreement with the CPU twin: gl_deviation_bound() bounds |GL - CPU| for one box from the
// float arithmetic of the shaders (derivation in gl_estimator.cpp); the test suite checks it.
//
// Boxes that float cannot evaluate. A face whose plane passes the box centre by less than float
// keeps (a scaled plane below 3 FLT_MIN: a box so large against the mesh, or so thin, that a
// face's distance from its centre underflows in box units) would give zeta = 0 in the shader
// and lose hits worth up to the whole box, where double keeps them. Such a box is evaluated by
// the CPU twin's code in double instead (gl_evaluates_in_float, cpu_fallbacks()): its value is
// the CPU twin's, bit for bit, and its deviation bound is 0.
#pragma once

#include <atomic>
#include <memory>
#include <string>
#include <vector>

#include "common/mesh.h"
#include "common/obb.h"
#include "common/status.h"
#include "fast/cubemap_bound.h"
#include "fast/gl_context.h"
#include "fast/texel_plan.h"

namespace vobb {

class GlObvEstimator {
 public:
  // Makes the GL context and compiles the shaders; on failure `out` stays empty and the Status
  // says why in one line. Keeps a reference to `mesh`. `device_only`: only on a GPU (see
  // GlContext::create).
  static Status create(const Mesh& mesh, std::unique_ptr<GlObvEstimator>* out,
                       bool device_only = false);
  ~GlObvEstimator();

  // OBV estimate of each box at resolution m, 1 <= m <= max_m(), in world volume units. May be
  // called from several threads at once (above). The drawing thread binds the context only
  // while it draws, so that another thread (one drawing a figure, say) can take it between
  // calls, though not during one. Like the CPU twin's, not under a changed
  // floating-point environment (a CGAL rounding scope): the planning workers keep the one
  // captured when their arena started.
  std::vector<double> estimate(const std::vector<Obb>& boxes, int m);
  double estimate(const Obb& box, int m);
  int max_m() const;

  // Ablations for the benchmark: culling off draws every mesh face for every box over its
  // whole projection; batching off makes one GPU round trip per box.
  void set_culling(bool on) { planner_.set_culling(on); }
  void set_batching(bool on) { batching_ = on; }
  const BoxPlanner& planner() const { return planner_; }

  const std::string& renderer() const { return context_->renderer(); }
  // The estimator's GL context, for other drawing in the same process (tree_figure.h), between
  // estimate() calls.
  const GlContext& context() const { return *context_; }
  size_t round_trips() const { return round_trips_; }  // since construction
  size_t cpu_fallbacks() const {
    return cpu_fallbacks_;
  }  // boxes evaluated in double, since construction
  // Rounds of the drawing thread that held the boxes of more than one call (calls from several
  // threads at once).
  size_t shared_round_trips() const { return shared_round_trips_; }
  // For tests: while held, the drawing thread takes no call, so that the calls made meanwhile
  // are drawn together once released; queued_calls() counts the calls' requests waiting.
  void hold_draws(bool hold);
  size_t queued_calls() const;

 private:
  struct Gl;
  struct Request;
  explicit GlObvEstimator(const Mesh& mesh);
  void draw(Request* request);
  void drawing_loop();
  void draw_round(const std::vector<Request*>& round);
  void flush(int m);

  BoxPlanner planner_;
  std::unique_ptr<GlContext> context_;
  std::unique_ptr<Gl> gl_;
  bool batching_ = true;
  std::atomic<size_t> round_trips_{0};
  std::atomic<size_t> cpu_fallbacks_{0};
  std::atomic<size_t> shared_round_trips_{0};
};

}  // namespace vobb
