// vobb_core_consumer MESH TREE: builds a variational tree of MESH, certifies it, writes it to
// TREE and prints "e <rational>". Exit 1 when a step fails or the tree does not certify.
#include <vobb/vobb.h>

#include <cstdio>

int main(int argc, char** argv) {
  if (argc != 3) return std::fprintf(stderr, "usage: vobb_core_consumer MESH TREE\n"), 2;
  vobb::LoadedMesh solid;
  vobb::Status s = vobb::load_solid(argv[1], &solid);
  vobb::BuildOptions build;
  build.depth = 4;
  build.m = 8;
  vobb::Tree tree;
  if (s) s = vobb::build_tree(solid.mesh, build, &tree);
  vobb::CertifyOptions exact;
  exact.rational = true;
  vobb::exact::Certificate certificate;
  if (s) s = vobb::certify(solid.mesh, tree, exact, &certificate);
  if (s) s = vobb::write_tree(tree, argv[2]);
  if (!s || !certificate.ok())
    return std::fprintf(stderr, "%s\n", s ? "not certified" : s.message().c_str()), 1;
  std::printf("e %s\n", certificate.weighted_error.get_str().c_str());
  return 0;
}
