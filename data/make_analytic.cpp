// Writes the analytic meshes as OFF files into a folder: vobb-make-analytic DIR
#include <cstdio>
#include <string>

#include "common/io/mesh_io.h"
#include "data/analytic_meshes.h"

int main(int argc, char** argv) {
  if (argc != 2) {
    std::fprintf(stderr, "usage: vobb-make-analytic DIR\n");
    return 2;
  }
  for (const auto& a : vobb::analytic::all()) {
    const std::string path = std::string(argv[1]) + "/" + a.name + ".off";
    vobb::Status s = vobb::save_mesh(a.mesh, path, vobb::MeshFormat::kOff);
    if (!s) {
      std::fprintf(stderr, "vobb-make-analytic: %s\n", s.message().c_str());
      return 2;
    }
    std::printf("%s  volume %s\n", path.c_str(), a.volume.get_str().c_str());
  }
  return 0;
}
