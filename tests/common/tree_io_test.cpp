#include "common/tree_io.h"

#include <gtest/gtest.h>
#include <sys/stat.h>

#include <cstdio>
#include <fstream>

#include "common/sha256.h"
#include "common/text_util.h"
#include "octahedron_trees.h"
#include "test_common.h"

namespace vobb {
namespace {

// A two-level tree over the octahedron: root, two leaves of four faces each.
Tree small_tree() {
  Tree t = test::octahedron_tree(1, {{-1, 0, {1, 2}, {0, 1, 2, 3, 4, 5, 6, 7}},
                                     {0, 1, {}, {0, 1, 2, 3}},
                                     {0, 1, {}, {4, 5, 6, 7}}});
  t.mesh_sha256 = "abc";
  return t;
}

void expect_same(const Tree& x, const Tree& y) {
  EXPECT_EQ(x.method, y.method);
  EXPECT_EQ(x.arity, y.arity);
  EXPECT_EQ(x.depth, y.depth);
  EXPECT_EQ(x.mesh_triangles, y.mesh_triangles);
  EXPECT_EQ(x.mesh_sha256, y.mesh_sha256);
  ASSERT_EQ(x.nodes.size(), y.nodes.size());
  for (size_t i = 0; i < x.nodes.size(); ++i) {
    const TreeNode &a = x.nodes[i], &b = y.nodes[i];
    EXPECT_EQ(a.id, b.id);
    EXPECT_EQ(a.parent, b.parent);
    EXPECT_EQ(a.level, b.level);
    EXPECT_EQ(a.children, b.children);
    EXPECT_EQ(a.faces, b.faces);
    EXPECT_EQ(a.box.center, b.box.center);  // bit for bit
    EXPECT_EQ(a.box.half, b.box.half);
    for (int k = 0; k < 3; ++k) EXPECT_EQ(a.box.axes[k], b.box.axes[k]);
  }
}

TEST(TreeIo, RoundTripIsBitExactAndDeterministic) {
  const Tree t = small_tree();
  const std::string path = test::temp_path("tree.json");
  ASSERT_TRUE(write_tree(t, path));
  Tree back;
  const Status s = read_tree(path, &back);
  ASSERT_TRUE(s) << s.message();
  expect_same(t, back);
  EXPECT_EQ(tree_to_json(t), tree_to_json(back));
  std::remove(path.c_str());
}

TEST(TreeIo, UnknownKeysIgnoredAndInnerFacesFilledIn) {
  std::string j = tree_to_json(small_tree());
  // Drop the root's faces and add a key nobody knows.
  const size_t at = j.find("\"faces\":[0,1,2,3,4,5,6,7]");
  ASSERT_NE(at, std::string::npos);
  j.replace(at, std::string("\"faces\":[0,1,2,3,4,5,6,7]").size(), "\"colour\":\"red\"");
  Tree t;
  const Status s = parse_tree(j, "t.json", &t);
  ASSERT_TRUE(s) << s.message();
  EXPECT_EQ(t.nodes[0].faces, std::vector<int32_t>({0, 1, 2, 3, 4, 5, 6, 7}));
}

TEST(TreeIo, RefusesBrokenTreesWithOneLine) {
  const std::string good = tree_to_json(small_tree());
  auto refused = [](const std::string& text, const std::string& phrase) {
    Tree t;
    const Status s = parse_tree(text, "t.json", &t);
    EXPECT_FALSE(s) << "accepted: " << text.substr(0, 80);
    EXPECT_NE(s.message().find(phrase), std::string::npos) << s.message();
    EXPECT_EQ(s.message().find('\n'), std::string::npos);
    EXPECT_EQ(s.message().rfind("t.json: ", 0), 0u);
  };
  auto edit = [&](const std::string& from, const std::string& to) {
    std::string s = good;
    const size_t at = s.find(from);
    EXPECT_NE(at, std::string::npos) << from;
    return s.replace(at, from.size(), to);
  };
  refused("", "not valid JSON");
  refused(good.substr(0, good.size() / 2), "not valid JSON");
  refused("{\"format\":\"other\"}", "not a vobb tree");
  // A key given twice (which value a reader takes is up to it): refused, not read one way.
  refused(edit("\"depth\":", "\"depth\":7,\"depth\":"), "the key \"depth\" twice in one object");
  refused(edit("\"version\":1", "\"version\":2"), "version");
  refused(edit("\"faces\":[4,5,6,7]", "\"faces\":[3,5,6,7]"), "two leaves");
  refused(edit("\"faces\":[4,5,6,7]", "\"faces\":[5,6,7]"), "union");
  refused(edit("\"faces\":[4,5,6,7]", "\"faces\":[4,5,6,70]"), "out of range");
  refused(edit("\"center\":[", "\"centre\":["), "center");
  refused(edit("\"depth\":1", "\"depth\":3"), "deepest leaf");
  refused(edit("\"parent\":0", "\"parent\":2"), "bad child 1");
  refused(edit("\"children\":[1,2]", "\"children\":[1,1]"), "bad child 1");  // taken twice
  refused(edit("\"level\":1", "\"level\":2"), "bad 'parent' or 'level'");    // below the depth
  // Integers beyond int64 are not wrapped (2^64 - 1 would read as -1, the root's parent).
  refused(edit("\"parent\":0", "\"parent\":18446744073709551615"), "'parent'");
  refused(edit("\"faces\":[4,5,6,7]", "\"faces\":[4,5,6,18446744073709551615]"), "bad 'faces'");
  // Inner nodes' faces are filled in from their children's: a chain of one-child nodes deeper
  // than kMaxTreeDepth could make a small file cost its length times its faces in memory.
  refused(edit("\"depth\":1", "\"depth\":65"), "depth 65 is outside 0..64");
  // A sha256 or method of another type is damage, not absence: it must not turn the mesh check off.
  refused(edit("\"sha256\":\"abc\"", "\"sha256\":5"), "bad 'mesh.sha256'");
  refused(edit("\"method\":\"test\"", "\"method\":[1]"), "bad 'method'");
  // A claimed triangle count far beyond the faces listed is refused without sizing memory by it.
  refused(edit("\"triangles\":8", "\"triangles\":2147483647"), "the mesh has 2147483647 triangles");
  // DESIGN §7: axes only nearly orthonormal; a scaled or sheared frame is not a box.
  refused(edit("\"axes\":[[", "\"axes\":[[10,0,0],[0,1,0],[0,0,1]],\"was\":[["),
          "axes are not orthonormal");
  // Boxes as far out as coordinates may be (solidity.h), and no further.
  refused(edit("\"half_extents\":[", "\"half_extents\":[1e200,1,1],\"was\":["), "extends beyond");
}

TEST(BoxFile, RefusesBoxesThatAreNotBoxes) {
  const std::string path = test::temp_path("bad_boxes.json");
  for (const char* box :
       {R"({"center":[0,0,0],"axes":[[1,0,0],[0,1,0],[0,1,0]],"half_extents":[1,1,1]})",
        R"({"center":[0,0,0],"axes":[[2,0,0],[0,1,0],[0,0,1]],"half_extents":[1,1,1]})",
        R"({"center":[0,0,0],"axes":[[1,0,0],[0,1,0],[0,0,1]],"half_extents":[1e103,1,1]})",
        // subnormal: 1 / h overflows in the box's frame (fast/cubemap.h)
        R"({"center":[0,0,0],"axes":[[1,0,0],[0,1,0],[0,0,1]],"half_extents":[1e-310,1,1]})"}) {
    std::ofstream(path) << "{\"boxes\":[" << box << "]}";
    std::vector<Obb> boxes;
    const Status s = read_boxes(path, &boxes);
    EXPECT_FALSE(s) << box;
    EXPECT_NE(s.message().find("box 0"), std::string::npos) << s.message();
  }
  // Axes as a 6-digit writer leaves them are still accepted, and so are flat boxes (a zero half
  // extent) and tiny ones (the least normal double).
  std::ofstream(path)
      << R"({"boxes":[{"center":[0,0,0],"axes":[[0.6,0.8,0],[-0.8,0.6,0],[0,0,1]],"half_extents":[1,1,1]},)"
      << R"({"center":[0,0,0],"axes":[[1,0,0],[0,1,0],[0,0,1]],"half_extents":[0,2.2250738585072014e-308,1]}]})";
  std::vector<Obb> boxes;
  EXPECT_TRUE(read_boxes(path, &boxes));
  EXPECT_EQ(boxes.size(), 2u);
  std::remove(path.c_str());
}

// Only regular files are read: /dev/zero would be read forever and a FIFO would block, so both
// are refused before they are opened, as is a folder (by name, not as "not valid JSON").
TEST(TreeIo, OnlyRegularFilesAreRead) {
  const std::string fifo = test::temp_path("fifo_tree.json");
  std::remove(fifo.c_str());
  ASSERT_EQ(::mkfifo(fifo.c_str(), 0600), 0);
  const std::string folder = test::temp_path("folder_tree.json");
  ::mkdir(folder.c_str(), 0700);
  Tree t;
  std::vector<Obb> boxes;
  for (const std::string& path : {std::string("/dev/zero"), fifo}) {
    const Status tree = read_tree(path, &t);
    EXPECT_FALSE(tree);
    EXPECT_NE(tree.message().find(": not a regular file"), std::string::npos) << tree.message();
    const Status box = read_boxes(path, &boxes);
    EXPECT_FALSE(box);
    EXPECT_NE(box.message().find(": not a regular file"), std::string::npos) << box.message();
  }
  const std::string name = basename_of(folder);
  EXPECT_EQ(read_tree(folder, &t).message(), name + ": is a directory, not a tree file");
  EXPECT_EQ(read_boxes(folder, &boxes).message(), name + ": is a directory, not a box file");
  const std::string absent = test::temp_path("absent_tree.json");
  EXPECT_EQ(read_tree(absent, &t).message(),
            basename_of(absent) + ": cannot open: No such file or directory");
  std::remove(fifo.c_str());
  ::rmdir(folder.c_str());
}

TEST(BoxFile, RoundTrip) {
  const Tree t = small_tree();
  std::vector<Obb> boxes = {t.nodes[0].box, t.nodes[1].box};
  const std::string path = test::temp_path("boxes.json");
  ASSERT_TRUE(write_boxes(boxes, path));
  std::vector<Obb> back;
  ASSERT_TRUE(read_boxes(path, &back));
  ASSERT_EQ(back.size(), 2u);
  for (size_t i = 0; i < 2; ++i) {  // every number of both boxes, bit for bit
    EXPECT_EQ(back[i].center, boxes[i].center) << i;
    EXPECT_EQ(back[i].half, boxes[i].half) << i;
    for (int k = 0; k < 3; ++k) EXPECT_EQ(back[i].axes[k], boxes[i].axes[k]) << i << " " << k;
  }
  std::remove(path.c_str());
}

}  // namespace
}  // namespace vobb
