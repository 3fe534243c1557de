#include "common/io/mesh_report.h"

#include <gtest/gtest.h>

#include <cstdio>
#include <nlohmann/json.hpp>
#include <string>

#include "data/analytic_meshes.h"
#include "test_common.h"

namespace vobb {
namespace {

// A cube of side 2: 8 vertices, 12 faces, 18 edges, one shell, volume exactly 8.
std::string write_cube(const std::string& name, size_t drop_faces = 0) {
  Mesh m = analytic::cube(2.0, Vec3(-1, -1, -1)).mesh;
  m.faces.resize(m.faces.size() - drop_faces);
  const std::string path = test::temp_path(name);
  test::write_off(m, path);
  return path;
}

TEST(MeshReport, SolidCubeIsReportedWithItsExactVolume) {
  const std::string path = write_cube("report_cube.off");
  MeshReport r;
  ASSERT_TRUE(inspect_mesh(path, &r));
  EXPECT_TRUE(r.solidity.solid());
  EXPECT_TRUE(solidity_status(r));
  const nlohmann::json j = nlohmann::json::parse(format_report_json(r, true));
  EXPECT_EQ(j.at("faces"), 12);
  EXPECT_EQ(j.at("vertices"), 8);
  EXPECT_EQ(j.at("edges"), 18);
  EXPECT_EQ(j.at("shells"), 1);
  EXPECT_EQ(j.at("volume"), 8.0);
  EXPECT_EQ(j.at("solid"), true);
  EXPECT_EQ(j.at("verdict"), "solid");
  EXPECT_TRUE(j.at("defects").empty());
  EXPECT_EQ(j.at("bbox").at("min"), nlohmann::json::array({-1.0, -1.0, -1.0}));
  const std::string text = format_report_text(r, true);
  EXPECT_NE(text.find("verdict:   solid"), std::string::npos) << text;
  EXPECT_NE(text.find("rational:  8\n"), std::string::npos) << text;
  EXPECT_EQ(format_report_text(r, false).find("rational:"), std::string::npos)
      << "rational only when asked";
  LoadedMesh loaded;
  ASSERT_TRUE(load_solid(path, &loaded));
  EXPECT_EQ(loaded.mesh.faces.size(), 12u);
  std::remove(path.c_str());
}

// A cube missing one face reads, is not solid, and is refused by load_solid with one line that
// names the file (by its name), the defect and its count (3 border edges); its report has no
// volume.
TEST(MeshReport, OpenMeshIsReportedAndRefused) {
  const std::string path = write_cube("report_open.off", 1);
  MeshReport r;
  ASSERT_TRUE(inspect_mesh(path, &r)) << "an open mesh reads: its defects are in the report";
  EXPECT_FALSE(r.solidity.solid());
  const Status s = solidity_status(r);
  EXPECT_FALSE(s);
  EXPECT_EQ(s.message().rfind(path.substr(path.rfind('/') + 1) + ": ", 0), 0u)
      << "named by its file name: " << s.message();
  EXPECT_NE(s.message().find("not closed: 3 border edges"), std::string::npos) << s.message();
  EXPECT_EQ(s.message().find('\n'), std::string::npos);
  const nlohmann::json j = nlohmann::json::parse(format_report_json(r, false));
  EXPECT_TRUE(j.at("volume").is_null());
  EXPECT_EQ(j.at("solid"), false);
  EXPECT_EQ(j.at("defects"), nlohmann::json::parse(R"([{"defect":"not-closed","count":3}])"));
  LoadedMesh loaded;
  const Status refused = load_solid(path, &loaded);
  EXPECT_FALSE(refused);
  EXPECT_EQ(refused.message(), s.message());
  std::remove(path.c_str());
}

TEST(MeshReport, UnreadableFileIsAStatusNamingIt) {
  const std::string path = test::temp_path("report_missing.off");
  MeshReport r;
  const Status s = inspect_mesh(path, &r);
  EXPECT_FALSE(s);
  EXPECT_NE(s.message().find("report_missing.off"), std::string::npos) << s.message();
  LoadedMesh loaded;
  EXPECT_FALSE(load_solid(path, &loaded));
}

}  // namespace
}  // namespace vobb
