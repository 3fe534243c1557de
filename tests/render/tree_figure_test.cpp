#include "render/tree_figure.h"

#include <gtest/gtest.h>

#include <cstdlib>
#include <cstring>
#include <memory>
#include <set>
#include <thread>

#include "builder/obbtree_builder.h"
#include "common/png_io.h"
#include "data/analytic_meshes.h"
#include "fast/gl_estimator.h"
#include "fast/gl_test_util.h"
#include "test_common.h"

namespace vobb {
namespace {

bool same_rgba(const uint8_t* p, const std::array<uint8_t, 4>& c) {
  return std::memcmp(p, c.data(), 4) == 0;
}

// A 6 x 2 x 1 brick (the cube's 12 faces, stretched): distinct extents give the baseline
// definite covariance axes, so its boxes are the brick's own and lie inside it, and the view
// through the panel centre meets a brick face away from every box edge.
Mesh brick() {
  Mesh m = analytic::cube(2.0, Vec3(-1, -1, -1)).mesh;
  for (Vec3& v : m.vertices) v = Vec3(3 * v[0], v[1], 0.5 * v[2]);
  return m;
}

// Two rows over the brick: the baseline at arity 2 and at arity 3, depth 2, so that each
// panel holds a few boxes.
struct Fixture {
  Mesh mesh = brick();
  Tree binary = build_obbtree(mesh, {2, 2});
  Tree ternary = build_obbtree(mesh, {2, 3});
  std::vector<FigureRow> rows() const { return {{"arity 2", &binary}, {"arity 3", &ternary}}; }
};

FigureOptions small_options() {
  FigureOptions o;
  o.panel_px = 96;
  o.gap_px = 2;
  o.edge_width_px = 3;  // wide enough for interior pixels that every sample covers
  // Pinned, not the default, so that a change of the default look does not move the brick's
  // coincident box edges (from which only one colour may show) under these checks.
  o.view = Vec3(1.0, 0.7, 1.5);
  return o;
}

TEST(TreeFigure, DefaultLevelsAreOneToDepthCappedAtEight) {
  Tree deep, shallow, root_only;
  deep.depth = 11;
  shallow.depth = 3;
  EXPECT_EQ(default_figure_levels({{"a", &shallow}}), (std::vector<int>{1, 2, 3}));
  EXPECT_EQ(default_figure_levels({{"a", &shallow}, {"b", &deep}}),
            (std::vector<int>{1, 2, 3, 4, 5, 6, 7, 8}));
  EXPECT_EQ(default_figure_levels({{"a", &root_only}}), (std::vector<int>{0}));
}

TEST(TreeFigure, UpAxisSetsAnObliqueViewAboutIt) {
  FigureOptions o;
  ASSERT_TRUE(set_figure_up("y", &o));
  const FigureOptions defaults;
  EXPECT_EQ(o.view, defaults.view);
  EXPECT_EQ(o.up, defaults.up);
  ASSERT_TRUE(set_figure_up("-z", &o));
  EXPECT_EQ(o.up, Vec3(0, 0, -1));
  EXPECT_EQ(o.view, Vec3(1, -0.5, -0.45));
  EXPECT_FALSE(set_figure_up("w", &o));
  EXPECT_FALSE(set_figure_up("", &o));
  EXPECT_FALSE(set_figure_up("--y", &o));
}

TEST(TreeFigure, BoxColoursOfALayerDiffer) {
  std::set<std::array<uint8_t, 4>> seen;
  for (size_t i = 0; i < 64; ++i) seen.insert(figure_box_color(i));
  EXPECT_EQ(seen.size(), 64u);
}

TEST(TreeFigure, GridOfPanelsShowsMeshAndBoxes) {
  VOBB_MAKE_CONTEXT(ctx);
  const Fixture f;
  FigureOptions o = small_options();
  o.fill_alpha = 0;  // no tint: the mesh's own grey shows
  RgbaImage img;
  const Status s = render_tree_figure(*ctx, f.mesh, f.rows(), o, &img);
  ASSERT_TRUE(s) << s.message();
  // Default levels 1..2: 2 columns, 2 rows.
  ASSERT_EQ(img.width, 2 * 96 + 3 * 2);
  ASSERT_EQ(img.height, 2 * 96 + 3 * 2);
  ASSERT_EQ(img.rgba.size(), static_cast<size_t>(img.width) * img.height * 4);
  // Image corners are the border colour.
  for (int x : {0, img.width - 1})
    for (int y : {0, img.height - 1})
      EXPECT_TRUE(same_rgba(img.pixel(x, y), o.gap_color)) << x << "," << y;
  const Tree* trees[2] = {&f.binary, &f.ternary};
  for (int r = 0; r < 2; ++r)
    for (int c = 0; c < 2; ++c) {
      const PanelRect p = figure_panel(o, r, c);
      SCOPED_TRACE("panel row " + std::to_string(r) + " column " + std::to_string(c));
      // The camera keeps everything drawn at least edge width + 2 px from the panel's rim
      // (tree_figure.h), so the corner pixels are the background, exactly.
      for (int x : {p.x0, p.x0 + p.side - 1})
        for (int y : {p.y0, p.y0 + p.side - 1})
          EXPECT_TRUE(same_rgba(img.pixel(x, y), o.background));
      // The centre looks at the brick: most pixels of a 9x9 window there are the mesh's grey
      // (albedo 0.80, 0.80, 0.78 times a shade in [0.38, 1]: r == g up to rounding, b a
      // little lower), not the white background. An edge may cross the window, hence "most".
      int grey = 0;
      for (int y = p.y0 + p.side / 2 - 4; y <= p.y0 + p.side / 2 + 4; ++y)
        for (int x = p.x0 + p.side / 2 - 4; x <= p.x0 + p.side / 2 + 4; ++x) {
          const uint8_t* px = img.pixel(x, y);
          // Red is 0.80 (0.38 + 0.62 lambert) of 255: 77.5 to 204, to 8-bit rounding.
          if (std::abs(px[0] - px[1]) <= 1 && px[2] <= px[1] && px[1] - px[2] <= 6 && px[0] >= 77 &&
              px[0] <= 205)
            ++grey;
        }
      EXPECT_GE(grey, 41) << "of 81";
      // Some pixel of the panel has exactly the colour of one of this layer's boxes: an edge
      // drawn unlit and opaque, 3 px wide, covers whole pixels (all samples: resolve is exact).
      const std::vector<int32_t> ids = layer(*trees[r], c + 1);
      std::set<std::array<uint8_t, 4>> colours;
      for (size_t i = 0; i < ids.size(); ++i) colours.insert(figure_box_color(i));
      std::set<std::array<uint8_t, 4>> found;
      for (int y = p.y0; y < p.y0 + p.side; ++y)
        for (int x = p.x0; x < p.x0 + p.side; ++x) {
          std::array<uint8_t, 4> px;
          std::memcpy(px.data(), img.pixel(x, y), 4);
          if (colours.count(px)) found.insert(px);
        }
      EXPECT_GE(found.size(), 2u) << "at least two boxes' edges visible";
      // Border pixels between panels keep the border colour.
      EXPECT_TRUE(same_rgba(img.pixel(p.x0 - 1, p.y0 + p.side / 2), o.gap_color));
    }
}

TEST(TreeFigure, LevelsAndPanelSizeFollowOptions) {
  VOBB_MAKE_CONTEXT(ctx);
  const Fixture f;
  FigureOptions o = small_options();
  o.levels = {0, 1, 2, 5};  // 5 is past the depth: the leaves
  o.panel_px = 40;
  o.gap_px = 0;
  RgbaImage img;
  const Status s = render_tree_figure(*ctx, f.mesh, {{"one", &f.binary}}, o, &img);
  ASSERT_TRUE(s) << s.message();
  EXPECT_EQ(img.width, 4 * 40);
  EXPECT_EQ(img.height, 40);
  // Level 5 is past the depth, so it shows the leaves, as level 2 does. Side by side the two
  // panels sit at different window offsets, where float rounding of the viewport transform
  // may flip a few edge samples; so each level is rendered alone, at the same offset, where
  // the same scene must give the same bytes, and another layer (level 1) must not.
  auto alone = [&](int level) {
    FigureOptions one = o;
    one.levels = {level};
    RgbaImage single;
    const Status st = render_tree_figure(*ctx, f.mesh, {{"one", &f.binary}}, one, &single);
    EXPECT_TRUE(st) << st.message();
    return single.rgba;
  };
  const std::vector<uint8_t> level2 = alone(2), level5 = alone(5), level1 = alone(1);
  ASSERT_EQ(level2.size(), 40u * 40 * 4);
  EXPECT_TRUE(level2 == level5) << "level 5 (past the depth) must draw the leaves, as level 2 does";
  EXPECT_FALSE(level1 == level5) << "level 1 must differ from the leaves";
}

TEST(TreeFigure, BadInputIsAStatusNotACrash) {
  VOBB_MAKE_CONTEXT(ctx);
  const Fixture f;
  RgbaImage img;
  EXPECT_FALSE(render_tree_figure(*ctx, f.mesh, {}, small_options(), &img));
  const analytic::AnalyticMesh other = analytic::octahedron();
  EXPECT_FALSE(
      render_tree_figure(*ctx, other.mesh, f.rows(), small_options(), &img));  // wrong mesh
  FigureOptions o = small_options();
  o.levels = {-1};
  EXPECT_FALSE(render_tree_figure(*ctx, f.mesh, f.rows(), o, &img));
  o = small_options();
  o.panel_px = 1 << 20;  // beyond any renderer's framebuffer
  const Status s = render_tree_figure(*ctx, f.mesh, f.rows(), o, &img);
  EXPECT_FALSE(s);
  EXPECT_EQ(s.message().find('\n'), std::string::npos);
  EXPECT_TRUE(img.rgba.empty());
}

TEST(TreeFigure, PngRoundTripKeepsEveryPixel) {
  VOBB_MAKE_CONTEXT(ctx);
  const Fixture f;
  RgbaImage img;
  ASSERT_TRUE(render_tree_figure(*ctx, f.mesh, f.rows(), small_options(), &img));
  const std::string path = test::temp_path("figure.png");
  const Status w = write_png(path, img);
  ASSERT_TRUE(w) << w.message();
  RgbaImage back;
  const Status r = read_png(path, &back);
  std::remove(path.c_str());
  ASSERT_TRUE(r) << r.message();
  EXPECT_EQ(back.width, img.width);
  EXPECT_EQ(back.height, img.height);
  EXPECT_TRUE(back.rgba == img.rgba);
}

// The command line draws a figure with the GL estimator's context after a build whose calls
// came from several threads (compare --backend gl --figure): the estimator's drawing thread
// holds the context only while it draws, so the figure can bind it between calls, and the
// estimator draws again after it (render_tree_figure releases it). The figure is the one drawn
// with a context of its own, pixel for pixel: the same renderer and drawing.
TEST(TreeFigure, DrawsWithAGlEstimatorsContextBetweenItsCalls) {
  VOBB_MAKE_CONTEXT(own);
  const Fixture f;
  VOBB_MAKE_GL(gl, f.mesh);
  std::vector<Obb> boxes;
  for (const TreeNode& n : f.binary.nodes) boxes.push_back(n.box);
  std::vector<double> first[2];
  std::thread a([&] { first[0] = gl->estimate(boxes, 8); });
  std::thread b([&] { first[1] = gl->estimate(boxes, 8); });
  a.join();
  b.join();
  EXPECT_EQ(first[0], first[1]);
  const FigureOptions o = small_options();
  RgbaImage shared, alone;
  Status s = render_tree_figure(gl->context(), f.mesh, f.rows(), o, &shared);
  ASSERT_TRUE(s) << s.message();
  s = render_tree_figure(*own, f.mesh, f.rows(), o, &alone);
  ASSERT_TRUE(s) << s.message();
  EXPECT_EQ(shared.rgba, alone.rgba);
  EXPECT_EQ(gl->estimate(boxes, 8), first[0]);
  gl.reset();  // joins the drawing thread, which deletes the GL objects in the context
}

}  // namespace
}  // namespace vobb
