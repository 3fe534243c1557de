#include "common/sha256.h"

#include <gtest/gtest.h>

#include <cstdint>
#include <cstring>
#include <string>

#include "data/analytic_meshes.h"

namespace vobb {
namespace {

// The examples of FIPS 180-2 (appendix B) and the empty message.
TEST(Sha256, StandardVectors) {
  auto hex = [](const std::string& m) { return sha256_hex(m.data(), m.size()); };
  EXPECT_EQ(hex("abc"), "ba7816bf8f01cfea414140de5dae2223b00361a396177a9cb410ff61f20015ad");
  EXPECT_EQ(hex(""), "e3b0c44298fc1c149afbf4c8996fb92427ae41e4649b934ca495991b7852b855");
  EXPECT_EQ(hex("abcdbcdecdefdefgefghfghighijhijkijkljklmklmnlmnomnopnopq"),
            "248d6a61d20638b8e5c026930c3e6039a33ce45964ff2167f6ecedd419db06c1");
  EXPECT_EQ(hex(std::string(1000000, 'a')),
            "cdc76e5c9914fb9281a1c7e284d73e67f1809a48a497200e046d39ccc7112cd0");
}

// mesh_sha256 is defined by its bytes (sha256.h): per face in order, its corners' x, y, z as
// little-endian IEEE-754 doubles. Built here byte by byte, independently of the host's order.
// The vertices' numbering does not enter it; the faces' order and corners do.
TEST(Sha256, MeshFingerprintIsTheFacesCornersInOrder) {
  const Mesh cube = analytic::cube(1.5).mesh;
  std::string bytes;
  for (const Face& f : cube.faces)
    for (int c = 0; c < 3; ++c)
      for (int k = 0; k < 3; ++k) {
        uint64_t bits;
        const double x = cube.vertices[f[c]][k];
        std::memcpy(&bits, &x, sizeof bits);
        for (int b = 0; b < 8; ++b) bytes.push_back(static_cast<char>((bits >> (8 * b)) & 0xff));
      }
  EXPECT_EQ(mesh_sha256(cube), sha256_hex(bytes.data(), bytes.size()));

  Mesh renumbered = cube;  // vertices reversed, faces pointing at the same corners
  const int n = static_cast<int>(cube.vertices.size());
  for (int i = 0; i < n; ++i) renumbered.vertices[n - 1 - i] = cube.vertices[i];
  for (Face& f : renumbered.faces)
    for (int c = 0; c < 3; ++c) f[c] = n - 1 - f[c];
  EXPECT_EQ(mesh_sha256(renumbered), mesh_sha256(cube));

  Mesh swapped = cube;
  std::swap(swapped.faces[0], swapped.faces[1]);
  EXPECT_NE(mesh_sha256(swapped), mesh_sha256(cube));
  Mesh rotated = cube;  // the same triangle, its corners started elsewhere
  rotated.faces[0] = {cube.faces[0][1], cube.faces[0][2], cube.faces[0][0]};
  EXPECT_NE(mesh_sha256(rotated), mesh_sha256(cube));
}

}  // namespace
}  // namespace vobb
