#include "fast/gl_estimator.h"

#define GL_GLEXT_PROTOTYPES 1
#include <GL/glcorearb.h>

#include <algorithm>
#include <cmath>
#include <cstring>

#include "fast/cubemap.h"
#include "vobb/shaders.h"

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

// Scale factor 2^-e bringing the largest |x_i| into [0.5, 1): exact in binary, so it keeps
// zeros, signs, exact negations between the faces of a shared edge, and the ratio plane/nd.
double pow2_normalizer(double a, double b, double c, double d = 0) {
  const double big = std::max({std::abs(a), std::abs(b), std::abs(c), std::abs(d)});
  if (big == 0 || !std::isfinite(big)) return 1;
  int e;
  std::frexp(big, &e);
  return std::ldexp(1.0, -e);
}

}  // namespace

struct GlObvEstimator::Gl {
  GLuint spans_program = 0, reduce_program = 0;
  GLuint vao = 0, records = 0, atlas = 0, fbo = 0, sums = 0;
  GLint max_texture = 0;
  int atlas_m = 0, atlas_w = 0, atlas_h = 0, tiles_per_row = 0, capacity = 0;
  // The batch being gathered.
  std::vector<SpanRecord> batch_records;
  std::vector<size_t> batch_boxes;         // output index of each tile
  std::vector<double> batch_scale, batch_constant;
  std::vector<double>* out = nullptr;
};

GlObvEstimator::GlObvEstimator(const Mesh& mesh) : planner_(mesh), gl_(new Gl) {}

GlObvEstimator::~GlObvEstimator() {
  if (!context_ || !gl_) return;
  context_->make_current();
  glDeleteProgram(gl_->spans_program);
  glDeleteProgram(gl_->reduce_program);
  glDeleteVertexArrays(1, &gl_->vao);
  glDeleteBuffers(1, &gl_->records);
  glDeleteBuffers(1, &gl_->sums);
  glDeleteFramebuffers(1, &gl_->fbo);
  glDeleteTextures(1, &gl_->atlas);
}

Status GlObvEstimator::create(const Mesh& mesh, std::unique_ptr<GlObvEstimator>* out, bool device_only) {
  out->reset();
  std::unique_ptr<GlObvEstimator> e(new GlObvEstimator(mesh));
  Status s = GlContext::create(&e->context_, device_only);
  if (!s) return s;
  Gl& g = *e->gl_;
  std::string log;
  g.spans_program = gl_program({{GL_VERTEX_SHADER, shaders::kShader_texel_spans_vert},
                                {GL_FRAGMENT_SHADER, shaders::kShader_texel_spans_frag}}, &log);
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
    glVertexAttribPointer(2 + k, 3, GL_FLOAT, GL_FALSE, stride,
                          reinterpret_cast<void*>(offsetof(SpanRecord, edge) + k * 3 * sizeof(float)));
  glVertexAttribPointer(5, 4, GL_FLOAT, GL_FALSE, stride, reinterpret_cast<void*>(offsetof(SpanRecord, plane)));
  for (GLuint a = 0; a < 6; ++a) {
    glEnableVertexAttribArray(a);
    glVertexAttribDivisor(a, 1);
  }
  glGenBuffers(1, &g.sums);
  glGenFramebuffers(1, &g.fbo);
  glGetIntegerv(GL_MAX_TEXTURE_SIZE, &g.max_texture);
  if (glGetError() != GL_NO_ERROR) return Status::error("GL estimator: OpenGL error while setting up");
  *out = std::move(e);
  return Status::ok();
}

int GlObvEstimator::max_m() const { return gl_->max_texture / 3; }

double GlObvEstimator::estimate(const Obb& box, int m) { return estimate(std::vector<Obb>{box}, m)[0]; }

std::vector<double> GlObvEstimator::estimate(const std::vector<Obb>& boxes, int m) {
  VOBB_ASSERT(m >= 1 && m <= max_m(), "GL cubemap resolution within 1..max_m()");
  context_->make_current();
  Gl& g = *gl_;
  if (g.atlas_m != m) {
    // An atlas of tiles of 3m x 2m texels: 4096 pixels a side (64 MiB), larger only for big m.
    const int side = std::min(g.max_texture, std::max(4096, 3 * m));
    g.tiles_per_row = side / (3 * m);
    const int rows = side / (2 * m);
    g.capacity = std::min(g.tiles_per_row * rows, 4096);
    g.atlas_w = g.tiles_per_row * 3 * m;
    g.atlas_h = (g.capacity + g.tiles_per_row - 1) / g.tiles_per_row * 2 * m;
    if (g.atlas) glDeleteTextures(1, &g.atlas);
    glGenTextures(1, &g.atlas);
    glBindTexture(GL_TEXTURE_2D, g.atlas);
    glTexStorage2D(GL_TEXTURE_2D, 1, GL_R32F, g.atlas_w, g.atlas_h);
    glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_MIN_FILTER, GL_NEAREST);
    glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_MAG_FILTER, GL_NEAREST);
    glBindFramebuffer(GL_FRAMEBUFFER, g.fbo);
    glFramebufferTexture2D(GL_FRAMEBUFFER, GL_COLOR_ATTACHMENT0, GL_TEXTURE_2D, g.atlas, 0);
    VOBB_ASSERT(glCheckFramebufferStatus(GL_FRAMEBUFFER) == GL_FRAMEBUFFER_COMPLETE, "R32F atlas is renderable");
    g.atlas_m = m;
  }
  std::vector<double> out(boxes.size(), 0.0);
  g.out = &out;
  for (size_t b = 0; b < boxes.size(); ++b) {
    const BoxPlan plan = planner_.plan(boxes[b], m);
    if (plan.flat) continue;  // OBV 0
    out[b] = plan.frame.volume_scale * plan.constant;  // the whole answer when nothing is drawn
    const size_t records_before = g.batch_records.size();
    const int tile = static_cast<int>(g.batch_boxes.size());
    const int tile_x = tile % g.tiles_per_row * 3 * m, tile_y = tile / g.tiles_per_row * 2 * m;
    std::vector<std::array<float, 13>> tri_data(plan.tris.size());
    for (size_t t = 0; t < plan.tris.size(); ++t) {
      const LocalTriangle& tri = plan.tris[t];
      for (int k = 0; k < 3; ++k) {
        const Vec3& e = tri.edge_cross[k];
        const double f = pow2_normalizer(e[0], e[1], e[2]);
        for (int c = 0; c < 3; ++c) tri_data[t][3 * k + c] = static_cast<float>(e[c] * f);
      }
      const double f = pow2_normalizer(tri.normal[0], tri.normal[1], tri.normal[2]);
      for (int c = 0; c < 3; ++c) tri_data[t][9 + c] = static_cast<float>(tri.normal[c] * f);
      tri_data[t][12] = static_cast<float>(tri.plane * f);
    }
    for (const TexelSpan& span : plan.spans) {
      if (span.i0 > span.i1 || span.j0 > span.j1) continue;  // covers no texel centre
      SpanRecord r;
      r.span[0] = span.i0;
      r.span[1] = span.j0;
      r.span[2] = span.i1;
      r.span[3] = span.j1;
      r.meta[0] = tile_x + span.face % 3 * m;
      r.meta[1] = tile_y + span.face / 3 * m;
      r.meta[2] = span.face | (plan.far_count << 6);
      r.meta[3] = 0;
      std::memcpy(r.edge, tri_data[span.tri].data(), 9 * sizeof(float));
      std::memcpy(r.plane, tri_data[span.tri].data() + 9, 4 * sizeof(float));
      g.batch_records.push_back(r);
    }
    if (g.batch_records.size() == records_before) continue;  // no span covers a texel centre
    g.batch_boxes.push_back(b);
    g.batch_scale.push_back(plan.frame.volume_scale);
    g.batch_constant.push_back(plan.constant);
    // Flush when the atlas is full, or the span records pass 64 MiB (boxes in far-count mode or
    // without culling draw every face of the mesh).
    constexpr size_t kMaxRecords = (size_t{64} << 20) / sizeof(SpanRecord);
    if (!batching_ || static_cast<int>(g.batch_boxes.size()) == g.capacity || g.batch_records.size() >= kMaxRecords)
      flush(m);
  }
  if (!g.batch_boxes.empty()) flush(m);
  g.out = nullptr;
  return out;
}

void GlObvEstimator::flush(int m) {
  Gl& g = *gl_;
  const int n = static_cast<int>(g.batch_boxes.size());
  const int rows = (n + g.tiles_per_row - 1) / g.tiles_per_row;
  glBindFramebuffer(GL_FRAMEBUFFER, g.fbo);
  glViewport(0, 0, g.atlas_w, g.atlas_h);
  glEnable(GL_SCISSOR_TEST);
  glScissor(0, 0, n < g.tiles_per_row ? n * 3 * m : g.atlas_w, rows * 2 * m);
  const GLfloat zero[4] = {0, 0, 0, 0};
  glClearBufferfv(GL_COLOR, 0, zero);
  glDisable(GL_SCISSOR_TEST);
  glEnable(GL_BLEND);
  glBlendEquation(GL_FUNC_ADD);
  glBlendFunc(GL_ONE, GL_ONE);
  glDisable(GL_DEPTH_TEST);
  glDisable(GL_CULL_FACE);

  glUseProgram(g.spans_program);
  glUniform2f(glGetUniformLocation(g.spans_program, "u_atlas_size"), static_cast<float>(g.atlas_w),
              static_cast<float>(g.atlas_h));
  glUniform1i(glGetUniformLocation(g.spans_program, "u_m"), m);
  glBindVertexArray(g.vao);
  glBindBuffer(GL_ARRAY_BUFFER, g.records);
  glBufferData(GL_ARRAY_BUFFER, g.batch_records.size() * sizeof(SpanRecord), g.batch_records.data(), GL_STREAM_DRAW);
  glDrawArraysInstanced(GL_TRIANGLE_STRIP, 0, 4, static_cast<GLsizei>(g.batch_records.size()));
  glDisable(GL_BLEND);

  glMemoryBarrier(GL_TEXTURE_FETCH_BARRIER_BIT);
  glUseProgram(g.reduce_program);
  glActiveTexture(GL_TEXTURE0);
  glBindTexture(GL_TEXTURE_2D, g.atlas);
  glUniform1i(glGetUniformLocation(g.reduce_program, "u_atlas"), 0);
  glUniform1i(glGetUniformLocation(g.reduce_program, "u_m"), m);
  glUniform1i(glGetUniformLocation(g.reduce_program, "u_tiles_per_row"), g.tiles_per_row);
  glBindBuffer(GL_SHADER_STORAGE_BUFFER, g.sums);
  glBufferData(GL_SHADER_STORAGE_BUFFER, n * sizeof(float), nullptr, GL_STREAM_READ);
  glBindBufferBase(GL_SHADER_STORAGE_BUFFER, 0, g.sums);
  glDispatchCompute(n, 1, 1);
  glMemoryBarrier(GL_BUFFER_UPDATE_BARRIER_BIT);
  std::vector<float> sums(n);
  glGetBufferSubData(GL_SHADER_STORAGE_BUFFER, 0, n * sizeof(float), sums.data());
  VOBB_ASSERT(glGetError() == GL_NO_ERROR, "GL estimator batch ran without GL errors");
  ++round_trips_;

  const double texel_weight = 4.0 / (3.0 * m * m);
  for (int t = 0; t < n; ++t)
    (*g.out)[g.batch_boxes[t]] = g.batch_scale[t] * (g.batch_constant[t] + texel_weight * static_cast<double>(sums[t]));
  g.batch_records.clear();
  g.batch_boxes.clear();
  g.batch_scale.clear();
  g.batch_constant.clear();
}

// ---- the deviation bound -----------------------------------------------------------------
//
// The shaders see the plan's doubles rounded to float (after exact power-of-two scaling) and
// compute, per texel and span, with u = 2^-24 (float unit round-off):
//  - the direction d: components -1 + (2i+1)/m; GLSL allows 2.5 ulp for a division and the
//    quotient is at most 2 in magnitude, so each of the two varying components is off by at
//    most 2.5u*2 + u (the subtraction) < 8u, absolutely; the axis component +-1 is exact;
//  - dot products d.E with E rounded (relative u) and three roundings of a 3-term sum (gamma_3):
//    |fl(d.E) - d.E| <= 8u (|E_a| + |E_b|) + 5u sum_i |d_i E_i| =: err(E).
//    An edge test whose |d.E| <= err(E) may come out either way ("uncertain"), as may one with
//    a float-underflowing input;
//  - zeta = plane / nd: nd has relative error r = err(n) / |nd|; with the plane rounded (u) and
//    the division (2.5u, taken as 3u), zeta's relative error is at most
//    z = (1 + r) / (1 - r) (1 + u)(1 + 3u) - 1, and zeta^3's at most (1 + z)^3 (1 + u)^2 - 1 =: z3;
//  - a hit's value s (1 - zeta^3) (or -s zeta^3) is then off by at most zeta^3 z3 + u (1 + zeta^3 (1 + z3)).
//  - A hit whose zeta lies within its error of a threshold (0 or 1) may be counted or not: at
//    1 the two sides differ by |1 - zeta^3| plus the error above. At 0 the float zeta keeps
//    the exact sign as long as r < 1/2 and the plane does not underflow; otherwise (a grazing
//    ray, or a centre within float underflow of the face's plane) the pair is uncertain.
//  - An uncertain (texel, face) pair adds 2: each side's value lies in [-1, 1].
//  - Sums (assuming round-to-nearest float blending, which GL does not promise but every
//    implementation we know does): each texel blends its hits in float, and the reduction adds per lane
//    ceil(6m^2 / 256) texels and then 8 tree levels: all in all at most K = H + ceil(6m^2/256)
//    + 8 additions per term, H the most hits in one texel, so the summation error is at most
//    gamma_K sum |values| (the recursive-summation bound, Higham, Accuracy and Stability of
//    Numerical Algorithms, 2nd ed., eq. 4.4).
// The double side (the CPU twin) has round-off some 2^29 times smaller, far below this bound.
// The bound is first-principles, not fitted: the test asserts it, and reports how close the
// observed deviations come to it.
double gl_deviation_bound(const BoxPlan& plan, int m) {
  if (plan.flat || plan.spans.empty()) return 0.0;
  constexpr double u = 1.0 / (1 << 24);
  auto gamma = [&](double n) { return n * u / (1 - n * u); };
  constexpr double kFloatMin = 1.1754943508222875e-38;
  double sum_abs = 0, errors = 0, uncertain = 0;
  std::vector<uint16_t> hits(6 * static_cast<size_t>(m) * m, 0);
  for (const TexelSpan& span : plan.spans) {
    const LocalTriangle& t = plan.tris[span.tri];
    const int k = span.face / 2, a = (k + 1) % 3, b = (k + 2) % 3;
    const double fn = pow2_normalizer(t.normal[0], t.normal[1], t.normal[2]);
    // zeta = plane / nd with |nd| up to 3 (|d_i| <= 1, |n_i| < 1 after scaling): a plane below
    // 3 FLT_MIN may give a subnormal zeta, which GLSL may flush to 0.
    const bool plane_underflows = t.plane != 0 && std::abs(t.plane * fn) < 3 * kFloatMin;
    double fe[3];  // the shader's power-of-two scale of each edge cross
    for (int e = 0; e < 3; ++e) fe[e] = pow2_normalizer(t.edge_cross[e][0], t.edge_cross[e][1], t.edge_cross[e][2]);
    for (int i = span.i0; i <= span.i1; ++i) {
      for (int j = span.j0; j <= span.j1; ++j) {
        const Vec3 d = cubemap_direction(span.face, texel_center(i, m), texel_center(j, m));
        // Edge tests: definite sides must agree; any uncertain one makes the pair uncertain.
        int definite = 0;
        bool unsure = false, miss = false;
        for (int e = 0; e < 3 && !miss; ++e) {
          const Vec3& E = t.edge_cross[e];
          const double dot = d.dot(E) * fe[e];
          const double err = 8 * u * (std::abs(E[a]) + std::abs(E[b])) * fe[e] +
                             5 * u * d.cwiseAbs().dot(E.cwiseAbs()) * fe[e] + 3 * kFloatMin;
          int side;
          if (std::abs(dot) <= err) {
            unsure = true;
            continue;
          }
          side = dot > 0 ? 1 : -1;
          if (definite == 0) definite = side;
          else if (side != definite) miss = true;
        }
        if (miss) continue;
        const size_t texel = (static_cast<size_t>(span.face) * m + i) * m + j;
        if (unsure || plane_underflows) {
          uncertain += 1;
          hits[texel] = static_cast<uint16_t>(std::min(65535, hits[texel] + 1));
          continue;
        }
        const double nd = t.normal.dot(d);
        const double r = (8 * u * (std::abs(t.normal[a]) + std::abs(t.normal[b])) +
                          5 * u * d.cwiseAbs().dot(t.normal.cwiseAbs())) / std::abs(nd);
        if (!(r < 0.5)) {
          uncertain += 1;
          hits[texel] = static_cast<uint16_t>(std::min(65535, hits[texel] + 1));
          continue;
        }
        const double zeta = t.plane / nd;
        if (zeta <= 0) continue;  // r < 1/2 keeps nd's sign, rounding keeps the plane's: GL agrees
        const double z = (1 + r) / (1 - r) * (1 + u) * (1 + 3 * u) - 1;
        const bool near_one = std::abs(zeta - 1) <= zeta * z;
        if (zeta >= 1 && !near_one) {  // beyond the box in both: nothing, or exactly -s (far)
          if (plan.far_count) {
            sum_abs += 1;
            hits[texel] = static_cast<uint16_t>(std::min(65535, hits[texel] + 1));
          }
          continue;
        }
        const double z3 = std::pow(1 + z, 3) * (1 + u) * (1 + u) - 1;
        const double c3 = zeta * zeta * zeta;
        const double value_err = c3 * z3 + u * (1 + c3 * (1 + z3));
        hits[texel] = static_cast<uint16_t>(std::min(65535, hits[texel] + 1));
        sum_abs += std::min(1.0, (plan.far_count ? c3 : std::abs(1 - c3)) + value_err);
        errors += value_err + (near_one ? std::abs(1 - c3) : 0);
      }
    }
  }
  const uint16_t most = *std::max_element(hits.begin(), hits.end());
  const double lanes = std::ceil(6.0 * m * m / 256);
  const double summation = gamma(most + lanes + 8) * (sum_abs + 2 * uncertain);
  const double texel_weight = 4.0 / (3.0 * m * m);
  return plan.frame.volume_scale * texel_weight * (errors + 2 * uncertain + summation);
}

}  // namespace vobb
