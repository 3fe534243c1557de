#include "fast/gl_estimator.h"

#define GL_GLEXT_PROTOTYPES 1
#include <GL/glcorearb.h>
#include <tbb/parallel_for.h>
#include <tbb/task_arena.h>

#include <algorithm>
#include <array>
#include <cfenv>
#include <cmath>
#include <condition_variable>
#include <cstring>
#include <exception>
#include <mutex>
#include <thread>

#include "fast/cpu_estimator.h"
#include "fast/cubemap.h"
#include "shaders/shaders.h"

namespace vobb {

namespace {

// One texel span as the vertex shader reads it (per-instance attributes, 84 bytes).
struct SpanRecord {
  int32_t span[4];  // i0, j0, i1, j1
  int32_t meta[4];  // atlas pixel of texel (0, 0) of the cubemap face; flags; 0
  float edge[3][3];
  float plane[4];
};
static_assert(sizeof(SpanRecord) == 84, "SpanRecord is read with a fixed stride");

// One box of a window, planned on a worker thread: what the packing on the GL thread needs.
struct PlannedBox {
  BoxPlan plan;                     // vectors keep their capacity from window to window
  std::vector<SpanRecord> records;  // meta[0..1] relative to the box's tile (0, 0)
  std::vector<std::array<float, 13>> tri_data;
  bool fallback = false;  // evaluated in double by the CPU twin's code
  double value = 0;       // the box's whole OBV when nothing goes to the GPU
};

// The heap memory a slot keeps for its next box.
size_t held_bytes(const PlannedBox& p) {
  return p.plan.tris.capacity() * sizeof(LocalTriangle) +
         p.plan.spans.capacity() * sizeof(TexelSpan) +
         p.tri_data.capacity() * sizeof(p.tri_data[0]) + p.records.capacity() * sizeof(SpanRecord);
}

// Plans `box` into *p and turns its spans into records; all of it depends on the box alone.
void plan_box(const BoxPlanner& planner, const Obb& box, int m, PlannedBox* p) {
  planner.plan(box, m, &p->plan);
  const BoxPlan& plan = p->plan;
  p->records.clear();
  p->fallback = false;
  p->value = 0;
  if (plan.flat) return;               // OBV 0
  if (!gl_evaluates_in_float(plan)) {  // the CPU twin's expression, in double (header)
    p->fallback = true;
    p->value = evaluate_plan(plan, m);
    return;
  }
  p->value = plan.frame.volume_scale * plan.constant;  // the whole answer when nothing is drawn
  p->tri_data.resize(plan.tris.size());
  for (size_t t = 0; t < plan.tris.size(); ++t) {
    const LocalTriangle& tri = plan.tris[t];
    for (int k = 0; k < 3; ++k) {
      const Vec3& e = tri.edge_cross[k];
      const double f = pow2_normalizer(e[0], e[1], e[2]);
      for (int c = 0; c < 3; ++c) p->tri_data[t][3 * k + c] = static_cast<float>(e[c] * f);
    }
    const double f = pow2_normalizer(tri.normal[0], tri.normal[1], tri.normal[2]);
    for (int c = 0; c < 3; ++c) p->tri_data[t][9 + c] = static_cast<float>(tri.normal[c] * f);
    p->tri_data[t][12] = static_cast<float>(tri.plane * f);
  }
  for (const TexelSpan& span : plan.spans) {
    if (span.i0 > span.i1 || span.j0 > span.j1) continue;  // covers no texel centre
    SpanRecord r;
    r.span[0] = span.i0;
    r.span[1] = span.j0;
    r.span[2] = span.i1;
    r.span[3] = span.j1;
    r.meta[0] = span.face % 3 * m;
    r.meta[1] = span.face / 3 * m;
    r.meta[2] = span.face | (plan.far_count << 6);
    r.meta[3] = 0;
    std::memcpy(r.edge, p->tri_data[span.tri].data(), 9 * sizeof(float));
    std::memcpy(r.plane, p->tri_data[span.tri].data() + 9, 4 * sizeof(float));
    p->records.push_back(r);
  }
}

// The atlas for resolution m: tiles of 3m x 2m texels on a side of 4096 pixels (64 MiB),
// larger only for big m, at most 4096 tiles.
struct AtlasLayout {
  int tiles_per_row, capacity, width, height;
};
AtlasLayout atlas_layout(int max_texture, int m) {
  const int side = std::min(max_texture, std::max(4096, 3 * m));
  AtlasLayout a;
  a.tiles_per_row = side / (3 * m);
  const int rows = side / (2 * m);
  a.capacity = std::min(a.tiles_per_row * rows, 4096);
  a.width = a.tiles_per_row * 3 * m;
  a.height = (a.capacity + a.tiles_per_row - 1) / a.tiles_per_row * 2 * m;
  return a;
}

// A batch is drawn once the atlas is full or its span records pass 64 MiB (boxes in far-count
// mode or without culling draw every face of the mesh).
constexpr size_t kMaxRecords = (size_t{64} << 20) / sizeof(SpanRecord);

}  // namespace

// The drawn boxes of one estimate() call, gathered for the drawing thread: each box's span
// records relative to its tile's texel (0, 0), and where its value goes. A call sends one
// request per atlas of boxes (or 64 MiB of records), as one call drew one batch before calls
// could come from several threads.
struct GlObvEstimator::Request {
  int m = 0;
  std::vector<SpanRecord> records;
  std::vector<size_t> ends;  // per box: the end of its records
  std::vector<double> scale, constant;
  std::vector<double*> out;
  bool done = false;         // drawn, values written (under Gl::mutex)
  std::exception_ptr error;  // what the drawing thread threw, rethrown by the caller
  void clear() {
    records.clear();
    ends.clear();
    scale.clear();
    constant.clear();
    out.clear();
    done = false;
    error = nullptr;
  }
};

struct GlObvEstimator::Gl {
  GLuint spans_program = 0, reduce_program = 0;
  GLuint vao = 0, records = 0, atlas = 0, fbo = 0, sums = 0;
  GLint max_texture = 0;
  int atlas_m = 0;
  AtlasLayout atlas_layout{};
  // The batch being gathered by the drawing thread: records, and per tile where its value goes.
  std::vector<SpanRecord> batch_records;
  std::vector<double*> batch_out;
  std::vector<double> batch_scale, batch_constant;
  // Calls waiting for a draw, and the drawing thread's stop flag; guarded by `mutex`.
  std::mutex mutex;
  std::condition_variable changed;  // a request queued or drawn, or stop set
  std::vector<Request*> queue;
  bool stop = false;
  bool held = false;   // hold_draws()
  std::thread drawer;  // the only thread that binds the context after create()
  // A call's planning slots and request, kept with their vectors' capacity for a later call
  // (one set per call under way, so calls from several threads never share one; at most as
  // many kept as the arena has threads).
  struct Scratch {
    std::vector<PlannedBox> slots;
    Request request;
  };
  std::vector<std::unique_ptr<Scratch>> idle;
};

GlObvEstimator::GlObvEstimator(const Mesh& mesh) : planner_(mesh), gl_(new Gl) {}

GlObvEstimator::~GlObvEstimator() {
  if (!gl_ || !gl_->drawer.joinable()) return;  // create() failed before the thread started
  {
    std::lock_guard<std::mutex> lock(gl_->mutex);
    gl_->stop = true;
  }
  gl_->changed.notify_all();
  gl_->drawer.join();  // it deletes the GL objects on its way out
}

Status GlObvEstimator::create(const Mesh& mesh, std::unique_ptr<GlObvEstimator>* out,
                              bool device_only) {
  out->reset();
  std::unique_ptr<GlObvEstimator> e(new GlObvEstimator(mesh));
  Status s = GlContext::create(&e->context_, device_only);
  if (!s) return s;
  Gl& g = *e->gl_;
  std::string log;
  g.spans_program = gl_program({{GL_VERTEX_SHADER, shaders::kShader_texel_spans_vert},
                                {GL_FRAGMENT_SHADER, shaders::kShader_texel_spans_frag}},
                               &log);
  if (!g.spans_program) return Status::error("GL estimator: texel_spans shaders: " + log);
  g.reduce_program = gl_program({{GL_COMPUTE_SHADER, shaders::kShader_reduce_tiles_comp}}, &log);
  if (!g.reduce_program) return Status::error("GL estimator: reduce_tiles shader: " + log);

  glGenVertexArrays(1, &g.vao);
  glBindVertexArray(g.vao);
  glGenBuffers(1, &g.records);
  glBindBuffer(GL_ARRAY_BUFFER, g.records);
  const GLsizei stride = sizeof(SpanRecord);
  glVertexAttribIPointer(0, 4, GL_INT, stride, reinterpret_cast<void*>(offsetof(SpanRecord, span)));
  glVertexAttribIPointer(1, 4, GL_INT, stride, reinterpret_cast<void*>(offsetof(SpanRecord, meta)));
  for (int k = 0; k < 3; ++k)
    glVertexAttribPointer(
        2 + k, 3, GL_FLOAT, GL_FALSE, stride,
        reinterpret_cast<void*>(offsetof(SpanRecord, edge) + k * 3 * sizeof(float)));
  glVertexAttribPointer(5, 4, GL_FLOAT, GL_FALSE, stride,
                        reinterpret_cast<void*>(offsetof(SpanRecord, plane)));
  for (GLuint a = 0; a < 6; ++a) {
    glEnableVertexAttribArray(a);
    glVertexAttribDivisor(a, 1);
  }
  glGenBuffers(1, &g.sums);
  glGenFramebuffers(1, &g.fbo);
  glGetIntegerv(GL_MAX_TEXTURE_SIZE, &g.max_texture);
  if (glGetError() != GL_NO_ERROR)
    return Status::error("GL estimator: OpenGL error while setting up");
  e->context_->release();  // bound by the drawing thread from now on
  GlObvEstimator* self = e.get();
  g.drawer = std::thread([self] { self->drawing_loop(); });
  *out = std::move(e);
  return Status::ok();
}

int GlObvEstimator::max_m() const { return gl_->max_texture / 3; }

double GlObvEstimator::estimate(const Obb& box, int m) {
  return estimate(std::vector<Obb>{box}, m)[0];
}

std::vector<double> GlObvEstimator::estimate(const std::vector<Obb>& boxes, int m) {
  VOBB_ASSERT(m >= 1 && m <= max_m(), "GL cubemap resolution within 1..max_m()");
  Gl& g = *gl_;
  std::vector<double> out(boxes.size(), 0.0);
  std::unique_ptr<Gl::Scratch> scratch;
  {
    std::lock_guard<std::mutex> lock(g.mutex);
    if (!g.idle.empty()) {
      scratch = std::move(g.idle.back());
      g.idle.pop_back();
    }
  }
  if (!scratch) scratch = std::make_unique<Gl::Scratch>();
  std::vector<PlannedBox>& slots = scratch->slots;
  Request& r = scratch->request;
  r.clear();
  r.m = m;
  const int capacity = atlas_layout(g.max_texture, m).capacity;
  // The boxes are planned in parallel (TBB, as many threads as the caller's arena allows), a
  // window of twice that many at a time, and the drawn boxes' records are gathered in box
  // order into the request, which is drawn (draw()) when it holds an atlas of boxes or 64 MiB
  // of records, and at the end. Each box's records depend on that box alone, so the records
  // drawn for a box, their order, and the floats blended are the same for any number of
  // threads.
  // Memory: a slot keeps its vectors' capacity from call to call unless they pass
  // kPlanKeepBytes (cpu_estimator.h); after a window with such a plan, the next window holds
  // one box per thread, so that large plans are held at most one per thread at once by a call,
  // as the CPU twin holds them; the request holds records alone, up to 64 MiB and one box.
  const size_t threads = static_cast<size_t>(std::max(1, tbb::this_task_arena::max_concurrency()));
  size_t window = 2 * threads;
  if (slots.size() < std::min(window, boxes.size())) slots.resize(std::min(window, boxes.size()));
  for (size_t w0 = 0, w1 = 0; w0 < boxes.size(); w0 = w1) {
    w1 = std::min(boxes.size(), w0 + window);
    tbb::parallel_for(w0, w1, [&](size_t b) { plan_box(planner_, boxes[b], m, &slots[b - w0]); });
    for (size_t b = w0; b < w1; ++b) {
      const PlannedBox& p = slots[b - w0];
      out[b] = p.value;  // the whole answer unless the box is drawn
      if (p.fallback) ++cpu_fallbacks_;
      if (p.records.empty())
        continue;  // flat, evaluated in double, or no span covers a texel centre
      r.records.insert(r.records.end(), p.records.begin(), p.records.end());
      r.ends.push_back(r.records.size());
      r.scale.push_back(p.plan.frame.volume_scale);
      r.constant.push_back(p.plan.constant);
      r.out.push_back(&out[b]);
      if (!batching_ || static_cast<int>(r.out.size()) == capacity ||
          r.records.size() >= kMaxRecords) {
        draw(&r);
        r.clear();
        r.m = m;
      }
    }
    window = 2 * threads;
    for (size_t b = w0; b < w1; ++b) {  // the slots of large plans are not kept
      if (held_bytes(slots[b - w0]) <= kPlanKeepBytes) continue;
      slots[b - w0] = PlannedBox{};
      window = threads;
    }
  }
  if (!r.out.empty()) draw(&r);
  // A request past 64 MiB is not kept either.
  if (r.records.capacity() * sizeof(SpanRecord) > kPlanKeepBytes) r = Request{};
  std::lock_guard<std::mutex> lock(g.mutex);
  if (g.idle.size() < threads) g.idle.push_back(std::move(scratch));
  return out;
}

void GlObvEstimator::hold_draws(bool hold) {
  {
    std::lock_guard<std::mutex> lock(gl_->mutex);
    gl_->held = hold;
  }
  gl_->changed.notify_all();
}

size_t GlObvEstimator::queued_calls() const {
  std::lock_guard<std::mutex> lock(gl_->mutex);
  return gl_->queue.size();
}

// Queues the request and waits until the drawing thread has drawn it. The wait blocks the
// calling thread without taking other TBB work, and the drawing thread waits for nothing but
// requests, so no call can wait on itself.
void GlObvEstimator::draw(Request* request) {
  Gl& g = *gl_;
  std::unique_lock<std::mutex> lock(g.mutex);
  VOBB_ASSERT(!g.stop, "no estimate() call while the estimator is destroyed");
  g.queue.push_back(request);
  g.changed.notify_all();
  g.changed.wait(lock, [request] { return request->done; });
  if (request->error) std::rethrow_exception(request->error);
}

// The drawing thread: takes every request queued at that moment with the first one's m (calls
// at another m wait for a round of their own) and draws them together, holding the context
// only during the round. Only this thread binds the context once create() has returned: EGL
// state bound on the callers' threads (TBB's workers, alive until the process ends) was seen
// to corrupt the heap at exit on llvmpipe and to abort on NVIDIA's driver.
void GlObvEstimator::drawing_loop() {
  // A thread starts with its creator's floating-point environment; the values are assembled
  // here (flush()) in the default one, as the CPU twin's are.
  std::fesetenv(FE_DFL_ENV);
  Gl& g = *gl_;
  std::unique_lock<std::mutex> lock(g.mutex);
  for (;;) {
    g.changed.wait(lock, [&g] { return g.stop || (!g.queue.empty() && !g.held); });
    if (g.queue.empty()) break;  // stop, and every request drawn
    const int m = g.queue.front()->m;
    auto same_m = std::stable_partition(g.queue.begin(), g.queue.end(),
                                        [m](const Request* q) { return q->m == m; });
    const std::vector<Request*> round(g.queue.begin(), same_m);
    g.queue.erase(g.queue.begin(), same_m);
    lock.unlock();
    std::exception_ptr error;
    try {
      draw_round(round);
    } catch (...) {
      error = std::current_exception();
    }
    if (round.size() > 1) ++shared_round_trips_;
    lock.lock();
    for (Request* q : round) {
      q->done = true;
      q->error = error;
    }
    g.changed.notify_all();
  }
  lock.unlock();
  GlContext::Current bound(*context_);
  glDeleteProgram(g.spans_program);
  glDeleteProgram(g.reduce_program);
  glDeleteVertexArrays(1, &g.vao);
  glDeleteBuffers(1, &g.records);
  glDeleteBuffers(1, &g.sums);
  glDeleteFramebuffers(1, &g.fbo);
  glDeleteTextures(1, &g.atlas);
}

void GlObvEstimator::draw_round(const std::vector<Request*>& round) {
  Gl& g = *gl_;
  const int m = round.front()->m;
  GlContext::Current bound(*context_);
  if (g.atlas_m != m) {
    const AtlasLayout& a = g.atlas_layout = atlas_layout(g.max_texture, m);
    if (g.atlas) glDeleteTextures(1, &g.atlas);
    glGenTextures(1, &g.atlas);
    glBindTexture(GL_TEXTURE_2D, g.atlas);
    glTexStorage2D(GL_TEXTURE_2D, 1, GL_R32F, a.width, a.height);
    glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_MIN_FILTER, GL_NEAREST);
    glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_MAG_FILTER, GL_NEAREST);
    glBindFramebuffer(GL_FRAMEBUFFER, g.fbo);
    glFramebufferTexture2D(GL_FRAMEBUFFER, GL_COLOR_ATTACHMENT0, GL_TEXTURE_2D, g.atlas, 0);
    VOBB_ASSERT(glCheckFramebufferStatus(GL_FRAMEBUFFER) == GL_FRAMEBUFFER_COMPLETE,
                "R32F atlas is renderable");
    g.atlas_m = m;
  }
  const AtlasLayout& a = g.atlas_layout;
  // A round that threw (an allocation, say) may have left a batch half gathered.
  g.batch_records.clear();
  g.batch_out.clear();
  g.batch_scale.clear();
  g.batch_constant.clear();
  // The requests' boxes take the atlas's tiles in order; a request may span two batches.
  for (const Request* q : round)
    for (size_t b = 0; b < q->out.size(); ++b) {
      const int tile = static_cast<int>(g.batch_out.size());
      const int tile_x = tile % a.tiles_per_row * 3 * m, tile_y = tile / a.tiles_per_row * 2 * m;
      const size_t first = g.batch_records.size();
      g.batch_records.insert(g.batch_records.end(),
                             q->records.begin() + (b == 0 ? 0 : q->ends[b - 1]),
                             q->records.begin() + q->ends[b]);
      for (size_t i = first; i < g.batch_records.size(); ++i) {
        g.batch_records[i].meta[0] += tile_x;
        g.batch_records[i].meta[1] += tile_y;
      }
      g.batch_out.push_back(q->out[b]);
      g.batch_scale.push_back(q->scale[b]);
      g.batch_constant.push_back(q->constant[b]);
      if (!batching_ || static_cast<int>(g.batch_out.size()) == a.capacity ||
          g.batch_records.size() >= kMaxRecords)
        flush(m);
    }
  if (!g.batch_out.empty()) flush(m);
}

void GlObvEstimator::flush(int m) {
  Gl& g = *gl_;
  const int n = static_cast<int>(g.batch_out.size());
  const int rows = (n + g.atlas_layout.tiles_per_row - 1) / g.atlas_layout.tiles_per_row;
  glBindFramebuffer(GL_FRAMEBUFFER, g.fbo);
  glViewport(0, 0, g.atlas_layout.width, g.atlas_layout.height);
  glEnable(GL_SCISSOR_TEST);
  glScissor(0, 0, n < g.atlas_layout.tiles_per_row ? n * 3 * m : g.atlas_layout.width,
            rows * 2 * m);
  const GLfloat zero[4] = {0, 0, 0, 0};
  glClearBufferfv(GL_COLOR, 0, zero);
  glDisable(GL_SCISSOR_TEST);
  glEnable(GL_BLEND);
  glBlendEquation(GL_FUNC_ADD);
  glBlendFunc(GL_ONE, GL_ONE);
  glDisable(GL_DEPTH_TEST);
  glDisable(GL_CULL_FACE);

  glUseProgram(g.spans_program);
  glUniform2f(glGetUniformLocation(g.spans_program, "u_atlas_size"),
              static_cast<float>(g.atlas_layout.width), static_cast<float>(g.atlas_layout.height));
  glUniform1i(glGetUniformLocation(g.spans_program, "u_m"), m);
  glBindVertexArray(g.vao);
  glBindBuffer(GL_ARRAY_BUFFER, g.records);
  glBufferData(GL_ARRAY_BUFFER, g.batch_records.size() * sizeof(SpanRecord), g.batch_records.data(),
               GL_STREAM_DRAW);
  glDrawArraysInstanced(GL_TRIANGLE_STRIP, 0, 4, static_cast<GLsizei>(g.batch_records.size()));
  glDisable(GL_BLEND);

  glMemoryBarrier(GL_TEXTURE_FETCH_BARRIER_BIT);
  glUseProgram(g.reduce_program);
  glActiveTexture(GL_TEXTURE0);
  glBindTexture(GL_TEXTURE_2D, g.atlas);
  glUniform1i(glGetUniformLocation(g.reduce_program, "u_atlas"), 0);
  glUniform1i(glGetUniformLocation(g.reduce_program, "u_m"), m);
  glUniform1i(glGetUniformLocation(g.reduce_program, "u_tiles_per_row"),
              g.atlas_layout.tiles_per_row);
  const int slices = reduce_slices(m);
  glUniform1i(glGetUniformLocation(g.reduce_program, "u_slice_texels"), kReduceSliceTexels);
  glUniform1i(glGetUniformLocation(g.reduce_program, "u_slices"), slices);
  const size_t floats = static_cast<size_t>(n) * slices;
  glBindBuffer(GL_SHADER_STORAGE_BUFFER, g.sums);
  glBufferData(GL_SHADER_STORAGE_BUFFER, floats * sizeof(float), nullptr, GL_STREAM_READ);
  glBindBufferBase(GL_SHADER_STORAGE_BUFFER, 0, g.sums);
  glDispatchCompute(n, slices, 1);
  glMemoryBarrier(GL_BUFFER_UPDATE_BARRIER_BIT);
  std::vector<float> sums(floats);
  glGetBufferSubData(GL_SHADER_STORAGE_BUFFER, 0, floats * sizeof(float), sums.data());
  VOBB_ASSERT(glGetError() == GL_NO_ERROR, "GL estimator batch ran without GL errors");
  ++round_trips_;

  const double texel_weight = 4.0 / (3.0 * m * m);
  for (int t = 0; t < n; ++t) {
    double sum = 0;  // the slices in order; one slice: its float, as it was summed
    for (int s = 0; s < slices; ++s)
      sum += static_cast<double>(sums[static_cast<size_t>(t) * slices + s]);
    *g.batch_out[t] = g.batch_scale[t] * (g.batch_constant[t] + texel_weight * sum);
  }
  g.batch_records.clear();
  g.batch_out.clear();
  g.batch_scale.clear();
  g.batch_constant.clear();
}

}  // namespace vobb
