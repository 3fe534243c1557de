// SHA-256 (OpenSSL), as lowercase hex.
#pragma once

#include <cstddef>
#include <string>

#include "common/mesh.h"

namespace vobb {

std::string sha256_hex(const void* data, size_t size);

// Fingerprint of a mesh's geometry as the tree file records it: SHA-256 over the faces in
// order, each as its three corners' x, y, z in IEEE-754 little-endian doubles. It ties a tree
// to the triangles and face ids it indexes, whatever file format carried them.
std::string mesh_sha256(const Mesh& mesh);

}  // namespace vobb
