// Formats other than OFF/OBJ/PLY/STL, through Debian's assimp. Its `ai_real` is float, so
// coordinates arrive rounded to float32; the caller is told (`single_precision`).
#include <assimp/postprocess.h>
#include <assimp/scene.h>

#include <assimp/Importer.hpp>

#include "common/io/mesh_io.h"

namespace vobb {

Status load_with_assimp(const std::string& path, const std::string& display, LoadedMesh* out) {
  Assimp::Importer importer;
  // Bake node transforms into the vertices; split polygons into triangles. Welding is ours.
  const aiScene* scene = importer.ReadFile(
      path, aiProcess_Triangulate | aiProcess_PreTransformVertices | aiProcess_SortByPType);
  if (scene == nullptr || (scene->mFlags & AI_SCENE_FLAGS_INCOMPLETE)) {
    std::string why = importer.GetErrorString();
    for (char& c : why)
      if (c == '\n' || c == '\r') c = ' ';
    return Status::error(display + ": cannot read: " + (why.empty() ? "unknown format" : why));
  }
  Mesh& m = out->mesh;
  for (unsigned i = 0; i < scene->mNumMeshes; ++i) {
    const aiMesh* am = scene->mMeshes[i];
    if (!(am->mPrimitiveTypes & aiPrimitiveType_TRIANGLE)) continue;
    const int32_t base = static_cast<int32_t>(m.vertices.size());
    for (unsigned v = 0; v < am->mNumVertices; ++v)
      m.vertices.emplace_back(am->mVertices[v].x, am->mVertices[v].y, am->mVertices[v].z);
    for (unsigned f = 0; f < am->mNumFaces; ++f) {
      const aiFace& face = am->mFaces[f];
      if (face.mNumIndices != 3) continue;  // points and lines are not part of a solid
      m.faces.push_back({base + static_cast<int32_t>(face.mIndices[0]),
                         base + static_cast<int32_t>(face.mIndices[1]),
                         base + static_cast<int32_t>(face.mIndices[2])});
    }
  }
  if (m.faces.empty()) return Status::error(display + ": no triangles in the scene");
  const size_t dot = path.find_last_of('.');
  out->format = dot == std::string::npos ? "assimp" : path.substr(dot + 1);
  out->single_precision = true;
  return Status::ok();
}

}  // namespace vobb
