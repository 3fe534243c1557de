#include "render/tree_figure.h"

#define GL_GLEXT_PROTOTYPES 1
#include <GL/glcorearb.h>

#include <algorithm>
#include <cmath>
#include <initializer_list>

#include "common/obb.h"
#include "shaders/shaders.h"

namespace vobb {

namespace {

constexpr int kMaxLevel = 30;  // as the command line's --depth

// Links a vertex and a fragment shader; 0 with `log` set on failure.
GLuint program(const char* vert, const char* frag, std::string* log) {
  return gl_program({{GL_VERTEX_SHADER, vert}, {GL_FRAGMENT_SHADER, frag}}, log);
}

// Every GL object of one render, deleted on the way out whatever the outcome (the context is
// current for the whole call).
struct GlObjects {
  GLuint mesh_program = 0, fill_program = 0, lines_program = 0;
  GLuint vaos[3] = {0, 0, 0};           // mesh, fill, lines
  GLuint buffers[3] = {0, 0, 0};        // likewise
  GLuint fbos[2] = {0, 0};              // multisampled, resolved
  GLuint renderbuffers[3] = {0, 0, 0};  // multisampled colour and depth, resolved colour
  ~GlObjects() {
    glDeleteProgram(mesh_program);
    glDeleteProgram(fill_program);
    glDeleteProgram(lines_program);
    glDeleteVertexArrays(3, vaos);
    glDeleteBuffers(3, buffers);
    glDeleteFramebuffers(2, fbos);
    glDeleteRenderbuffers(3, renderbuffers);
  }
};

// GL errors are sticky until read; drain what an earlier user left so that a later check
// reports ours. Returns the first error, GL_NO_ERROR when none.
GLenum drain_errors() {
  GLenum first = GL_NO_ERROR;
  for (int i = 0; i < 64; ++i) {
    const GLenum e = glGetError();
    if (e == GL_NO_ERROR) break;
    if (first == GL_NO_ERROR) first = e;
  }
  return first;
}

std::string gl_error_name(GLenum e) {
  switch (e) {
    case GL_INVALID_ENUM:
      return "GL_INVALID_ENUM";
    case GL_INVALID_VALUE:
      return "GL_INVALID_VALUE";
    case GL_INVALID_OPERATION:
      return "GL_INVALID_OPERATION";
    case GL_INVALID_FRAMEBUFFER_OPERATION:
      return "GL_INVALID_FRAMEBUFFER_OPERATION";
    case GL_OUT_OF_MEMORY:
      return "GL_OUT_OF_MEMORY";
    default:
      return "GL error " + std::to_string(e);
  }
}

// The view frame: z towards the viewer, x screen right, y screen up.
struct ViewFrame {
  Vec3 x, y, z;
};

ViewFrame view_frame(const FigureOptions& o) {
  ViewFrame f;
  f.z = o.view.normalized();
  f.x = o.up.cross(f.z).normalized();
  f.y = f.z.cross(f.x);
  return f;
}

// The camera: world point p maps to q = (p - centre) / radius, inside the unit ball, and q to
// clip coordinates by an orthographic projection along the view frame. Depth: NDC z = -z.q /
// 1.01, inside (-1, 1) with room for the edges' depth bias. Screen: the square about the
// midpoint of the drawn points' screen extent, its half side the larger half extent, maps to
// the panel less a margin of `margin_px` on each side.
struct Camera {
  std::array<float, 16> view_proj{};  // column-major, applied to q
  Vec3 light;                         // unit, towards the light
};

Camera make_camera(const ViewFrame& f, const Vec3& lo, const Vec3& hi, double margin_px,
                   int panel_px) {
  // lo, hi: the extent of x.q and y.q over the drawn points (components 0 and 1).
  Camera cam;
  const double half = std::max(hi[0] - lo[0], hi[1] - lo[1]) / 2;
  const double s = (1.0 - 2.0 * margin_px / panel_px) / half;
  const double mx = (lo[0] + hi[0]) / 2, my = (lo[1] + hi[1]) / 2;
  const Vec3 rows[3] = {s * f.x, s * f.y, -f.z / 1.01};
  const double shift[3] = {-s * mx, -s * my, 0};
  cam.view_proj.fill(0.0f);
  for (int r = 0; r < 3; ++r) {
    for (int c = 0; c < 3; ++c) cam.view_proj[c * 4 + r] = static_cast<float>(rows[r][c]);
    cam.view_proj[12 + r] = static_cast<float>(shift[r]);
  }
  cam.view_proj[15] = 1.0f;
  // Light from the viewer's upper left, a little in front.
  cam.light = (-0.45 * f.x + 0.65 * f.y + 0.9 * f.z).normalized();
  return cam;
}

void hsv_to_rgb(double h, double s, double v, double rgb[3]) {
  const double k[3] = {5, 3, 1};
  for (int i = 0; i < 3; ++i) {
    const double t = std::fmod(k[i] + h * 6.0, 6.0);
    rgb[i] = v - v * s * std::max(0.0, std::min({t, 4.0 - t, 1.0}));
  }
}

// One panel's share of the fill and edge buffers.
struct PanelDraw {
  GLint fill_first = 0;
  GLsizei fill_count = 0;
  GLuint edge_first = 0;
  GLsizei edge_count = 0;
};

struct FillVertex {
  float pos[3];
  float color[4];
};
struct EdgeInstance {
  float p0[3], p1[3];
  float color[4];
};

}  // namespace

std::vector<int> default_figure_levels(const std::vector<FigureRow>& rows) {
  int depth = 0;
  for (const FigureRow& r : rows)
    if (r.tree != nullptr) depth = std::max(depth, r.tree->depth);
  std::vector<int> levels;
  for (int l = 1; l <= std::min(8, depth); ++l) levels.push_back(l);
  if (levels.empty()) levels.push_back(0);
  return levels;
}

std::array<uint8_t, 4> figure_box_color(size_t index) {
  // Golden-ratio hue steps: consecutive boxes sit about 222 degrees apart on the hue circle.
  const double hue = std::fmod(0.58 + 0.6180339887498949 * static_cast<double>(index % 4096), 1.0);
  const double value = index % 2 == 0 ? 0.88 : 0.70;  // alternate brightness too
  double rgb[3];
  hsv_to_rgb(hue, 0.85, value, rgb);
  std::array<uint8_t, 4> out;
  for (int i = 0; i < 3; ++i) out[i] = static_cast<uint8_t>(std::lround(255.0 * rgb[i]));
  out[3] = 255;
  return out;
}

Status set_figure_up(const std::string& axis, FigureOptions* o) {
  const bool negative = !axis.empty() && axis[0] == '-';
  const std::string name = negative ? axis.substr(1) : axis;
  if (name.size() != 1 || name[0] < 'x' || name[0] > 'z')
    return Status::error("figure up axis '" + axis + "': expected x, y, z, -x, -y or -z");
  const int k = name[0] - 'x';
  const Vec3 up = (negative ? -1.0 : 1.0) * Vec3::Unit(k);
  o->up = up;
  o->view = Vec3::Unit((k + 1) % 3) - 0.5 * Vec3::Unit((k + 2) % 3) + 0.45 * up;
  return Status::ok();
}

PanelRect figure_panel(const FigureOptions& o, int row, int column) {
  PanelRect r;
  r.side = o.panel_px;
  r.x0 = o.gap_px + column * (o.panel_px + o.gap_px);
  r.y0 = o.gap_px + row * (o.panel_px + o.gap_px);
  return r;
}

namespace {

// An error of the figure, as every one reads.
Status figure_error(const std::string& why) { return Status::error("tree figure: " + why); }

// Checks the arguments that need no GL context, in the order their errors are reported, and
// sets `levels` to the columns.
Status check_figure_arguments(const Mesh& mesh, const std::vector<FigureRow>& rows,
                              const FigureOptions& options, std::vector<int>* levels) {
  if (rows.empty()) return figure_error("no trees to draw");
  if (mesh.faces.empty()) return figure_error("the mesh has no faces");
  if (options.panel_px < 16)
    return figure_error("panel size " + std::to_string(options.panel_px) + " px is below 16");
  if (options.gap_px < 0) return figure_error("negative gap");
  for (size_t r = 0; r < rows.size(); ++r) {
    if (rows[r].tree == nullptr || rows[r].tree->nodes.empty())
      return figure_error("row " + std::to_string(r + 1) + " has no tree");
    if (rows[r].tree->mesh_triangles != mesh.faces.size())
      return figure_error("row " + std::to_string(r + 1) + " (" + rows[r].label +
                          ") was built for " + std::to_string(rows[r].tree->mesh_triangles) +
                          " triangles, the mesh has " + std::to_string(mesh.faces.size()));
  }
  *levels = options.levels.empty() ? default_figure_levels(rows) : options.levels;
  for (int l : *levels)
    if (l < 0 || l > kMaxLevel)
      return figure_error("level " + std::to_string(l) + " is outside 0.." +
                          std::to_string(kMaxLevel));
  const Vec3 view = options.view, up = options.up;
  if (!view.allFinite() || !up.allFinite() || view.norm() == 0 ||
      up.cross(view).norm() <= 1e-6 * up.norm() * view.norm())
    return figure_error("the view direction is zero or parallel to up");
  return Status::ok();
}

// What every panel shares: the ball that holds the mesh and every box drawn, the boxes of each
// panel, and the camera.
struct FigureScene {
  Vec3 centre;
  double radius = 0;
  std::vector<std::vector<std::vector<int32_t>>> layers;  // [row][column] node ids
  Camera cam;
};

// World point p in units of the scene's ball, as the vertex buffers hold it.
void to_unit(const FigureScene& scene, const Vec3& p, float q[3]) {
  for (int k = 0; k < 3; ++k) q[k] = static_cast<float>((p[k] - scene.centre[k]) / scene.radius);
}

// Sets up the scene: the ball, centred on the mesh's bounds, the layers drawn, and the camera
// that frames the screen extent of everything drawn.
Status frame_figure(const Mesh& mesh, const std::vector<FigureRow>& rows,
                    const FigureOptions& options, const std::vector<int>& levels,
                    FigureScene* scene) {
  // The ball: centred on the mesh's bounds, holding the mesh and every box that is drawn.
  const Aabb bounds = mesh.bounds();
  if (!bounds.lo.allFinite() || !bounds.hi.allFinite())
    return figure_error("the mesh has non-finite vertices");
  const Vec3 centre = 0.5 * (bounds.lo + bounds.hi);
  double radius = 0;
  for (const Vec3& v : mesh.vertices) radius = std::max(radius, (v - centre).norm());
  const int n_rows = static_cast<int>(rows.size());
  std::vector<std::vector<std::vector<int32_t>>>& layers = scene->layers;
  layers.assign(n_rows, {});
  for (int r = 0; r < n_rows; ++r)
    for (int l : levels) {
      layers[r].push_back(layer(*rows[r].tree, l));
      for (int32_t id : layers[r].back())
        for (const Vec3& c : corners(rows[r].tree->nodes[id].box))
          radius = std::max(radius, (c - centre).norm());
    }
  if (!(radius > 0) || !std::isfinite(radius))
    return figure_error("the mesh and boxes have no extent");
  scene->centre = centre;
  scene->radius = radius;
  // The screen extent of everything drawn, in units of the ball.
  const ViewFrame frame = view_frame(options);
  Vec3 lo = Vec3::Constant(HUGE_VAL), hi = Vec3::Constant(-HUGE_VAL);
  auto extend = [&](const Vec3& p) {
    const Vec3 q = (p - centre) / radius;
    const Vec3 screen(frame.x.dot(q), frame.y.dot(q), 0);
    lo = lo.cwiseMin(screen);
    hi = hi.cwiseMax(screen);
  };
  for (const Vec3& v : mesh.vertices) extend(v);
  for (int r = 0; r < n_rows; ++r)
    for (const auto& ids : layers[r])
      for (int32_t id : ids)
        for (const Vec3& c : corners(rows[r].tree->nodes[id].box)) extend(c);
  if (!(std::max(hi[0] - lo[0], hi[1] - lo[1]) > 1e-9))
    return figure_error("the mesh and boxes have no extent on screen");
  // Margin: an edge's quad reaches half its width past the edge's end and to either side, so
  // within edge_width_px of a drawn point; 2 px and 2 % more keep the panel's rim clear.
  const double margin_px = options.edge_width_px + 2.0 + 0.02 * options.panel_px;
  if (2 * margin_px >= options.panel_px) return figure_error("edges too wide for the panel");
  scene->cam = make_camera(frame, lo, hi, margin_px, options.panel_px);
  return Status::ok();
}

// The mesh's vertex data: three vertices per face, each with the face's unit normal (flat
// shading).
std::vector<float> mesh_vertex_data(const Mesh& mesh, const FigureScene& scene) {
  std::vector<float> mesh_data;
  mesh_data.reserve(mesh.faces.size() * 18);
  for (size_t f = 0; f < mesh.faces.size(); ++f) {
    const Vec3 &a = mesh.corner(f, 0), &b = mesh.corner(f, 1), &c = mesh.corner(f, 2);
    Vec3 n = (b - a).cross(c - a);
    n = n.norm() > 0 ? Vec3(n.normalized()) : Vec3(0, 0, 0);
    for (int k = 0; k < 3; ++k) {
      float q[3];
      to_unit(scene, mesh.corner(f, k), q);
      mesh_data.insert(mesh_data.end(), {q[0], q[1], q[2], static_cast<float>(n[0]),
                                         static_cast<float>(n[1]), static_cast<float>(n[2])});
    }
  }
  return mesh_data;
}

// The boxes' vertex data, panel by panel (row-major): two triangles per box face and one
// instance per box edge.
struct BoxGeometry {
  std::vector<FillVertex> fill;
  std::vector<EdgeInstance> edges;
  std::vector<PanelDraw> draws;
};

// Appends one box's edge instances, and where options.fill_alpha > 0 its fill triangles, in
// the colour of the `index`-th box of its layer.
void add_box(const FigureScene& scene, const FigureOptions& options, const Obb& box, size_t index,
             BoxGeometry* out) {
  const std::array<Vec3, 8> corner = corners(box);
  float q[8][3];
  for (int k = 0; k < 8; ++k) to_unit(scene, corner[k], q[k]);
  const std::array<uint8_t, 4> rgb = figure_box_color(index);
  float color[4];
  for (int k = 0; k < 4; ++k) color[k] = rgb[k] / 255.0f;
  for (int a = 0; a < 8; ++a)
    for (int bit = 1; bit < 8; bit <<= 1)
      if ((a & bit) == 0) {
        EdgeInstance e;
        std::copy(q[a], q[a] + 3, e.p0);
        std::copy(q[a | bit], q[a | bit] + 3, e.p1);
        std::copy(color, color + 4, e.color);
        out->edges.push_back(e);
      }
  if (options.fill_alpha > 0) {
    color[3] = options.fill_alpha;
    for (const auto& quad : kBoxQuads)
      for (int t : {0, 1, 2, 0, 2, 3}) {
        FillVertex v;
        std::copy(q[quad[t]], q[quad[t]] + 3, v.pos);
        std::copy(color, color + 4, v.color);
        out->fill.push_back(v);
      }
  }
}

// Every panel's boxes, in an n_rows x n_cols grid.
BoxGeometry box_geometry(const std::vector<FigureRow>& rows, const FigureOptions& options,
                         const FigureScene& scene, int n_rows, int n_cols) {
  BoxGeometry out;
  for (int r = 0; r < n_rows; ++r)
    for (int c = 0; c < n_cols; ++c) {
      PanelDraw d;
      d.fill_first = static_cast<GLint>(out.fill.size());
      d.edge_first = static_cast<GLuint>(out.edges.size());
      const std::vector<int32_t>& ids = scene.layers[r][c];
      for (size_t i = 0; i < ids.size(); ++i)
        add_box(scene, options, rows[r].tree->nodes[ids[i]].box, i, &out);
      d.fill_count = static_cast<GLsizei>(out.fill.size()) - d.fill_first;
      d.edge_count = static_cast<GLsizei>(out.edges.size() - d.edge_first);
      out.draws.push_back(d);
    }
  return out;
}

// Links the three programs into g.
Status link_programs(GlObjects* g) {
  std::string log;
  g->mesh_program =
      program(shaders::kShader_figure_mesh_vert, shaders::kShader_figure_mesh_frag, &log);
  if (!g->mesh_program) return figure_error("figure_mesh shaders: " + log);
  g->fill_program =
      program(shaders::kShader_figure_fill_vert, shaders::kShader_figure_fill_frag, &log);
  if (!g->fill_program) return figure_error("figure_fill shaders: " + log);
  g->lines_program =
      program(shaders::kShader_figure_lines_vert, shaders::kShader_figure_fill_frag, &log);
  if (!g->lines_program) return figure_error("figure_lines shaders: " + log);
  return Status::ok();
}

// Framebuffers: draw into the multisampled one, resolve into the plain one, read that.
Status create_framebuffers(GLsizei samples, long long width, long long height, GlObjects* g) {
  glGenRenderbuffers(3, g->renderbuffers);
  glBindRenderbuffer(GL_RENDERBUFFER, g->renderbuffers[0]);
  glRenderbufferStorageMultisample(GL_RENDERBUFFER, samples, GL_RGBA8, width, height);
  glBindRenderbuffer(GL_RENDERBUFFER, g->renderbuffers[1]);
  glRenderbufferStorageMultisample(GL_RENDERBUFFER, samples, GL_DEPTH_COMPONENT24, width, height);
  glBindRenderbuffer(GL_RENDERBUFFER, g->renderbuffers[2]);
  glRenderbufferStorage(GL_RENDERBUFFER, GL_RGBA8, width, height);
  glGenFramebuffers(2, g->fbos);
  glBindFramebuffer(GL_FRAMEBUFFER, g->fbos[1]);
  glFramebufferRenderbuffer(GL_FRAMEBUFFER, GL_COLOR_ATTACHMENT0, GL_RENDERBUFFER,
                            g->renderbuffers[2]);
  if (glCheckFramebufferStatus(GL_FRAMEBUFFER) != GL_FRAMEBUFFER_COMPLETE)
    return figure_error("resolve framebuffer incomplete");
  glBindFramebuffer(GL_FRAMEBUFFER, g->fbos[0]);
  glFramebufferRenderbuffer(GL_FRAMEBUFFER, GL_COLOR_ATTACHMENT0, GL_RENDERBUFFER,
                            g->renderbuffers[0]);
  glFramebufferRenderbuffer(GL_FRAMEBUFFER, GL_DEPTH_ATTACHMENT, GL_RENDERBUFFER,
                            g->renderbuffers[1]);
  if (glCheckFramebufferStatus(GL_FRAMEBUFFER) != GL_FRAMEBUFFER_COMPLETE)
    return figure_error("multisampled framebuffer incomplete (" + std::to_string(samples) +
                        " samples)");
  return Status::ok();
}

// Uploads the vertex data: the mesh's, the boxes' fill and their edge instances, each into its
// vertex array.
void upload_vertex_data(const std::vector<float>& mesh_data, const BoxGeometry& boxes,
                        GlObjects* g) {
  const std::vector<FillVertex>& fill = boxes.fill;
  const std::vector<EdgeInstance>& edges = boxes.edges;
  glGenVertexArrays(3, g->vaos);
  glGenBuffers(3, g->buffers);
  glBindVertexArray(g->vaos[0]);
  glBindBuffer(GL_ARRAY_BUFFER, g->buffers[0]);
  glBufferData(GL_ARRAY_BUFFER, mesh_data.size() * sizeof(float), mesh_data.data(), GL_STATIC_DRAW);
  glVertexAttribPointer(0, 3, GL_FLOAT, GL_FALSE, 6 * sizeof(float), nullptr);
  glVertexAttribPointer(1, 3, GL_FLOAT, GL_FALSE, 6 * sizeof(float),
                        reinterpret_cast<void*>(3 * sizeof(float)));
  glEnableVertexAttribArray(0);
  glEnableVertexAttribArray(1);
  glBindVertexArray(g->vaos[1]);
  glBindBuffer(GL_ARRAY_BUFFER, g->buffers[1]);
  glBufferData(GL_ARRAY_BUFFER, fill.size() * sizeof(FillVertex), fill.data(), GL_STATIC_DRAW);
  glVertexAttribPointer(0, 3, GL_FLOAT, GL_FALSE, sizeof(FillVertex),
                        reinterpret_cast<void*>(offsetof(FillVertex, pos)));
  glVertexAttribPointer(1, 4, GL_FLOAT, GL_FALSE, sizeof(FillVertex),
                        reinterpret_cast<void*>(offsetof(FillVertex, color)));
  glEnableVertexAttribArray(0);
  glEnableVertexAttribArray(1);
  glBindVertexArray(g->vaos[2]);
  glBindBuffer(GL_ARRAY_BUFFER, g->buffers[2]);
  glBufferData(GL_ARRAY_BUFFER, edges.size() * sizeof(EdgeInstance), edges.data(), GL_STATIC_DRAW);
  glVertexAttribPointer(0, 3, GL_FLOAT, GL_FALSE, sizeof(EdgeInstance),
                        reinterpret_cast<void*>(offsetof(EdgeInstance, p0)));
  glVertexAttribPointer(1, 3, GL_FLOAT, GL_FALSE, sizeof(EdgeInstance),
                        reinterpret_cast<void*>(offsetof(EdgeInstance, p1)));
  glVertexAttribPointer(2, 4, GL_FLOAT, GL_FALSE, sizeof(EdgeInstance),
                        reinterpret_cast<void*>(offsetof(EdgeInstance, color)));
  for (GLuint a = 0; a < 3; ++a) {
    glEnableVertexAttribArray(a);
    glVertexAttribDivisor(a, 1);
  }
}

// Sets the programs' uniforms: the camera, the light and the edges' width and depth bias.
void set_uniforms(const GlObjects& g, const Camera& cam, const FigureOptions& options) {
  glUseProgram(g.mesh_program);
  glUniformMatrix4fv(glGetUniformLocation(g.mesh_program, "u_view_proj"), 1, GL_FALSE,
                     cam.view_proj.data());
  glUniform3f(glGetUniformLocation(g.mesh_program, "u_light"), static_cast<float>(cam.light[0]),
              static_cast<float>(cam.light[1]), static_cast<float>(cam.light[2]));
  glUniform3f(glGetUniformLocation(g.mesh_program, "u_albedo"), 0.80f, 0.80f, 0.78f);
  glUseProgram(g.fill_program);
  glUniformMatrix4fv(glGetUniformLocation(g.fill_program, "u_view_proj"), 1, GL_FALSE,
                     cam.view_proj.data());
  glUseProgram(g.lines_program);
  glUniformMatrix4fv(glGetUniformLocation(g.lines_program, "u_view_proj"), 1, GL_FALSE,
                     cam.view_proj.data());
  glUniform2f(glGetUniformLocation(g.lines_program, "u_viewport"),
              static_cast<float>(options.panel_px), static_cast<float>(options.panel_px));
  glUniform1f(glGetUniformLocation(g.lines_program, "u_half_width"), 0.5f * options.edge_width_px);
  // Depth bias: 2^-9 of the NDC depth range [-1, 1] is 1/256 of the ball's diameter, enough
  // for an edge lying on the mesh (box faces touch it) to win over the 24-bit depth's
  // rounding, small enough that edges behind a fold of the mesh stay hidden.
  glUniform1f(glGetUniformLocation(g.lines_program, "u_depth_bias"), 1.0f / 512.0f);
}

// Clears the multisampled framebuffer of a width x height image to the gap colour and draws
// each of the n_rows x n_cols panels into it: background, mesh, box fill, box edges.
void draw_panels(const GlObjects& g, const Mesh& mesh, const FigureOptions& options,
                 const std::vector<PanelDraw>& draws, int n_rows, int n_cols, long long width,
                 long long height) {
  glBindFramebuffer(GL_FRAMEBUFFER, g.fbos[0]);
  glViewport(0, 0, static_cast<GLsizei>(width), static_cast<GLsizei>(height));
  glDisable(GL_SCISSOR_TEST);
  glColorMask(GL_TRUE, GL_TRUE, GL_TRUE, GL_TRUE);
  glDepthMask(GL_TRUE);
  auto clear_color = [](const std::array<uint8_t, 4>& c) {
    const GLfloat f[4] = {c[0] / 255.0f, c[1] / 255.0f, c[2] / 255.0f, c[3] / 255.0f};
    glClearBufferfv(GL_COLOR, 0, f);
  };
  clear_color(options.gap_color);
  const GLfloat far_depth = 1.0f;
  glClearBufferfv(GL_DEPTH, 0, &far_depth);
  glDisable(GL_CULL_FACE);
  glEnable(GL_MULTISAMPLE);
  for (int r = 0; r < n_rows; ++r)
    for (int c = 0; c < n_cols; ++c) {
      const PanelRect p = figure_panel(options, r, c);
      const GLint gl_y = static_cast<GLint>(height) - p.y0 - p.side;  // GL rows run bottom-up
      glViewport(p.x0, gl_y, p.side, p.side);
      glEnable(GL_SCISSOR_TEST);
      glScissor(p.x0, gl_y, p.side, p.side);
      clear_color(options.background);
      glDisable(GL_BLEND);
      glEnable(GL_DEPTH_TEST);
      glDepthFunc(GL_LESS);
      glDepthMask(GL_TRUE);
      glUseProgram(g.mesh_program);
      glBindVertexArray(g.vaos[0]);
      glDrawArrays(GL_TRIANGLES, 0, static_cast<GLsizei>(mesh.faces.size() * 3));
      const PanelDraw& d = draws[r * n_cols + c];
      if (d.fill_count > 0) {
        glEnable(GL_BLEND);
        glBlendEquation(GL_FUNC_ADD);
        glBlendFuncSeparate(GL_SRC_ALPHA, GL_ONE_MINUS_SRC_ALPHA, GL_ONE, GL_ONE_MINUS_SRC_ALPHA);
        glDepthMask(GL_FALSE);
        glUseProgram(g.fill_program);
        glBindVertexArray(g.vaos[1]);
        glDrawArrays(GL_TRIANGLES, d.fill_first, d.fill_count);
        glDisable(GL_BLEND);
        glDepthMask(GL_TRUE);
      }
      if (d.edge_count > 0) {
        glDepthFunc(GL_LEQUAL);
        glUseProgram(g.lines_program);
        glBindVertexArray(g.vaos[2]);
        glDrawArraysInstancedBaseInstance(GL_TRIANGLE_STRIP, 0, 4, d.edge_count, d.edge_first);
      }
    }
  glDisable(GL_SCISSOR_TEST);
  glDisable(GL_DEPTH_TEST);
  glDepthFunc(GL_LESS);
}

// Resolves the multisampled framebuffer into the plain one and reads it back, bottom row
// first, then unbinds the framebuffer, vertex array and program.
std::vector<uint8_t> resolve_and_read(const GlObjects& g, long long width, long long height) {
  glBindFramebuffer(GL_READ_FRAMEBUFFER, g.fbos[0]);
  glBindFramebuffer(GL_DRAW_FRAMEBUFFER, g.fbos[1]);
  glBlitFramebuffer(0, 0, width, height, 0, 0, width, height, GL_COLOR_BUFFER_BIT, GL_NEAREST);
  glBindFramebuffer(GL_READ_FRAMEBUFFER, g.fbos[1]);
  glPixelStorei(GL_PACK_ALIGNMENT, 1);
  glPixelStorei(GL_PACK_ROW_LENGTH, 0);
  glBindBuffer(GL_PIXEL_PACK_BUFFER, 0);
  std::vector<uint8_t> bottom_up(static_cast<size_t>(width) * height * 4);
  glReadPixels(0, 0, width, height, GL_RGBA, GL_UNSIGNED_BYTE, bottom_up.data());
  glBindFramebuffer(GL_FRAMEBUFFER, 0);
  glBindVertexArray(0);
  glUseProgram(0);
  return bottom_up;
}

}  // namespace

Status render_tree_figure(const GlContext& context, const Mesh& mesh,
                          const std::vector<FigureRow>& rows, const FigureOptions& options,
                          RgbaImage* out) {
  *out = RgbaImage();
  std::vector<int> levels;
  Status s = check_figure_arguments(mesh, rows, options, &levels);
  if (!s) return s;
  FigureScene scene;
  s = frame_figure(mesh, rows, options, levels, &scene);
  if (!s) return s;
  const int n_rows = static_cast<int>(rows.size()), n_cols = static_cast<int>(levels.size());
  const std::vector<float> mesh_data = mesh_vertex_data(mesh, scene);
  const BoxGeometry boxes = box_geometry(rows, options, scene, n_rows, n_cols);

  const long long width =
      static_cast<long long>(n_cols) * options.panel_px + (n_cols + 1LL) * options.gap_px;
  const long long height =
      static_cast<long long>(n_rows) * options.panel_px + (n_rows + 1LL) * options.gap_px;

  GlContext::Current bound(context);  // released after g's objects are deleted
  drain_errors();
  GlObjects g;
  GLint max_rb = 0, max_samples = 0;
  glGetIntegerv(GL_MAX_RENDERBUFFER_SIZE, &max_rb);
  glGetIntegerv(GL_MAX_SAMPLES, &max_samples);
  if (width > max_rb || height > max_rb)
    return figure_error("a " + std::to_string(width) + "x" + std::to_string(height) +
                        " image exceeds the renderer's " + std::to_string(max_rb) +
                        " px framebuffer limit");
  const GLsizei samples =
      std::max(0, std::min(options.samples > 1 ? options.samples : 0, max_samples));
  s = link_programs(&g);
  if (!s) return s;
  s = create_framebuffers(samples, width, height, &g);
  if (!s) return s;
  upload_vertex_data(mesh_data, boxes, &g);
  if (const GLenum e = drain_errors(); e != GL_NO_ERROR)
    return figure_error(gl_error_name(e) + " while setting up");
  set_uniforms(g, scene.cam, options);
  draw_panels(g, mesh, options, boxes.draws, n_rows, n_cols, width, height);
  const std::vector<uint8_t> bottom_up = resolve_and_read(g, width, height);
  if (const GLenum e = drain_errors(); e != GL_NO_ERROR)
    return figure_error(gl_error_name(e) + " while drawing");

  out->width = static_cast<int>(width);
  out->height = static_cast<int>(height);
  out->rgba.resize(bottom_up.size());
  const size_t row_bytes = static_cast<size_t>(width) * 4;
  for (long long y = 0; y < height; ++y)
    std::copy_n(bottom_up.data() + (height - 1 - y) * row_bytes, row_bytes,
                out->rgba.data() + y * row_bytes);
  return Status::ok();
}

}  // namespace vobb
