// What `vobb info` tells about a mesh file: load it, check its solidity, and format the
// result as text or JSON. Also `load_solid`, the front door of every command that needs a
// solid: it refuses anything else with one line naming the file, the defect and a count.
#pragma once

#include <string>

#include "common/io/mesh_io.h"
#include "common/solidity.h"
#include "common/status.h"

namespace vobb {

struct MeshReport {
  std::string file;  // as given
  LoadedMesh loaded;
  SolidityReport solidity;
};

// Loads and checks. A failed Status means the file could not be read at all; a file that
// reads but is not solid succeeds here, with the defects in `report->solidity`.
Status inspect_mesh(const std::string& path, MeshReport* report);

// One-line refusal for a mesh that is not solid: "<file>: <defects>".
Status solidity_status(const MeshReport& report);

// Loads, checks, and refuses non-solids. On success `out` holds the welded mesh.
Status load_solid(const std::string& path, LoadedMesh* out);

std::string format_report_text(const MeshReport& report, bool rational);
std::string format_report_json(const MeshReport& report, bool rational);

}  // namespace vobb
