// Reading a mesh through assimp (the formats vobb does not parse itself): the assimp component
// (target vobb::assimp). enable_assimp() makes load_mesh() use it; load_with_assimp is declared
// here for the tests of its limits.
//
// The import runs in a child process, so that an importer that crashes or loops on a damaged
// file cannot take the caller with it: a crash, a loop past `cpu_seconds` of CPU time, or
// running out of the memory allowance each ends in a failed Status with a one-line message
// "<file>: cannot read: <reason>". Output of assimp's own goes to /dev/null.
#pragma once

#include <cstdint>
#include <string>

#include "common/io/mesh_io.h"
#include "common/status.h"

namespace vobb {

// Registers load_with_assimp with load_mesh (set_foreign_mesh_reader) for every format that
// vobb does not parse itself.
void enable_assimp();

// The default CPU-time limit for a file of this size: 20 s plus 2 s per MiB. Assimp's text
// importers read tens of MiB per second, so a well-formed file stays far below it.
double assimp_cpu_seconds(uint64_t file_bytes);

// `path` must be a regular file (load_mesh checks); `cpu_seconds` > 0, usually
// assimp_cpu_seconds() of its size.
Status load_with_assimp(const std::string& path, const std::string& display, LoadedMesh* out,
                        double cpu_seconds);

}  // namespace vobb
