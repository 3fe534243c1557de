// Formats other than OFF/OBJ/PLY/STL, through Debian's assimp. Its `ai_real` is float, so
// coordinates arrive rounded to float32; the caller is told (`single_precision`).
#include <assimp/postprocess.h>
#include <assimp/scene.h>

#include <assimp/Importer.hpp>

#include <sys/resource.h>
#include <sys/stat.h>
#include <unistd.h>

#include <cstdio>
#include <new>

#include "common/io/mesh_io.h"

namespace vobb {
namespace {

// Some formats describe geometry procedurally (NFF's "pp 99999999 99999999" is 21 bytes and
// asks for 10^16 vertices), so assimp's memory is not bounded by the file's size. While it
// reads, the process's address space is capped at what it uses now plus an allowance
// (1 GiB + 256 bytes per byte of file: text formats hold a vertex in about 30 bytes and
// assimp keeps it in 12, and compressed formats rarely expand 100-fold), so a bomb ends in
// std::bad_alloc, which assimp reports as a failed read, instead of exhausting the machine.
class AddressSpaceCap {
 public:
  explicit AddressSpaceCap(const std::string& path) {
    struct stat st;
    if (::stat(path.c_str(), &st) != 0 || ::getrlimit(RLIMIT_AS, &saved_) != 0) return;
    unsigned long pages = 0;
    if (FILE* f = std::fopen("/proc/self/statm", "r")) {
      if (std::fscanf(f, "%lu", &pages) != 1) pages = 0;
      std::fclose(f);
    }
    if (pages == 0) return;
    const double used = static_cast<double>(pages) * static_cast<double>(::sysconf(_SC_PAGESIZE));
    allowance_ = (1u << 30) + 256.0 * static_cast<double>(st.st_size);
    const double cap = used + allowance_;
    if (saved_.rlim_cur != RLIM_INFINITY && static_cast<double>(saved_.rlim_cur) <= cap) return;
    struct rlimit lowered = saved_;
    lowered.rlim_cur = static_cast<rlim_t>(cap);
    active_ = ::setrlimit(RLIMIT_AS, &lowered) == 0;
  }
  ~AddressSpaceCap() {
    if (active_) ::setrlimit(RLIMIT_AS, &saved_);
  }
  double allowance_gib() const { return allowance_ / (1u << 30); }

 private:
  struct rlimit saved_ {};
  bool active_ = false;
  double allowance_ = 0;
};

}  // namespace

Status load_with_assimp(const std::string& path, const std::string& display, LoadedMesh* out) {
  Assimp::Importer importer;
  const aiScene* scene = nullptr;
  std::string why;
  {
    AddressSpaceCap cap(path);
    // Bake node transforms into the vertices; split polygons into triangles. Welding is ours.
    bool out_of_memory = false;
    try {
      scene = importer.ReadFile(path, aiProcess_Triangulate | aiProcess_PreTransformVertices | aiProcess_SortByPType);
    } catch (const std::bad_alloc&) {
      scene = nullptr;
      out_of_memory = true;
    }
    why = importer.GetErrorString();
    if (scene == nullptr && (out_of_memory || why.find("bad_alloc") != std::string::npos)) {
      char gib[32];
      std::snprintf(gib, sizeof gib, "%.1f", cap.allowance_gib());
      return Status::error(display + ": cannot read: the file asks for more than " + gib +
                           " GiB of memory (assimp ran out)");
    }
  }
  if (scene == nullptr || (scene->mFlags & AI_SCENE_FLAGS_INCOMPLETE)) {
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
