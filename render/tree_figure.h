// vobb::render_tree_figure — the paper's Figure 6 layout: a grid of panels, one row per tree and
// one column per level, each panel the mesh flat-shaded with that level's boxes over it.
//
// Drawn offscreen through a GlContext (gl_context.h) into a multisampled framebuffer and read
// back as RGBA8. Every panel uses the same orthographic camera: a fixed oblique view along
// `FigureOptions::view`, framed so that the mesh and every box drawn in any panel fit inside
// each panel with a margin of edge_width_px + 2 px + 2 %: all panels share one scale, nothing
// is cut off, and a panel's rim shows the background.
//
// In a panel, layer L of a tree (tree.h: the nodes at level L and every leaf above it) is
// drawn as each box's 12 edges in a colour of its own (figure_box_color) over a faint fill of
// its faces in that colour; the mesh hides what is behind it. The image carries no text: the
// caller says which row is which.
//
// Shaders: shaders/figure_{mesh,fill}.{vert,frag}, shaders/figure_lines.vert, embedded at
// build time. GL state the estimator relies on is set by it before each use, so the two can
// share a context.
#pragma once

#include <array>
#include <cstdint>
#include <string>
#include <vector>

#include "common/mesh.h"
#include "common/rgba_image.h"
#include "common/status.h"
#include "common/tree.h"
#include "fast/gl_context.h"

namespace vobb {

struct FigureRow {
  std::string label;           // method name, for the caller's legend only
  const Tree* tree = nullptr;  // not owned; must outlive the call
};

struct FigureOptions {
  std::vector<int>
      levels;          // columns; empty: 1..min(8, deepest depth of the rows), or {0} for depth 0
  int panel_px = 256;  // side of a square panel, pixels, >= 16
  int gap_px = 3;      // border around and between panels, pixels, >= 0
  int samples = 8;     // multisampling; clamped to what the renderer offers (1: none)
  float edge_width_px = 1.6f;         // box edges, pixels
  float fill_alpha = 0.12f;           // box faces' opacity; 0 draws no fill
  Vec3 view = Vec3(-0.5, 0.45, 1.0);  // towards the viewer (world coordinates); need not be unit
  Vec3 up = Vec3(0.0, 1.0, 0.0);      // world up; must not be parallel to `view`
  std::array<uint8_t, 4> background = {255, 255, 255, 255};  // inside panels
  std::array<uint8_t, 4> gap_color = {190, 190, 190, 255};   // the border
};

// Sets `up` to a world axis, "x", "y" or "z", optionally signed ("-z"), and `view` to the same
// oblique direction about it as the default about +y: up u = +-e_k, view = e_(k+1) - 0.5
// e_(k+2) + 0.45 u (indices mod 3). Meshes come y-up or z-up; this stands either upright.
Status set_figure_up(const std::string& axis, FigureOptions* options);

// The default columns for these rows (see FigureOptions::levels).
std::vector<int> default_figure_levels(const std::vector<FigureRow>& rows);

// Colour of the `index`-th box of a layer (ascending node id): hues stepped by the golden
// ratio so that neighbours in the list differ, saturated enough to stand out from the grey
// mesh. Alpha 255.
std::array<uint8_t, 4> figure_box_color(size_t index);

// Pixel rectangle of panel (row, column) in the image: x0, y0 (top-left, rows top-down), side.
struct PanelRect {
  int x0 = 0, y0 = 0, side = 0;
};
PanelRect figure_panel(const FigureOptions& options, int row, int column);

// Renders the grid into `out` (width = columns * panel + (columns + 1) * gap, likewise height).
// Preconditions (checked, an error Status): rows non-empty, each tree non-null and built for
// this mesh (faces < mesh size), each level in [0, 30], panel_px >= 16, the image within the
// renderer's framebuffer limits, a mesh with at least one face and finite vertices. A level
// deeper than a tree's depth shows that tree's leaves. Binds `context` to the calling thread
// for the render and releases it after; it must not be current on another thread (a GL
// estimator's context is not, between its calls). GL errors come back as a one-line Status.
Status render_tree_figure(const GlContext& context, const Mesh& mesh,
                          const std::vector<FigureRow>& rows, const FigureOptions& options,
                          RgbaImage* out);

}  // namespace vobb
