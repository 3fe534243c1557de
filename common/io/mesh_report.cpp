#include "common/io/mesh_report.h"

#include <nlohmann/json.hpp>
#include <sstream>

#include "common/text_util.h"

namespace vobb {
Status inspect_mesh(const std::string& path, MeshReport* report) {
  report->file = path;
  Status s = load_mesh(path, &report->loaded);
  if (!s) return s;
  report->solidity = check_solidity(report->loaded.mesh);
  return Status::ok();
}

Status solidity_status(const MeshReport& report) {
  if (report.solidity.solid()) return Status::ok();
  return Status::error(basename_of(report.file) + ": " + report.solidity.verdict());
}

Status load_solid(const std::string& path, LoadedMesh* out) {
  MeshReport report;
  Status s = inspect_mesh(path, &report);
  if (!s) return s;
  s = solidity_status(report);
  if (!s) return s;
  *out = std::move(report.loaded);
  return Status::ok();
}

std::string format_report_text(const MeshReport& r, bool rational) {
  std::ostringstream o;
  const SolidityReport& s = r.solidity;
  o << "file:      " << r.file << " (" << r.loaded.format << ", "
    << (r.loaded.single_precision ? "read in single precision through assimp"
                                  : "double precision, as written")
    << ")\n";
  o << "vertices:  " << s.vertices << " (" << r.loaded.file_vertices << " in the file, "
    << r.loaded.welded_vertices << " welded, " << r.loaded.unreferenced_vertices
    << " unreferenced)\n";
  o << "faces:     " << s.faces;
  if (r.loaded.polygons_split)
    o << " (" << r.loaded.polygons_split << " polygons split into triangles)";
  o << "\nedges:     " << s.edges << "\nshells:    " << s.shells << "\n";
  const Aabb b = r.loaded.mesh.bounds();
  if (!b.empty() && b.lo.allFinite() && b.hi.allFinite())
    // The file's own doubles: the shortest form that reads back exactly.
    o << "bbox:      [" << format_double(b.lo[0]) << ", " << format_double(b.lo[1]) << ", "
      << format_double(b.lo[2]) << "] .. [" << format_double(b.hi[0]) << ", "
      << format_double(b.hi[1]) << ", " << format_double(b.hi[2]) << "]\n";
  if (s.volume_known) {
    o << "volume:    " << format_nearest(s.volume) << " (exact, rounded to nearest)\n";
    if (rational) o << "rational:  " << s.volume.get_str() << "\n";
  }
  o << "verdict:   " << s.verdict() << "\n";
  return o.str();
}

std::string format_report_json(const MeshReport& r, bool rational) {
  nlohmann::ordered_json j;
  const SolidityReport& s = r.solidity;
  j["file"] = r.file;
  j["format"] = r.loaded.format;
  j["precision"] = r.loaded.single_precision ? "float32" : "float64";
  j["vertices"] = s.vertices;
  j["file_vertices"] = r.loaded.file_vertices;
  j["welded_vertices"] = r.loaded.welded_vertices;
  j["unreferenced_vertices"] = r.loaded.unreferenced_vertices;
  j["faces"] = s.faces;
  j["polygons_split"] = r.loaded.polygons_split;
  j["edges"] = s.edges;
  j["shells"] = s.shells;
  const Aabb b = r.loaded.mesh.bounds();
  if (!b.empty() && b.lo.allFinite() && b.hi.allFinite())
    j["bbox"] = {{"min", {b.lo[0], b.lo[1], b.lo[2]}}, {"max", {b.hi[0], b.hi[1], b.hi[2]}}};
  else
    j["bbox"] = nullptr;
  if (s.volume_known) {
    j["volume"] = to_double_nearest(s.volume);
    if (rational) j["volume_rational"] = s.volume.get_str();
  } else {
    j["volume"] = nullptr;
  }
  j["solid"] = s.solid();
  j["verdict"] = s.verdict();
  nlohmann::ordered_json d = nlohmann::ordered_json::array();
  for (const DefectCount& dc : s.defects) {
    nlohmann::ordered_json one = {{"defect", defect_name(dc.defect)}, {"count", dc.count}};
    if (dc.at_least) one["count_is_lower_bound"] = true;  // the search stopped there
    d.push_back(one);
  }
  j["defects"] = d;
  return j.dump(2, ' ', false, nlohmann::json::error_handler_t::replace) +
         "\n";  // file names need not be UTF-8
}

}  // namespace vobb
