// Mesh input and output.
//
// OFF (incl. COFF/NOFF/STOFF variants), OBJ, PLY (ASCII and binary) and STL (ASCII and
// binary) are read by vobb's own parsers, in double precision, exactly as the file writes
// each number (std::from_chars rounds correctly). Every other format that Debian's assimp
// knows (glTF, FBX, DAE, 3DS, ...) goes through assimp where the assimp component is enabled
// (enable_assimp, common/io/assimp_reader.h; target vobb::assimp). Assimp is built in single
// precision: such a mesh is marked `single_precision` and its coordinates are float32-rounded.
//
// After reading, exactly equal vertices are welded (-0 and +0 count as equal) and
// unreferenced vertices dropped, keeping first-appearance order; polygons are split into
// triangle fans, and face ids refer to the resulting triangles in file order.
// The reader checks syntax only; solidity is solidity.h's job.
#pragma once

#include <cstdint>
#include <string>

#include "common/mesh.h"
#include "common/status.h"

namespace vobb {

struct LoadedMesh {
  Mesh mesh;
  std::string format;             // "off", "obj", "ply", "stl", or assimp's extension
  bool single_precision = false;  // read through assimp's float32
  size_t file_vertices = 0;       // vertex records in the file
  size_t welded_vertices = 0;     // records merged into an exactly equal earlier vertex
  size_t unreferenced_vertices = 0;
  size_t polygons_split = 0;  // faces with more than 3 corners, split into fans
};

// Reads `path`. On failure the Status message is one line: "<file>: <reason>" or
// "<file>:<line>: <reason>". Never throws, never aborts on bad bytes. A regular file named
// *.json is refused as no mesh (vobb's own files are JSON).
Status load_mesh(const std::string& path, LoadedMesh* out);

// The reader of the formats vobb does not parse itself, for a regular file of `bytes` bytes
// (`display`: its name in messages). Without one registered, load_mesh refuses them.
using ForeignMeshReader = Status (*)(const std::string& path, const std::string& display,
                                     uint64_t bytes, LoadedMesh* out);
void set_foreign_mesh_reader(ForeignMeshReader reader);

// Writers, for round trips and generated data. Numbers are written with 17 significant
// digits, so a double survives the trip. The file appears atomically (temp + rename).
enum class MeshFormat { kOff, kObj, kPlyAscii, kPlyBinary, kStlAscii, kStlBinary };
Status save_mesh(const Mesh& mesh, const std::string& path, MeshFormat format);

// Welds exactly equal vertices and drops unreferenced ones in place; returns the counts.
void weld_vertices(Mesh* mesh, size_t* welded, size_t* unreferenced);

}  // namespace vobb
