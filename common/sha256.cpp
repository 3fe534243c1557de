#include "common/sha256.h"

#include <openssl/evp.h>

#include <cstring>
#include <vector>

namespace vobb {

std::string sha256_hex(const void* data, size_t size) {
  unsigned char md[EVP_MAX_MD_SIZE];
  unsigned int len = 0;
  EVP_Digest(data, size, md, &len, EVP_sha256(), nullptr);
  static const char* kHex = "0123456789abcdef";
  std::string out;
  for (unsigned i = 0; i < len; ++i) {
    out += kHex[md[i] >> 4];
    out += kHex[md[i] & 15];
  }
  return out;
}

std::string mesh_sha256(const Mesh& mesh) {
  static_assert(sizeof(double) == 8, "IEEE-754 doubles");
  std::vector<unsigned char> bytes;
  bytes.reserve(mesh.faces.size() * 72);
  for (size_t f = 0; f < mesh.faces.size(); ++f)
    for (int k = 0; k < 3; ++k)
      for (int c = 0; c < 3; ++c) {
        uint64_t bits;
        const double v = mesh.corner(f, k)[c];
        std::memcpy(&bits, &v, 8);
        for (int b = 0; b < 8; ++b) bytes.push_back(static_cast<unsigned char>(bits >> (8 * b)));
      }
  return sha256_hex(bytes.data(), bytes.size());
}

}  // namespace vobb
